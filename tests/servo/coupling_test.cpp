// The coupling (16) in both connections: (17) series with a penalty wall, (22) with an
// admittance environment.
#include "hapticd/servo/coupling.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>

#include "hapticd/theory/velocity_filter.hpp"
#include "servo_fakes.hpp"

namespace hapticd::servo {
namespace {

constexpr double kPeriod = 1e-3;

// A wall through the origin with unit normal n, filling n.x < 0: f = k_w (-n.x) n.
struct TiltedWall {
    Vec3 normal{1.0, 0.0, 0.0};
    double stiffness_n_per_m = 1000.0;
    PenaltyForce evaluate(const Vec3& x, const Vec3&) const noexcept {
        PenaltyForce out;
        const double depth = -glm::dot(normal, x);
        if (depth > 0.0) {
            out.force_n = stiffness_n_per_m * depth * normal;
            out.stiffness_n_per_m = stiffness_n_per_m * glm::outerProduct(normal, normal);
        }
        return out;
    }
    void commit(const Vec3&, const Vec3&) noexcept {}
    void reset(const Vec3&) noexcept {}
};

TEST(ServoCoupling, RigidWallGivesSpringsInSeries) {
    // With b_c = 0 the massless tool balances the coupling spring against the wall spring:
    //   k_c (x_d - x_e) = k_w x_e   (wall surface at 0, x_e < 0 inside)
    //   => x_e = k_c x_d / (k_c + k_w),
    // and the handle force -k_c (x_d - x_e) = -k_c k_w / (k_c + k_w) x_d: two springs in series.
    const double k_c = 2000.0;
    const double k_w = 6000.0;
    fakes::PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = k_w};
    VirtualCoupling coupling({.stiffness_n_per_m = k_c, .damping_n_s_per_m = 0.0});
    coupling.reset(Vec3(0.01, 0.0, 0.0));

    const double x_d = -0.004;
    const CouplingStep step = coupling.step(wall, Vec3(x_d, 0.0, 0.0), kPeriod);

    const double series_stiffness = k_c * k_w / (k_c + k_w);
    EXPECT_TRUE(step.finite);
    EXPECT_TRUE(step.converged);
    EXPECT_LE(step.evaluations, 3);  // free-space step, in-wall step, confirmation
    EXPECT_NEAR(step.tool_position_m.x, k_c * x_d / (k_c + k_w), 1e-15);
    EXPECT_NEAR(step.handle_force_n.x, -series_stiffness * x_d, 1e-12);
    EXPECT_DOUBLE_EQ(step.handle_force_n.x, 6.0);  // 1500 N/m * 4 mm
    EXPECT_DOUBLE_EQ(step.tool_force_n.x, -step.handle_force_n.x);
    EXPECT_EQ(step.handle_force_n.y, 0.0);
    EXPECT_EQ(wall.commits, 1);
}

TEST(ServoCoupling, TiltedWallSolvesTheFullJacobian) {
    // Normal direction: springs in series; tangential: the tool follows the device freely.
    const double k_c = 1500.0;
    const double k_w = 4500.0;
    TiltedWall wall{.normal = glm::normalize(Vec3(1.0, 1.0, 0.5)), .stiffness_n_per_m = k_w};
    VirtualCoupling coupling({.stiffness_n_per_m = k_c});
    coupling.reset(Vec3(0.02, 0.02, 0.0));

    const Vec3 x_d(-0.003, 0.001, 0.002);
    const CouplingStep step = coupling.step(wall, x_d, kPeriod);

    const double normal_d = glm::dot(wall.normal, x_d);
    const Vec3 tangential_d = x_d - normal_d * wall.normal;
    const Vec3 expected = tangential_d + (k_c * normal_d / (k_c + k_w)) * wall.normal;
    ASSERT_TRUE(step.converged);
    for (int axis = 0; axis < 3; ++axis)
        EXPECT_NEAR(step.tool_position_m[axis], expected[axis], 1e-15);
    const Vec3 expected_handle = -(k_c * k_w / (k_c + k_w)) * normal_d * wall.normal;
    for (int axis = 0; axis < 3; ++axis) {
        EXPECT_NEAR(step.handle_force_n[axis], expected_handle[axis], 1e-12);
    }
}

TEST(ServoCoupling, DampedSeriesSolveSatisfiesTheBalanceOf17) {
    const double k_c = 3000.0;
    const double b_c = 4.0;
    // A continuous (undamped) wall: the balance has an exact root every tick.
    fakes::PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 20000.0};
    VirtualCoupling coupling({.stiffness_n_per_m = k_c, .damping_n_s_per_m = b_c});
    coupling.reset(Vec3(0.005, 0.0, 0.0));

