// haptic-tune plot-run and identify --chart, end to end through the real executable: the
// judgement of a run against traces whose growth is known, the coupling's energy and the
// fault marks against the log they came from, and the fit chart's numbers on a simulated
// identification run. Suite names start with "plot" (`ctest -R plot` runs every chart test).
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>

#include "identification_sim_run.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "text_file.hpp"

namespace hapticd {
namespace {

using hapticd::testing::read_file;
using hapticd::testing::run_command;
using hapticd::testing::ScratchDir;
using nlohmann::json;

std::string tune(const std::string& args) { return std::string(HAPTIC_TUNE) + " " + args; }

constexpr double kPeriodS = 1e-3;
constexpr double kStiffness = 2000.0;  // N/m, for the coupling's energy
constexpr double kStretchM = 2e-4;     // x - xe held by the coupling

/// A 1 kHz log of `seconds`: the handle oscillates at 40 Hz with envelope e^{σt} about a
/// creeping operating point; the tool trails it by kStretchM; the force is the spring's.
/// A fault bit (device_lost) rises at `fault_at_s` and the saturation flag is set on
/// `saturated_ticks` ticks from 1 s on.
std::string oscillating_log(double growth_per_s, double seconds, double fault_at_s = -1.0,
                            int saturated_ticks = 0) {
    std::ostringstream csv;
    csv.precision(17);
    csv << "# name: plot-run test\n"
        << "tick,t_s,x0_m,v0_mps,xe0_m,f0_n,status,flags,faults,state,wake_latency_us,"
           "compute_us,energy_j\n";
    const auto rows = static_cast<int>(seconds / kPeriodS);
    for (int i = 0; i < rows; ++i) {
        const double t = i * kPeriodS;
        const double x = 1e-3 * t + 1e-5 * std::exp(growth_per_s * t) *
                                        std::sin(2.0 * std::numbers::pi * 40.0 * t);
        const int flags = (t >= 1.0 && i < 1000 + saturated_ticks) ? 2 : 0;
        const int faults = (fault_at_s >= 0.0 && t >= fault_at_s) ? 1 : 0;
        csv << i << ',' << t << ',' << x << ",0," << x - kStretchM << ',' << -kStiffness * kStretchM
            << ",0," << flags << ',' << faults << ",2,0,1," << 0.001 * t << '\n';
    }
    return csv.str();
}

json judge(const ScratchDir& dir, const std::string& log, const std::string& extra = "") {
    const std::string path = dir.write("run.csv", log);
    const auto result = run_command(tune("plot-run " + path + " --json " + extra));
    EXPECT_EQ(result.exit_code, 0) << result.err;
    return json::parse(result.out);
}

TEST(plotRun, TheFittedGrowthIsTheEnvelopesAndTheVerdictFollowsIt) {
    const ScratchDir dir;
    for (const double sigma : {-6.0, 0.0, 4.0}) {
        const json j = judge(dir, oscillating_log(sigma, 3.0), "--window 0.1 --floor 1e-14");
        EXPECT_NEAR(j.at("growth_per_s").get<double>(), sigma, 0.05 + 0.02 * std::abs(sigma));
        EXPECT_EQ(j.at("verdict"), sigma > 1.0 ? "grows" : (sigma < -1.0 ? "decays" : "steady"));
        EXPECT_EQ(j.at("rows"), 3000);
        EXPECT_NEAR(j.at("rate_hz").get<double>(), 1000.0, 1e-6);
        EXPECT_EQ(j.at("windows"), 28);  // 0.2 s to 3 s in 0.1 s windows
    }
}

TEST(plotRun, ByDefaultAnEncodersDitherIsNoGrowth) {
    // A 10 um encoder: the handle still, then dithering by one count from 1 s on (a
    // quantised loop at rest). The floor is 3 counts of the smallest position step.
    std::ostringstream csv;
    csv << "t_s,x0_m,f0_n\n";
    for (int i = 0; i < 3000; ++i) {
        const double x = (i >= 1000 && i % 2 == 1) ? 1e-5 : 0.0;
        csv << i * kPeriodS << ',' << x << ",0\n";
    }
    const ScratchDir dir;
    const json j = judge(dir, csv.str());
    EXPECT_EQ(j.at("verdict"), "steady");
    EXPECT_NEAR(j.at("floor_m").get<double>(), 3e-5, 1e-12);
    EXPECT_EQ(j.at("floor_source"), "3 counts of the smallest position step");
    // Told a floor under the count, the same log rises from it.
    EXPECT_EQ(judge(dir, csv.str(), "--floor 1e-6").at("verdict"), "grows");
}

TEST(plotRun, TheCouplingsEnergyIsItsSpringsAndFaultsAndFlagsAreCounted) {
    const ScratchDir dir;
    const json j =
        judge(dir, oscillating_log(0.0, 2.0, 1.5, 7), "--stiffness " + std::to_string(kStiffness));
    EXPECT_NEAR(j.at("peak_coupling_energy_j").get<double>(),
                0.5 * kStiffness * kStretchM * kStretchM, 1e-12);
    ASSERT_EQ(j.at("faults").size(), 1u);
    EXPECT_EQ(j.at("faults")[0].at("fault"), "device_lost");
    EXPECT_NEAR(j.at("faults")[0].at("t_s").get<double>(), 1.5, 1e-9);
    EXPECT_EQ(j.at("flag_counts").at("saturated"), 7);
    EXPECT_EQ(j.at("flag_counts").at("overrun"), 0);
}

TEST(plotRun, WithoutTheStiffnessTheSummarySaysTheEnergyIsNotDrawn) {
    const ScratchDir dir;
    const json j = judge(dir, oscillating_log(0.0, 1.0));
    EXPECT_NE(j.at("coupling_energy").get<std::string>().find("--stiffness"), std::string::npos);
    EXPECT_FALSE(j.contains("peak_coupling_energy_j"));
}

TEST(plotRun, DrawsTheRunAsAPngWithItsJudgementInTheTitle) {
    const ScratchDir dir;
    const std::string log = dir.write("run.csv", oscillating_log(4.0, 2.0, 1.5, 30));
    const std::string out = dir.file("run.svg");
    const auto result = run_command(tune("plot-run " + log + " --stiffness 2000 --out " + out));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const std::string svg = read_file(out);
    EXPECT_NE(svg.find("the oscillation grows"), std::string::npos);
    EXPECT_NE(svg.find("device_lost</text>"), std::string::npos);  // the fault is marked
    EXPECT_NE(svg.find("force saturated (30 ticks shown)"), std::string::npos);
    EXPECT_NE(svg.find("passivity observer"), std::string::npos);
}

TEST(plotRun, BadInputExitsTwoAndNamesIt) {
    const ScratchDir dir;
    const std::string log = dir.write("run.csv", oscillating_log(0.0, 1.0));
    const auto axis = run_command(tune("plot-run " + log + " --axis 1"));
    EXPECT_EQ(axis.exit_code, 2);
    EXPECT_NE(axis.err.find("--axis 1"), std::string::npos) << axis.err;
    const auto missing = run_command(tune("plot-run " + dir.file("none.csv")));
    EXPECT_EQ(missing.exit_code, 2);
    EXPECT_NE(missing.err.find("none.csv"), std::string::npos) << missing.err;
    const std::string broken = dir.write("broken.csv", "t_s,x0_m,f0_n\n0,abc,0\n");
    const auto bad = run_command(tune("plot-run " + broken));
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_NE(bad.err.find("broken.csv:2"), std::string::npos) << bad.err;
    const auto format = run_command(tune("plot-run " + log + " --out " + dir.file("x.gif")));
    EXPECT_EQ(format.exit_code, 2);
    EXPECT_NE(format.err.find(".gif"), std::string::npos) << format.err;
}

TEST(plotIdentifyFit, TheIdentifiedModelRunFreeTracksTheMeasuredVelocity) {
    // A simulated identification run with a loop delay of 2.5 periods: the model that
    // identify fits, run free under the logged force with that delay, explains the measured
    // velocity but for the encoder's quantisation (10 um counts: 10 mm/s steps at 1 kHz).
    tune::testing::SimulatedRun run;
    run.delay_s = 0.0025;
    const ScratchDir dir;
    const std::string log =
        dir.write("id.csv", tune::testing::daemon_csv(tune::testing::simulate_run(run), run.axes));
    const std::string out = dir.file("fit.png");
    const auto result =
        run_command(tune("identify " + log + " --delay 0.0025 --json --chart " + out));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const json j = json::parse(result.out);
    EXPECT_EQ(j.at("chart"), out);
    EXPECT_GT(j.at("free_run_explained_fraction").get<double>(), 0.99);
    EXPECT_LT(j.at("free_run_velocity_rms_error_mps").get<double>(), 0.01);
    EXPECT_EQ(read_file(out).substr(1, 3), "PNG");
    // The same log with the delay left out: the free run lags, and the chart says so.
    const auto undelayed = run_command(
        tune("identify " + log + " --delay 0 --max-relative-std-error 1 --json --chart " + out));
    ASSERT_EQ(undelayed.exit_code, 0) << undelayed.err;
    EXPECT_LT(json::parse(undelayed.out).at("free_run_explained_fraction").get<double>(),
              j.at("free_run_explained_fraction").get<double>());
}

}  // namespace
}  // namespace hapticd
