// HilGodObject: constraint-based (admittance) environments through the coupling, (22), on
// a 3-axis pen display in the real daemon: the virtual tool never enters an obstacle while
// the device itself does, and the coupling pushes the device back out.
//
// Physics. With an admittance environment the coupling (16) is connected as in (22): the
// environment takes the device state and returns the tool position x_e, here the god-object
// (Zilles and Salisbury): the free point nearest the device, reached by sliding along the
// surfaces, or a virtual mass integrated under the coupling force and stopped by its
// constraints. The force on the handle is F = k_c (x_e - x_d) + b_c (v_e - v_d): a rigid
// obstacle is felt as the coupling spring, and the device sinks into it by F / k_c. The
// encoder-sized k_c = 2b/T = 4000 N/m at b_c = 0 (the exact bound k_c T/2 < b + b_c) holds
// against the rigid proxy for every passive operator; the stiff grasps here add damping.
//
// Experiment. Each axis is held by a stiff grasp (0.3 kg, 500 N/m, 5 N s/m) whose set-point
// follows its own push profile: x pushes 1 cm into a ball, y slides sideways meanwhile,
// then z pushes 1 cm into the table. Judged over every logged tick.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <iostream>
#include <string>

#include "hapticd_run.hpp"
#include "operators.hpp"
#include "pen_display.hpp"
#include "tuned_gains.hpp"