    // A handle that moves into the wall and back out: 1 cm amplitude, 2 Hz.
    int in_contact_ticks = 0;
    for (int n = 1; n <= 1000; ++n) {
        const Vec3 x_d(0.005 - 0.01 * std::sin(2.0 * M_PI * 2.0 * n * kPeriod), 0.0, 0.0);
        const Vec3 previous_x_d = coupling.previous_device_position_m();
        const Vec3 previous_x_e = coupling.previous_tool_position_m();
        const CouplingStep step = coupling.step(wall, x_d, kPeriod);
        ASSERT_TRUE(step.finite);
        ASSERT_TRUE(step.converged) << "tick " << n;
        ASSERT_LE(step.evaluations, 4) << "tick " << n;
        // (17): k_c (x_d - x_e) + b_c (v_d - v_e) + f_env(x_e, v_e) = 0, recomputed here.
        const Vec3 v_d = (x_d - previous_x_d) / kPeriod;
        const Vec3 v_e = (step.tool_position_m - previous_x_e) / kPeriod;
        const Vec3 balance = k_c * (x_d - step.tool_position_m) + b_c * (v_d - v_e) +
                             wall.evaluate(step.tool_position_m, v_e).force_n;
        EXPECT_NEAR(balance.x, 0.0, 1e-12) << "tick " << n;
        // The handle gets the negative of the coupling force on the tool.
        EXPECT_NEAR(step.handle_force_n.x,
                    -(k_c * (x_d.x - step.tool_position_m.x) + b_c * (v_d.x - v_e.x)), 1e-12);
        if (step.tool_position_m.x < 0.0) ++in_contact_ticks;
    }
    EXPECT_GT(in_contact_ticks, 100);  // the trajectory really exercised the wall
}

TEST(ServoCoupling, DampedWallEnteredAtSpeedSettlesOnTheSurface) {
    // f_env = k_w p - b_w v inside: entering at speed, f jumps by -b_w v_e at the surface, so
    // the balance may have no exact root. The solve must stay finite, never throw, and put
    // the tool where the residual is smallest: at the surface, with a residual no larger
    // than the jump.
    const double k_c = 3000.0;
    const double b_c = 4.0;
    const double b_w = 10.0;
    fakes::PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 20000.0, .damping_n_s_per_m = b_w};
    VirtualCoupling coupling({.stiffness_n_per_m = k_c, .damping_n_s_per_m = b_c});
    coupling.reset(Vec3(0.005, 0.0, 0.0));
    int not_converged = 0;
    for (int n = 1; n <= 1000; ++n) {
        const Vec3 x_d(0.005 - 0.01 * std::sin(2.0 * M_PI * 2.0 * n * kPeriod), 0.0, 0.0);
        const Vec3 previous_x_e = coupling.previous_tool_position_m();
        const CouplingStep step = coupling.step(wall, x_d, kPeriod);
        ASSERT_TRUE(step.finite);
        ASSERT_LE(step.evaluations, SeriesSolverOptions{}.max_evaluations);
        if (!step.converged) {
            ++not_converged;
            const double v_e = (step.tool_position_m.x - previous_x_e.x) / kPeriod;
            EXPECT_NEAR(step.tool_position_m.x, 0.0, 5e-6) << "tick " << n;  // within microns
            EXPECT_LE(step.residual_n, b_w * std::abs(v_e) + 1e-6) << "tick " << n;
        }
    }
    EXPECT_LT(not_converged, 10);  // only the ticks that cross the surface inwards
}

