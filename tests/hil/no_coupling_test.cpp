// HilNoCoupling: the conventional design the paper improves on. Without the virtual
// coupling ([coupling] enabled = false) the penalty wall's force acts on the handle
// directly, and the wall itself must meet Colgate and Schenkel's bound
//
//     b > K T / 2 + |B|
//
// (device damping b, wall stiffness K and damping B, period T): for the pen display,
// K < 2b/T = 4000 N/m at B = 0, however stiff the wall was meant to be. That is the limit
// the paper's coupling removes: with it, the wall above can be 1e5 N/m (HilEncoderGains).
//
// Physics. Hands-off, the handle (m = 0.1 kg, b = 2 N s/m) sits in the wall, held there by
// the scene's 0.5 N preload spring, 0.5 N / K deep. The zero-order hold and the sampled
// position delay the wall's force by about half a sample, which acts as a negative damping
// K T/2 against b: the exact sampled loop decays at (b - K T/2) / 2m = 2.5/s for
// K = 3000 N/m (0.75 of the bound) and grows at 2.35/s for K = 5000 N/m (1.25 of it).
//
// Experiment. The handle starts at rest on the wall's surface; after the soft start's wait
// for a still handle the preload and the wall ramp in over 0.5 s and the handle sinks to its
// rest depth (17 and 10 counts). Nothing excites the loop but the encoder's quantisation.
// Judged by the same ContactJudgement as the coupled tests; the tool is the handle here.
//
// Not tested: the wall damping B counts against b in the bound too, but the bound is a
// passivity bound. With K below 2b/T, a B that breaks it destabilises only an operator that
// makes the handle resonate near the Nyquist frequency (the exact limit there is
// B + K T/2 < (pi^2/8) b, docs/stability-models.md); hands-off stays stable (the exact loop
// decays at about 18/s for K = 2000 N/m, B = 2.5 N s/m), and a grip stiff enough to
// resonate the handle at 500 Hz holds it still to well under one 10 um encoder count, so
// the daemon never sees the motion.
#include <gtest/gtest.h>

#include <iostream>
#include <string>

#include "hapticd_run.hpp"
#include "operators.hpp"
#include "pen_display.hpp"
#include "wall_contact.hpp"

namespace hapticd::testing {
namespace {

constexpr double kDurationS = 6.0;
constexpr double kJudgeFromS = 0.7;  ///< the preload is fully in: 0.2 s wait + 0.5 s ramp

ContactJudgement run_rigid_wall(double wall_stiffness_n_per_m, double wall_damping_n_s_per_m) {
    DaemonConfig config;
    config.coupling = no_coupling_table();
    config.initial_position = "0.0";  // at rest on the surface
    config.humans = human_table(hands_off());
    const ScratchDir dir;
    const DaemonRun run = run_hapticd(
        dir, {.config_toml = config.toml(),
              .scene_toml = wall_contact_scene(wall_stiffness_n_per_m, wall_damping_n_s_per_m),
              .duration_s = kDurationS});
    EXPECT_EQ(run.exit_code, 0) << run.err;
    EXPECT_EQ(fault_list(run), "");
    EXPECT_EQ(run.log.rows(), static_cast<std::size_t>(kDurationS * kRateHz));
    if (run.log.rows() == 0) return {};
    // No coupling: the tool is the handle in every tick.
    EXPECT_EQ(run.log.column("xe0_m"), run.log.column("x0_m"));
    ContactJudgement judged = judge_wall_contact(run.log, kJudgeFromS);
    std::cout << "[hil] no coupling, K = " << wall_stiffness_n_per_m
              << " N/m, B = " << wall_damping_n_s_per_m << " N s/m (K T/2 + B = "
              << wall_stiffness_n_per_m * kPeriodS / 2.0 + wall_damping_n_s_per_m
              << " N s/m vs b = " << kPenDampingNsPerM << "): " << describe(judged) << "\n";
    return judged;
}

TEST(HilNoCoupling, ColgateBoundSeparatesAStableWallFromAGrowingOne) {
    const double inside_bound_n_per_m = 0.75 * kColgateStiffnessNPerM;   // 3000 N/m
    const double outside_bound_n_per_m = 1.25 * kColgateStiffnessNPerM;  // 5000 N/m
    const ContactJudgement stable = run_rigid_wall(inside_bound_n_per_m, 0.0);
    const ContactJudgement unstable = run_rigid_wall(outside_bound_n_per_m, 0.0);

    // Inside the bound: the quantisation noise does not grow, the handle stays in the wall.
    EXPECT_LE(stable.trend.growth_per_s, 0.2);
    EXPECT_EQ(stable.trend.rise_growth_per_s, 0.0);
    EXPECT_LE(stable.trend.peak_amplitude_m, 6.0 * kCountM);
    EXPECT_TRUE(stable.contact_kept()) << "left the wall at " << stable.contact_lost_at_s;

    // Outside it: the same noise grows tenfold and more until the handle bounces off.
    EXPECT_GE(unstable.trend.rise_growth_per_s, 1.0);
    EXPECT_GE(unstable.trend.rise_factor(), 10.0);
    EXPECT_FALSE(unstable.contact_kept());
}

}  // namespace
}  // namespace hapticd::testing
