// The flight recorder end to end (docs/daemon.md, "The flight recorder"): hapticd on the sim
// in lockstep, without --log, with an encoder jump at 2.5 s, once the grasp has pushed into
// the wall. The fault ends the run; the last 5 s of ticks (here all 2.5 s of them) are in a
// telemetry CSV beside the summary, the fault's tick last, and the summary and the log name
// the file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "default_config.hpp"
#include "hapticd_run.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "telemetry_csv.hpp"
#include "text_file.hpp"

namespace hapticd::testing {
namespace {

const std::string kJump = "[device.sim.faults]\njump_at = 2.5\njump_counts = 20000\n";

TEST(HilFlightRecorder, AFaultWritesTheTicksBeforeItBesideTheSummaryWithoutALog) {
    const ScratchDir dir;
    const DaemonRun run = run_hapticd(
        dir, {.config_toml = default_config() + kJump, .duration_s = 10.0, .with_log = false});
    ASSERT_EQ(run.exit_code, 1) << run.err;
    ASSERT_TRUE(run.summary.is_object()) << run.err;
    EXPECT_EQ(run.summary["exit"], "fault");
    EXPECT_EQ(run.summary["state"], "fault");
    ASSERT_EQ(run.summary["flight_records"].size(), 1u) << run.summary.dump(2);
    const std::string path = run.summary["flight_records"][0];
    EXPECT_EQ(std::filesystem::path(path).parent_path(), dir.path());
    EXPECT_TRUE(std::filesystem::path(path).filename().string().starts_with("flight-"));
    EXPECT_NE(run.err.find("hapticd: flight recorder: the last 2501 ticks to fault encoder_jump"),
              std::string::npos)
        << run.err;
    EXPECT_NE(run.err.find(path), std::string::npos) << run.err;

    const TelemetryLog flight = read_telemetry(path);
    ASSERT_EQ(flight.rows(), 2501u);  // ticks 0 .. 2500: the jump's tick is the last
    const std::vector<double>& tick = flight.column("tick");
    const std::vector<double>& faults = flight.column("faults");
    EXPECT_EQ(tick.front(), 0.0);
    EXPECT_EQ(tick.back(), 2500.0);
    EXPECT_NE(faults.back(), 0.0);
    for (std::size_t i = 0; i + 1 < faults.size(); ++i) {
        ASSERT_EQ(faults[i], 0.0) << "tick " << tick[i];
    }
    // The state column (§4.5): arming (1) from the start, running (2) once the soft start
    // is done, and fault (3) in the tick that latched it, never before.
    const std::vector<double>& state = flight.column("state");
    EXPECT_EQ(state.front(), 1.0);
    EXPECT_EQ(state.back(), 3.0);
    for (std::size_t i = 1; i + 1 < state.size(); ++i) {
        ASSERT_TRUE(state[i] == 1.0 || state[i] == 2.0) << "tick " << tick[i];
        ASSERT_GE(state[i], state[i - 1]) << "running went back to arming at tick " << tick[i];
    }
    EXPECT_EQ(state[state.size() - 2], 2.0) << "the soft start never finished before the fault";
    // The telemetry the run would have logged: the push into the wall left a force.
    double most_force_n = 0.0;
    for (const double f : flight.column("f0_n")) most_force_n = std::max(most_force_n, std::abs(f));
    EXPECT_GT(most_force_n, 1.0);
}

TEST(HilFlightRecorder, ARunWithNowhereToPutItSaysSoAndWritesNothing) {
    const ScratchDir dir;
    const std::string config = dir.write("cfg.toml", default_config() + kJump);
    const CommandResult r = run_command(
        "cd " + shell_quote(dir.path().string()) + " && " + shell_quote(HAPTICD_BIN) +
        " --lockstep --no-status --duration 10 --summary - --config " + shell_quote(config));
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("not written: no --log, --summary FILE or LOGS_DIRECTORY"),
              std::string::npos)
        << r.err;
    for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
        EXPECT_FALSE(entry.path().filename().string().starts_with("flight-")) << entry.path();
    }
    EXPECT_EQ(nlohmann::json::parse(r.out)["flight_records"], nlohmann::json::array());
}

// --summary /dev/null names no directory for the run's files (issue 28: the flight records
// went to /dev).
TEST(HilFlightRecorder, ASummaryToDevNullPutsNothingInDev) {
    const ScratchDir dir;
    const std::string config = dir.write("cfg.toml", default_config() + kJump);
    const auto flights_in_dev = [] {
        int n = 0;
        for (const auto& entry : std::filesystem::directory_iterator("/dev")) {
            n += entry.path().filename().string().starts_with("flight-") ? 1 : 0;
        }
        return n;
    };
    const int before = flights_in_dev();
    const CommandResult r = run_command(shell_quote(HAPTICD_BIN) +
                                        " --lockstep --no-status --duration 10 --summary "
                                        "/dev/null --config " +
                                        shell_quote(config));
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("not written: no --log, --summary FILE or LOGS_DIRECTORY"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(flights_in_dev(), before);
}

TEST(HilFlightRecorder, AServiceWritesItToItsLogsDirectory) {
    const ScratchDir dir;
    std::filesystem::create_directory(dir.file("logs"));
    const DaemonRun run = run_hapticd(dir, {.config_toml = default_config() + kJump,
                                            .duration_s = 10.0,
                                            .with_log = false,
                                            .environment = {{"LOGS_DIRECTORY", dir.file("logs")}}});
    ASSERT_EQ(run.exit_code, 1) << run.err;
    ASSERT_EQ(run.summary["flight_records"].size(), 1u);
    EXPECT_EQ(
        std::filesystem::path(run.summary["flight_records"][0].get<std::string>()).parent_path(),
        dir.file("logs"));
}

}  // namespace
}  // namespace hapticd::testing