TEST(ServoCoupling, FreeSpaceGivesNoForce) {
    fakes::PlaneWall wall{.wall_m = -1.0};
    VirtualCoupling coupling({.stiffness_n_per_m = 1000.0, .damping_n_s_per_m = 2.0});
    coupling.reset(Vec3(0.0));
    const CouplingStep step = coupling.step(wall, Vec3(0.003, -0.002, 0.001), kPeriod);
    EXPECT_TRUE(step.converged);
    EXPECT_NEAR(glm::length(step.handle_force_n), 0.0, 1e-12);
    EXPECT_NEAR(glm::length(step.tool_position_m - Vec3(0.003, -0.002, 0.001)), 0.0, 1e-15);
}

TEST(ServoCoupling, AdmittancePathGivesTheCouplingForceOf22) {
    const double k_c = 800.0;
    const double b_c = 3.0;
    fakes::FixedPoint environment{.tool_m = Vec3(0.001, 0.002, -0.001)};
    VirtualCoupling coupling({.stiffness_n_per_m = k_c, .damping_n_s_per_m = b_c});
    const Vec3 start(0.0005, 0.0, 0.0);
    coupling.reset(start);

    const Vec3 x_d(0.004, -0.001, 0.0);
    const CouplingStep step = coupling.step(environment, x_d, kPeriod);
    const Vec3 v_d = (x_d - start) / kPeriod;
    const Vec3 v_e = (environment.tool_m - start) / kPeriod;
    const Vec3 expected = -k_c * (x_d - environment.tool_m) - b_c * (v_d - v_e);
    for (int axis = 0; axis < 3; ++axis) {
        EXPECT_NEAR(step.handle_force_n[axis], expected[axis], 1e-12);
        EXPECT_DOUBLE_EQ(step.tool_position_m[axis], environment.tool_m[axis]);
    }
    // Second tick: the tool is still, so v_e = 0.
    const Vec3 x_d2(0.005, -0.001, 0.0);
    const CouplingStep step2 = coupling.step(environment, x_d2, kPeriod);
    const Vec3 expected2 = -k_c * (x_d2 - environment.tool_m) - b_c * (x_d2 - x_d) / kPeriod;
    for (int axis = 0; axis < 3; ++axis)
        EXPECT_NEAR(step2.handle_force_n[axis], expected2[axis], 1e-12);
}

TEST(ServoCoupling, NonFiniteEnvironmentIsReportedAndNotCommitted) {
    fakes::NanAfter environment{.after_evaluations = 0};
    VirtualCoupling coupling({.stiffness_n_per_m = 1000.0});
    coupling.reset(Vec3(0.0));
    const CouplingStep step = coupling.step(environment, Vec3(0.001, 0.0, 0.0), kPeriod);
    EXPECT_FALSE(step.finite);
    EXPECT_FALSE(step.converged);
    EXPECT_EQ(glm::length(step.handle_force_n), 0.0);
}

TEST(ServoCoupling, IterationCapReportsNonConvergenceWithoutThrowing) {
    fakes::PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 5000.0};
    VirtualCoupling coupling({.stiffness_n_per_m = 1000.0}, {.max_evaluations = 1});
    coupling.reset(Vec3(0.01, 0.0, 0.0));
    const CouplingStep step = coupling.step(wall, Vec3(-0.004, 0.0, 0.0), kPeriod);
    EXPECT_TRUE(step.finite);
    EXPECT_FALSE(step.converged);
    EXPECT_EQ(step.evaluations, 1);
    EXPECT_GT(step.residual_n, 1.0);
}

// ---- The damper's velocity filter (theory/velocity_filter.hpp) ------------------------------

/// f_c with a = exp(-2π f_c T) = 1/2 (to rounding) at T = 1 ms: ln 2 / (2π T).
const double kHalfPoleHz = std::log(2.0) / (2.0 * M_PI * kPeriod);