namespace hapticd::testing {
namespace {

using Vec = std::array<double, 3>;

constexpr double kFreeSpaceToleranceM = 1e-9;  ///< env::kContactTolerance_m
constexpr double kPenetrationM = 1e-3;         ///< the device must go this deep at least

double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec minus(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double norm(const Vec& a) { return std::sqrt(dot(a, a)); }

/// Row `i` of the columns `prefix`0`suffix` .. `prefix`2`suffix` (e.g. "x", "_m").
Vec row_vector(const TelemetryLog& log, const std::string& prefix, const std::string& suffix,
               std::size_t i) {
    return {log.column(prefix + "0" + suffix)[i], log.column(prefix + "1" + suffix)[i],
            log.column(prefix + "2" + suffix)[i]};
}

DaemonConfig three_axis_config(const std::vector<std::string>& grasps) {
    DaemonConfig config;
    config.axes = 3;
    config.coupling = coupling_table(size_coupling("encoder"), "encoder");
    config.initial_position = toml_vector({0.0, 0.0, 0.0});
    config.humans = per_axis_human_tables(grasps);
    return config;
}

DaemonRun run_three_axis(const ScratchDir& dir, const DaemonConfig& config,
                         const std::string& scene, double duration_s) {
    DaemonRun run = run_hapticd(
        dir, {.config_toml = config.toml(), .scene_toml = scene, .duration_s = duration_s});
    EXPECT_EQ(run.exit_code, 0) << run.err;
    EXPECT_EQ(fault_list(run), "");
    EXPECT_EQ(run.log.rows(), static_cast<std::size_t>(duration_s * kRateHz));
    return run;
}

// A table (the plane z = -2 cm, free above) with a solid ball of radius 2 cm on it whose
// near side is at x = 1 cm.
constexpr double kTableZ = -0.02;
constexpr Vec kBallCenter = {0.03, 0.0, 0.0};
constexpr double kBallRadius = 0.02;

std::string table_and_ball_scene() {
    return "[scene]\nname = \"hil-table-and-ball\"\naxes = 3\n"
           "[[proxy_plane]]\nnormal = [0.0, 0.0, 1.0]\noffset = " +
           toml_number(kTableZ) + "\n[[proxy_sphere]]\ncenter = " +
           toml_vector({kBallCenter[0], kBallCenter[1], kBallCenter[2]}) +
           "\nradius = " + toml_number(kBallRadius) + "\nside = \"outside\"\n";
}

TEST(HilGodObject, ProxyStaysInFreeSpaceWhileTheDevicePressesIntoBallAndTable) {
    constexpr double kDurationS = 6.5;
    const DaemonConfig config = three_axis_config({
        stiff_grasp(push_toml(0.02, 1.0, 0.5, 1.5)),   // x: 1 cm into the ball, 1 s .. 3.5 s
        stiff_grasp(push_toml(0.01, 1.0, 2.0, 0.0)),   // y: slides 1 cm sideways and back
        stiff_grasp(push_toml(-0.03, 3.5, 0.5, 1.5)),  // z: 1 cm into the table, 3.5 s .. 6 s
    });
    const ScratchDir dir;
    const DaemonRun run = run_three_axis(dir, config, table_and_ball_scene(), kDurationS);
    ASSERT_GT(run.log.rows(), 0u);
    const double k_c = size_coupling("encoder").stiffness_n_per_m;

    double ball_depth_max_m = 0.0, table_depth_max_m = 0.0;
    double proxy_ball_gap_min_m = 1.0, proxy_table_gap_min_m = 1.0;
    std::size_t pushed_out_of_ball = 0, in_ball = 0, pushed_out_of_table = 0, in_table = 0;
    double coupling_law_error_max_n = 0.0;
    const auto& flags = run.log.column("tick_flags");
    for (std::size_t i = 0; i < run.log.rows(); ++i) {
        const Vec x = row_vector(run.log, "x", "_m", i);
        const Vec xe = row_vector(run.log, "xe", "_m", i);
        const Vec f = row_vector(run.log, "f", "_n", i);
        // The proxy: outside the ball and above the table in every tick.
        proxy_ball_gap_min_m =
            std::min(proxy_ball_gap_min_m, norm(minus(xe, kBallCenter)) - kBallRadius);
        proxy_table_gap_min_m = std::min(proxy_table_gap_min_m, xe[2] - kTableZ);
        // The device: into the ball and into the table, and pushed back out along the
        // outward normal at its position.
        const Vec from_center = minus(x, kBallCenter);
        const double ball_depth_m = kBallRadius - norm(from_center);
        const double table_depth_m = kTableZ - x[2];
        ball_depth_max_m = std::max(ball_depth_max_m, ball_depth_m);
        table_depth_max_m = std::max(table_depth_max_m, table_depth_m);
        if (ball_depth_m > 20.0 * kCountM) {
            ++in_ball;
            if (dot(f, from_center) > 0.0) ++pushed_out_of_ball;
        }
        if (table_depth_m > 20.0 * kCountM) {
            ++in_table;
            if (f[2] > 0.0) ++pushed_out_of_table;
        }
        // (16) at b_c = 0, once the soft start is over: F = k_c (x_e - x_d), exactly.
        if ((static_cast<std::uint32_t>(flags[i]) & 8u) == 0u && run.log.column("t_s")[i] > 1.0) {
            for (int axis = 0; axis < 3; ++axis) {
                coupling_law_error_max_n = std::max(coupling_law_error_max_n,
                                                    std::abs(f[axis] - k_c * (xe[axis] - x[axis])));
            }
        }
    }
    std::cout << "[hil] god-object: device depth " << ball_depth_max_m * 1e3
              << " mm into the ball, " << table_depth_max_m * 1e3
              << " mm into the table; proxy gap min " << proxy_ball_gap_min_m * 1e9
              << " nm (ball), " << proxy_table_gap_min_m * 1e9 << " nm (table); pushed out in "
              << pushed_out_of_ball << "/" << in_ball << " and " << pushed_out_of_table << "/"
              << in_table << " ticks; |F - k_c (x_e - x_d)| <= " << coupling_law_error_max_n
              << " N\n";

    EXPECT_GE(proxy_ball_gap_min_m, -kFreeSpaceToleranceM);
    EXPECT_GE(proxy_table_gap_min_m, -kFreeSpaceToleranceM);
    EXPECT_GE(ball_depth_max_m, kPenetrationM);  // the test bites: the device was inside
    EXPECT_GE(table_depth_max_m, kPenetrationM);
    EXPECT_GT(in_ball, 1000u);
    EXPECT_GT(in_table, 1000u);
    EXPECT_EQ(pushed_out_of_ball, in_ball);
    EXPECT_EQ(pushed_out_of_table, in_table);
    EXPECT_LT(coupling_law_error_max_n, 1e-9);
}

// A 0.5 kg puck on a 20 N/m spring in a spherical bowl of radius 3 cm with a floor 1 cm
// below the centre. The grasp drags the handle 5 cm out along x and 2 cm down: the puck
// follows to the bowl's wall and the floor and stops there, the device goes on.
constexpr double kBowlRadius = 0.03;
constexpr double kFloorZ = -0.01;

std::string bowl_scene() {
    return "[scene]\nname = \"hil-puck-in-a-bowl\"\naxes = 3\n"
           "[virtual_mass]\nmass = 0.5\nstiffness = 20.0\ndamping = 1.0\n"
           "anchor = [0.0, 0.0, 0.0]\n"
           "[[virtual_mass.sphere]]\ncenter = [0.0, 0.0, 0.0]\nradius = " +
           toml_number(kBowlRadius) +
           "\nside = \"inside\"\n[[virtual_mass.plane]]\n"
           "normal = [0.0, 0.0, 1.0]\noffset = " +
           toml_number(kFloorZ) + "\n";
}

TEST(HilGodObject, VirtualMassStaysInItsBowlWhileTheDeviceLeavesIt) {
    constexpr double kDurationS = 4.0;
    const DaemonConfig config = three_axis_config({
        stiff_grasp(push_toml(0.05, 1.0, 1.0, 1.0)),   // x: 5 cm out, beyond the bowl
        stiff_grasp(""),                               // y: held at 0
        stiff_grasp(push_toml(-0.02, 1.0, 1.0, 1.0)),  // z: 2 cm down, below the floor
    });
    const ScratchDir dir;
    const DaemonRun run = run_three_axis(dir, config, bowl_scene(), kDurationS);
    ASSERT_GT(run.log.rows(), 0u);

    double puck_radius_max_m = 0.0, puck_height_min_m = 1.0, device_radius_max_m = 0.0;
    double device_height_min_m = 1.0;
    std::size_t outside = 0, pulled_back = 0;
    for (std::size_t i = 0; i < run.log.rows(); ++i) {
        const Vec x = row_vector(run.log, "x", "_m", i);
        const Vec xe = row_vector(run.log, "xe", "_m", i);
        const Vec f = row_vector(run.log, "f", "_n", i);
        puck_radius_max_m = std::max(puck_radius_max_m, norm(xe));
        puck_height_min_m = std::min(puck_height_min_m, xe[2]);
        device_radius_max_m = std::max(device_radius_max_m, norm(x));
        device_height_min_m = std::min(device_height_min_m, x[2]);
        if (norm(x) > kBowlRadius + 20.0 * kCountM) {
            ++outside;
            if (dot(f, x) < 0.0) ++pulled_back;  // toward the bowl, inward
        }
    }
    std::cout << "[hil] virtual mass: puck |x_e| max " << puck_radius_max_m * 1e3 << " mm (bowl "
              << kBowlRadius * 1e3 << "), z_e min " << puck_height_min_m * 1e3 << " mm (floor "
              << kFloorZ * 1e3 << "); device |x| max " << device_radius_max_m * 1e3 << " mm, z min "
              << device_height_min_m * 1e3 << " mm; pulled back in " << pulled_back << "/"
              << outside << " ticks\n";

    EXPECT_LE(puck_radius_max_m, kBowlRadius + kFreeSpaceToleranceM);
    EXPECT_GE(puck_height_min_m, kFloorZ - kFreeSpaceToleranceM);
    EXPECT_GE(device_radius_max_m, kBowlRadius + kPenetrationM);
    EXPECT_LE(device_height_min_m, kFloorZ - kPenetrationM);
    EXPECT_GT(outside, 500u);
    EXPECT_EQ(pulled_back, outside);
}

}  // namespace
}  // namespace hapticd::testing
