// HilPaperGains: the coupling the paper's own design procedure gives, (21) with the hold
// model (13) as printed, is unstable on the real sampled-data loop; the encoder-sized
// coupling on the identical setup is not. Same scene, same operator, same start, same
// judge: only k_c differs.
//
// Physics. The handle is coupled to the tool by (16), in series with the penalty wall
// (17), with gains sized by (21). At b_c = 0 the `paper` model allows k_c = 8b/T =
// 16000 N/m for the pen display, four times Colgate and Schenkel's bound 2b/T. The handle
// in contact feels k_c in series with the wall (1e5 N/m): 13793 N/m. The hold's half-sample
// delay and the backward difference's other half turn that stiffness into a negative
// damping of about k T/2 = 6.9 N s/m, against the device's b = 2 N s/m plus whatever the
// operator adds: the exact model finds hands-off against a rigid wall growing by
// |z| = 1.029 per tick at 63 Hz (28.7/s; 23.5/s with this wall), and a 0.3 kg hand with
// 0.5 N s/m to ground growing at about (6.9 - 2.5) / (2 * 0.4) = 5.5/s. The encoder-sized
// 4000 N/m (3846 N/m in series) stays inside the exact bound k T/2 < b + b_c
// (docs/stability-models.md).
//
// Experiment. The handle starts at rest on the wall's surface; after the soft start's wait
// for a still handle (0.2 s) the force is switched on at once (no ramp), and nothing but
// the encoder's quantisation excites the loop. An unstable loop grows from that count-level
// noise until the handle bounces off the wall (a limit cycle: the wall only pushes); a
// stable one stays at the count level. The daemon runs the paper's gains because the
// config asks for check = "paper" (they pass the model they were sized with); the default
// check = "passive" refuses them (tested below).
#include <gtest/gtest.h>

#include <iostream>
#include <string>

#include "hapticd_run.hpp"
#include "operators.hpp"
#include "pen_display.hpp"
#include "tuned_gains.hpp"
#include "wall_contact.hpp"

namespace hapticd::testing {
namespace {

constexpr double kWallStiffnessNPerM = 1e5;
constexpr double kDurationS = 4.0;
constexpr double kJudgeFromS = 0.2;  ///< the soft start's wait for a still handle ends
constexpr double kWindowS = 0.05;    ///< 3 periods at 63 Hz, 1.5 at the heavy hand's 30 Hz

ContactJudgement run_contact(const std::string& label, const CouplingGains& gains,
                             const std::string& check, const std::string& human) {
    DaemonConfig config;
    config.coupling = coupling_table(gains, check);
    config.initial_position = "0.0";  // at rest, touching the wall
    config.humans = human_table(human);
    // No ramp: the full k_c acts from the first force on (a ramp would sweep the loop
    // through a range of gains while the oscillation rises).
    config.soft_start_ramp_s = 0.0;
    const ScratchDir dir;
    const DaemonRun run = run_hapticd(dir, {.config_toml = config.toml(),
                                            .scene_toml = wall_contact_scene(kWallStiffnessNPerM),
                                            .duration_s = kDurationS});
    EXPECT_EQ(run.exit_code, 0) << label << "\n" << run.err;
    EXPECT_EQ(fault_list(run), "") << label;
    EXPECT_EQ(run.log.rows(), static_cast<std::size_t>(kDurationS * kRateHz)) << label;
    if (run.log.rows() == 0) return {};
    ContactJudgement judged = judge_wall_contact(run.log, kJudgeFromS, kWindowS);
    std::cout << "[hil] " << label << " (k_c = " << gains.stiffness_n_per_m
              << " N/m): " << describe(judged) << "\n";
    return judged;
}

// The judge, both ways, on the same numbers. Stable: no growth, the quantisation noise
// stays at the count level, and the tool never leaves the wall. Unstable: the oscillation
// rises from the quantisation noise at a clear exponential rate, more than tenfold, and the
// handle ends up bouncing off the wall (a limit cycle: the wall only pushes). The rise is
// slower than the linear pole (23.5/s hands-off): for hands-off the tool stays in the wall
// only while the handle's outward excursion is below 0.5 N / k_c = 31 um, so most of the
// rise is already the bouncing, whose energy grows a little at every contact.
void expect_stable(const ContactJudgement& judged) {
    EXPECT_LE(judged.trend.growth_per_s, 0.2);
    EXPECT_EQ(judged.trend.rise_growth_per_s, 0.0);
    EXPECT_LE(judged.trend.peak_amplitude_m, 6.0 * kCountM);
    EXPECT_TRUE(judged.contact_kept()) << "left the wall at " << judged.contact_lost_at_s << " s";
}

void expect_unstable(const ContactJudgement& judged, double min_growth_per_s) {
    EXPECT_GE(judged.trend.rise_growth_per_s, min_growth_per_s);
    EXPECT_GE(judged.trend.rise_factor(), 10.0);
    EXPECT_GE(judged.trend.peak_amplitude_m, 30.0 * kCountM);
    EXPECT_FALSE(judged.contact_kept());
}

TEST(HilPaperGains, GrowHandsOffWhileEncoderGainsDoNot) {
    const CouplingGains paper = size_coupling("paper");
    const CouplingGains encoder = size_coupling("encoder");
    ASSERT_NEAR(paper.stiffness_n_per_m, 4.0 * kColgateStiffnessNPerM, 1e-3);  // 8b/T
    const ContactJudgement unstable =
        run_contact("paper gains, hands-off", paper, "paper", hands_off());
    const ContactJudgement stable =
        run_contact("encoder gains, hands-off", encoder, "encoder", hands_off());
    expect_unstable(unstable, 5.0);
    expect_stable(stable);
}

TEST(HilPaperGains, GrowWithAHeavyHandWhileEncoderGainsDoNot) {
    const CouplingGains paper = size_coupling("paper");
    const CouplingGains encoder = size_coupling("encoder");
    const ContactJudgement unstable =
        run_contact("paper gains, heavy hand", paper, "paper", heavy_hand());
    const ContactJudgement stable =
        run_contact("encoder gains, heavy hand", encoder, "encoder", heavy_hand());
    expect_unstable(unstable, 1.5);
    expect_stable(stable);
}

// The daemon's own start-up check, with its default passive model, refuses the paper's
// gains before any force flows: the guard that the experiment above had to switch off.
TEST(HilPaperGains, AreRefusedByTheDefaultPassiveCheck) {
    DaemonConfig config;
    config.coupling = coupling_table(size_coupling("paper"), "passive");
    const ScratchDir dir;
    const DaemonRun run = run_hapticd(dir, {.config_toml = config.toml(),
                                            .scene_toml = wall_contact_scene(kWallStiffnessNPerM),
                                            .duration_s = 1.0});
    EXPECT_EQ(run.exit_code, 2) << run.err;
    EXPECT_NE(run.err.find("refusing to arm"), std::string::npos) << run.err;
    EXPECT_TRUE(run.log.rows() == 0);
}

}  // namespace
}  // namespace hapticd::testing