TEST(ServoCouplingFilter, FollowsTheHandComputedSequence) {
    // The tool held at 0 (v_e = 0), the handle at 1, 2, 2, 2, 0 mm from rest at 0: v_d = 1, 1,
    // 0, 0, -2 m/s, and with a = 1/2 the damper's velocity u[n] = u[n-1]/2 + v_d[n]/2 is
    // 0.5, 0.75, 0.375, 0.1875, -0.90625 m/s. F = k_c x_d + b_c u with k_c = 1000 N/m,
    // b_c = 2 N s/m: 2, 3.5, 2.75, 2.375, -1.8125 N on the tool; the handle gets -F.
    fakes::FixedPoint environment{.tool_m = Vec3(0.0)};
    VirtualCoupling coupling(
        {.stiffness_n_per_m = 1000.0, .damping_n_s_per_m = 2.0, .velocity_filter_hz = kHalfPoleHz});
    EXPECT_NEAR(theory::velocity_filter_pole(kHalfPoleHz, kPeriod), 0.5, 1e-15);
    coupling.reset(Vec3(0.0));
    const double x_mm[] = {1.0, 2.0, 2.0, 2.0, 0.0};
    const double u_expected[] = {0.5, 0.75, 0.375, 0.1875, -0.90625};
    const double f_expected[] = {2.0, 3.5, 2.75, 2.375, -1.8125};
    for (int n = 0; n < 5; ++n) {
        const CouplingStep step =
            coupling.step(environment, Vec3(x_mm[n] * 1e-3, 0.0, 0.0), kPeriod);
        ASSERT_TRUE(step.finite);
        EXPECT_NEAR(step.damper_velocity_mps.x, u_expected[n], 1e-12) << "tick " << n;
        EXPECT_NEAR(step.tool_force_n.x, f_expected[n], 1e-12) << "tick " << n;
        EXPECT_EQ(step.handle_force_n.x, -step.tool_force_n.x);
        EXPECT_EQ(coupling.previous_damper_velocity_mps().x, step.damper_velocity_mps.x);
    }
}

TEST(ServoCouplingFilter, SeriesSolveSatisfiesTheFilteredBalanceOf17) {
    // The handle in and out of a damped wall; each tick the committed x_e must balance
    //   k_c (x_d - x_e) + b_c u[n] + f_env(x_e, v_e) = 0,  u[n] = a u[n-1] + (1 - a)(v_d - v_e),
    // with u[n-1] the filter state recomputed here from the steps.
    const double k_c = 3000.0;
    const double b_c = 4.0;
    const double f_c = 100.0;
    const double a = std::exp(-2.0 * M_PI * f_c * kPeriod);
    fakes::PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 20000.0};
    VirtualCoupling coupling(
        {.stiffness_n_per_m = k_c, .damping_n_s_per_m = b_c, .velocity_filter_hz = f_c});
    coupling.reset(Vec3(0.005, 0.0, 0.0));
    double u = 0.0;
    int in_contact_ticks = 0;
    for (int n = 1; n <= 1000; ++n) {
        const Vec3 x_d(0.005 - 0.01 * std::sin(2.0 * M_PI * 2.0 * n * kPeriod), 0.0, 0.0);
        const Vec3 previous_x_d = coupling.previous_device_position_m();
        const Vec3 previous_x_e = coupling.previous_tool_position_m();
        const CouplingStep step = coupling.step(wall, x_d, kPeriod);
        ASSERT_TRUE(step.finite);
        ASSERT_TRUE(step.converged) << "tick " << n;
        const double v_d = (x_d.x - previous_x_d.x) / kPeriod;
        const double v_e = (step.tool_position_m.x - previous_x_e.x) / kPeriod;
        u = a * u + (1.0 - a) * (v_d - v_e);
        EXPECT_NEAR(step.damper_velocity_mps.x, u, 1e-12 * (1.0 + std::abs(u))) << "tick " << n;
        const double coupling_force = k_c * (x_d.x - step.tool_position_m.x) + b_c * u;
        const double balance =
            coupling_force + wall.evaluate(step.tool_position_m, Vec3(v_e, 0, 0)).force_n.x;
        EXPECT_NEAR(balance, 0.0, 1e-9) << "tick " << n;
        EXPECT_NEAR(step.handle_force_n.x, -coupling_force, 1e-9) << "tick " << n;
        if (step.tool_position_m.x < 0.0) ++in_contact_ticks;
    }
    EXPECT_GT(in_contact_ticks, 100);
}

