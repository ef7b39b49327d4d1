// haptic-tune identify end to end: a simulated run written by the daemon's CSV writer into a
// file, identified by the real executable.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "identification_sim_run.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"

namespace hapticd::tune {
namespace {

using hapticd::testing::run_command;
using hapticd::testing::ScratchDir;
using nlohmann::json;

std::string tune(const std::string& args) { return std::string(HAPTIC_TUNE) + " " + args; }

std::string simulated_csv(int axes = 1) {
    testing::SimulatedRun run;
    run.axes = axes;
    return testing::daemon_csv(testing::simulate_run(run), axes);
}

#define EXPECT_CONTAINS(text, part) \
    EXPECT_NE(std::string(text).find(part), std::string::npos) << "in: " << (text)

TEST(HapticTuneIdentify, PrintsTheDesignNamesAsJson) {
    const ScratchDir dir;
    const std::string log = dir.write("json.csv", simulated_csv());
    const auto result = run_command(tune("identify " + log + " --json"));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_EQ(result.err, "");
    const json j = json::parse(result.out);
    EXPECT_NEAR(j.at("mass").get<double>(), 0.1, 0.002);
    EXPECT_NEAR(j.at("damping").get<double>(), 2.0, 0.04);
    EXPECT_NEAR(j.at("coulomb").get<double>(), 0.2, 0.02);
    EXPECT_NEAR(j.at("offset").get<double>(), 0.05, 0.005);
    for (const char* key :
         {"mass_std_error", "damping_std_error", "coulomb_std_error", "offset_std_error",
          "residual_rms_m", "residual_rms_counts", "solve_time_s"}) {
        EXPECT_GT(j.at(key).get<double>(), 0.0) << key;
    }
    EXPECT_EQ(j.at("axis"), 0);
    EXPECT_EQ(j.at("samples"), 10001);
    EXPECT_EQ(j.at("segments"), 500);
    EXPECT_EQ(j.at("converged"), true);
    EXPECT_EQ(j.at("resolution_source"), "log");
    EXPECT_EQ(j.at("log"), log);
    EXPECT_LT(j.at("solve_time_s").get<double>(), 10.0);
}

TEST(HapticTuneIdentify, DelayShiftsTheForcesByTheLoopDelayAndIsChecked) {
    const ScratchDir dir;
    testing::SimulatedRun run;
    run.delay_s = 0.001;  // one period: a serial board's host-paced schedule
    const std::string log =
        dir.write("delayed.csv", testing::daemon_csv(testing::simulate_run(run), 1));
    const auto with = run_command(tune("identify " + log + " --json --delay 0.001"));
    ASSERT_EQ(with.exit_code, 0) << with.err;
    const json j = json::parse(with.out);
    EXPECT_EQ(j.at("delay_s").get<double>(), 0.001);
    EXPECT_NEAR(j.at("mass").get<double>(), 0.1, 0.0002);
    EXPECT_NEAR(j.at("damping").get<double>(), 2.0, 0.01);

    const auto without = run_command(tune("identify " + log + " --json"));
    EXPECT_EQ(without.exit_code, 2);
    EXPECT_CONTAINS(without.err, "[too_little_excitation]");
    EXPECT_CONTAINS(without.err, "--delay");

    for (const char* bad : {"-0.001", "nan", "x"}) {
        const auto refused = run_command(tune("identify " + log + " --delay " + bad));
        EXPECT_EQ(refused.exit_code, 2) << bad;
        EXPECT_CONTAINS(refused.err, "--delay");
    }
    const auto too_long = run_command(tune("identify " + log + " --delay 0.01"));
    EXPECT_EQ(too_long.exit_code, 2);
    EXPECT_CONTAINS(too_long.err, "delay_s");
    EXPECT_CONTAINS(too_long.err, "10 periods");
}

TEST(HapticTuneIdentify, TextOutputNamesEveryField) {
    const ScratchDir dir;
    const std::string log = dir.write("text.csv", simulated_csv());
    const auto result = run_command(tune("identify " + log));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    for (const char* key :
         {"mass ", "mass_std_error", "damping ", "damping_std_error", "coulomb ",
          "coulomb_std_error", "offset ", "residual_rms_counts", "solve_time_s"}) {
        EXPECT_CONTAINS(result.out, key);
    }
}

TEST(HapticTuneIdentify, EveryAxisOrTheOneAsked) {
    const ScratchDir dir;
    const std::string log = dir.write("axes.csv", simulated_csv(2));
    const auto all = run_command(tune("identify " + log + " --json"));
    ASSERT_EQ(all.exit_code, 0) << all.err;
    const json j = json::parse(all.out);
    ASSERT_EQ(j.at("axes").size(), 2u);
    EXPECT_EQ(j.at("axes")[1].at("axis"), 1);
    EXPECT_NEAR(j.at("axes")[1].at("mass").get<double>(), 0.1, 0.002);
    const auto one = run_command(tune("identify " + log + " --axis 1 --json"));
    ASSERT_EQ(one.exit_code, 0) << one.err;
    EXPECT_EQ(json::parse(one.out).at("axis"), 1);
    EXPECT_EQ(json::parse(one.out).at("mass"), j.at("axes")[1].at("mass"));
}

TEST(HapticTuneIdentify, ExitsTwoWithTheReasonOnALogThatCannotIdentify) {
    const ScratchDir dir;
    const std::string log = dir.write("one-axis.csv", simulated_csv());
    const auto wrong_axis = run_command(tune("identify " + log + " --axis 2"));
    EXPECT_EQ(wrong_axis.exit_code, 2);
    EXPECT_CONTAINS(wrong_axis.err, "cannot identify: no x2_m/f2_n for axis 2");
    EXPECT_CONTAINS(wrong_axis.err, "[missing_column]");
    EXPECT_EQ(wrong_axis.out, "");

    const std::string idle = dir.write("idle.csv", "t_s,x0_m,f0_n\n0,0,0\n0.001,0,0\n0.002,0,0\n");
    const auto too_short = run_command(tune("identify " + idle));
    EXPECT_EQ(too_short.exit_code, 2);
    EXPECT_CONTAINS(too_short.err, "[too_short]");

    const auto limited = run_command(tune("identify " + log + " --force-limit 1"));
    EXPECT_EQ(limited.exit_code, 2);
    EXPECT_CONTAINS(limited.err, "[saturated]");
}

TEST(HapticTuneIdentify, ExitsTwoOnABadLogOrBadOptions) {
    const ScratchDir dir;
    const std::string broken = dir.write("broken.csv", "t_s,x0_m,f0_n\n0,0,0\n0.001,zero,0\n");
    const auto bad = run_command(tune("identify " + broken));
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_CONTAINS(bad.err, "bad log: " + broken + ":3:2 (x0_m): 'zero' is not a finite");

    const auto missing = run_command(tune("identify /nonexistent/run.csv"));
    EXPECT_EQ(missing.exit_code, 2);
    EXPECT_CONTAINS(missing.err, "cannot open the log");

    const auto no_log = run_command(tune("identify"));
    EXPECT_EQ(no_log.exit_code, 2);
    EXPECT_CONTAINS(no_log.err, "LOG");

    const auto negative = run_command(tune("identify " + broken + " --resolution -1"));
    EXPECT_EQ(negative.exit_code, 2);
    EXPECT_CONTAINS(negative.err, "--resolution");
}

}  // namespace
}  // namespace hapticd::tune