TEST(ServoCouplingFilter, NoFilterIsTheUnfilteredForceToTheBit) {
    // f_c = 0: F_c = k_c (x_d - x_e) + b_c (v_d - v_e) exactly, tick after tick.
    const double k_c = 3000.0;
    const double b_c = 4.0;
    fakes::PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 20000.0, .damping_n_s_per_m = 3.0};
    VirtualCoupling coupling({.stiffness_n_per_m = k_c, .damping_n_s_per_m = b_c});
    coupling.reset(Vec3(0.005, 0.0, 0.0));
    for (int n = 1; n <= 500; ++n) {
        const Vec3 x_d(0.005 - 0.01 * std::sin(2.0 * M_PI * 3.0 * n * kPeriod), 0.0, 0.0);
        const Vec3 previous_x_d = coupling.previous_device_position_m();
        const Vec3 previous_x_e = coupling.previous_tool_position_m();
        const CouplingStep step = coupling.step(wall, x_d, kPeriod);
        const Vec3 v_d = (x_d - previous_x_d) * (1.0 / kPeriod);
        const Vec3 v_e = (step.tool_position_m - previous_x_e) * (1.0 / kPeriod);
        const Vec3 force = k_c * (x_d - step.tool_position_m) + b_c * (v_d - v_e);
        ASSERT_EQ(step.tool_force_n.x, force.x) << "tick " << n;
        ASSERT_EQ(step.damper_velocity_mps.x, (v_d - v_e).x) << "tick " << n;
    }
}

/// Admittance: a free virtual mass integrated by implicit Euler with the gains it is handed
/// (env::VirtualMass without spring, damper or constraints): it sees only the unfiltered
/// equivalent of the filtered coupling.
struct ImplicitMass {
    double mass_kg = 0.05;
    Vec3 x{0.0}, v{0.0};
    CouplingGains last_gains{};
    Vec3 step(const Vec3& x_d, const Vec3& v_d, const CouplingGains& g, double t) noexcept {
        last_gains = g;
        const double d = mass_kg + t * g.damping_n_s_per_m + t * t * g.stiffness_n_per_m;
        v = (mass_kg * v + t * (g.stiffness_n_per_m * (x_d - x) + g.damping_n_s_per_m * v_d)) / d;
        x += t * v;
        return x;
    }
    void reset(const Vec3& position) noexcept {
        x = position;
        v = Vec3(0.0);
    }
};
static_assert(AdmittancePort<ImplicitMass>);

TEST(ServoCouplingFilter, AdmittanceMassFeelsTheFilteredForceAtTheEndOfTheStep) {
    // The mass's implicit update must be driven by the filtered coupling force of the same
    // tick: m_e (v_e[n] - v_e[n-1]) / T = k_c (x_d - x_e[n]) + b_c u[n] (exact_model.hpp).
    const double k_c = 2000.0, b_c = 3.0, f_c = 50.0;
    ImplicitMass mass;
    mass.reset(Vec3(0.0));
    VirtualCoupling coupling(
        {.stiffness_n_per_m = k_c, .damping_n_s_per_m = b_c, .velocity_filter_hz = f_c});
    coupling.reset(Vec3(0.0));
    const double a = std::exp(-2.0 * M_PI * f_c * kPeriod);
    for (int n = 1; n <= 300; ++n) {
        const Vec3 x_d(0.002 * std::sin(2.0 * M_PI * 7.0 * n * kPeriod), 0.0, 0.0);
        const Vec3 v_before = mass.v;
        const CouplingStep step = coupling.step(mass, x_d, kPeriod);
        ASSERT_TRUE(step.finite);
        EXPECT_EQ(mass.last_gains.velocity_filter_hz, 0.0);
        EXPECT_NEAR(mass.last_gains.damping_n_s_per_m, (1.0 - a) * b_c, 1e-15);
        EXPECT_NEAR(mass.mass_kg * (mass.v.x - v_before.x) / kPeriod, step.tool_force_n.x,
                    1e-9 * (1.0 + std::abs(step.tool_force_n.x)))
            << "tick " << n;
        EXPECT_NEAR(step.tool_velocity_mps.x, mass.v.x, 1e-12);
    }
}

TEST(ServoCouplingFilter, ResetAndTrackingEmptyTheFilterAndFailuresCommitNothing) {
    fakes::FixedPoint environment{.tool_m = Vec3(0.0)};
    VirtualCoupling coupling(
        {.stiffness_n_per_m = 1000.0, .damping_n_s_per_m = 2.0, .velocity_filter_hz = 100.0});
    coupling.reset(Vec3(0.0));
    (void)coupling.step(environment, Vec3(0.001, 0.0, 0.0), kPeriod);
    EXPECT_GT(coupling.previous_damper_velocity_mps().x, 0.0);
    coupling.track_device(Vec3(0.002, 0.0, 0.0));
    EXPECT_EQ(coupling.previous_damper_velocity_mps().x, 0.0);
    (void)coupling.step(environment, Vec3(0.003, 0.0, 0.0), kPeriod);
    EXPECT_NE(coupling.previous_damper_velocity_mps().x, 0.0);
    coupling.reset(Vec3(0.003, 0.0, 0.0));
    EXPECT_EQ(coupling.previous_damper_velocity_mps(), Vec3(0.0));

    // A non-finite solve commits nothing, the filter's state included.
    fakes::PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 5000.0};
    VirtualCoupling series(
        {.stiffness_n_per_m = 1000.0, .damping_n_s_per_m = 2.0, .velocity_filter_hz = 100.0});
    series.reset(Vec3(0.0));
    (void)series.step(wall, Vec3(-0.001, 0.0, 0.0), kPeriod);
    const Vec3 state = series.previous_damper_velocity_mps();
    EXPECT_NE(state.x, 0.0);
    fakes::NanAfter nan{.after_evaluations = 0};
    const CouplingStep failed = series.step(nan, Vec3(-0.002, 0.0, 0.0), kPeriod);
    EXPECT_FALSE(failed.finite);
    EXPECT_EQ(series.previous_damper_velocity_mps(), state);
}

TEST(ServoCouplingFilter, AnOverrunSamplesTheLowPassOverTheWholeInterval) {
    // A step spanning 3 T uses a = exp(-2π f_c 3T): u = (1 - a) v_d from rest.
    const double f_c = 80.0;
    fakes::FixedPoint environment{.tool_m = Vec3(0.0)};
    VirtualCoupling coupling(
        {.stiffness_n_per_m = 0.0, .damping_n_s_per_m = 1.0, .velocity_filter_hz = f_c});
    coupling.reset(Vec3(0.0));
    const CouplingStep late = coupling.step(environment, Vec3(0.003, 0.0, 0.0), 3.0 * kPeriod);
    const double a3 = std::exp(-2.0 * M_PI * f_c * 3.0 * kPeriod);
    EXPECT_NEAR(late.damper_velocity_mps.x, (1.0 - a3) * 1.0, 1e-14);
    const CouplingStep next = coupling.step(environment, Vec3(0.003, 0.0, 0.0), kPeriod);
    const double a1 = std::exp(-2.0 * M_PI * f_c * kPeriod);
    EXPECT_NEAR(next.damper_velocity_mps.x, a1 * (1.0 - a3), 1e-14);
}

}  // namespace
}  // namespace hapticd::servo
