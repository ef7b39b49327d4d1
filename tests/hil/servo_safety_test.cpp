// HilServoSafety (docs/architecture.md §7.3, §7.6): force the user did not ask for, end to end
// through the real daemon and the sim plugin.
//   - A host stall between a tick's wake and its read (kill -STOP for 55 ms in a real-time
//     run): the backward difference must span the stall, so the velocity limit's brake does
//     not fire on a velocity the handle never had (it commanded max_force before).
//   - The soft start bounds the force commanded: a handle that starts 0.99 m deep in the
//     demo wall is entered through the ramp (the force reached the 20 N limit 3 ms into a
//     0.5 s ramp before).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

#include "hapticd_run.hpp"

namespace hapticd::testing {
namespace {

/// config/hapticd.toml's pen display, hands off, with [identify] and a patient overrun
/// budget (one 55 ms stall must not end the run).
std::string identify_config() {
    return "[servo]\nrate_hz = 1000.0\nrealtime = \"warn\"\n"
           "[device]\nplugin = \"sim\"\naxes = 1\n"
           "[device.model]\nmass = 0.1\ndamping = 2.0\n"
           "[safety]\nmax_force = 10.0\nmax_speed = 1.0\nmax_missed_periods = 1000\n"
           "[device.sim]\nmass = 0.1\ndamping = 2.0\ncounts_per_meter = 1e5\n"
           "force_limit = 20.0\ninitial_position = -0.01\n"
           "[device.sim.human]\nmodel = \"hands-off\"\n"
           // The sim's physics runs on through the stall under the held force (up to 0.75 N
           // for 55 ms moves the hands-off pen display ~20 mm): a wide workspace keeps the run
           // from ending at its edge, which is not what this test is about.
           "[identify]\nforce_amplitude = 0.75\nworkspace = 0.5\n";
}

TEST(HilServoSafety, AHostStallDoesNotTurnIntoAVelocity) {
    const ScratchDir dir;
    const std::string config = dir.write("cfg.toml", identify_config());
    const std::string csv = dir.file("identify.csv");
    const std::string summary = dir.file("summary.json");
    std::ostringstream script;
    script << shell_quote(HAPTICD_BIN) << " --identify --no-status --duration 3 --config "
           << shell_quote(config) << " --log " << shell_quote(csv) << " --summary "
           << shell_quote(summary) << " & pid=$!; sleep 1.5; kill -STOP $pid; sleep 0.055; "
           << "kill -CONT $pid; wait $pid";
    const CommandResult result = run_command("sh -c " + shell_quote(script.str()));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    std::ifstream in(summary);
    const nlohmann::json s = nlohmann::json::parse(in);
    EXPECT_TRUE(s.at("faults").empty()) << s.dump();
    // The stall happened and was seen: at least 40 periods missed in one place.
    const TelemetryLog log = read_telemetry(csv);
    ASSERT_GT(log.rows(), 2000u);
    const auto& t = log.column("t_s");
    const auto& f = log.column("f0_n");
    const auto& v = log.column("v0_mps");
    double longest_gap_s = 0.0;
    for (std::size_t i = 1; i < log.rows(); ++i)
        longest_gap_s = std::max(longest_gap_s, t[i] - t[i - 1]);
    EXPECT_GT(longest_gap_s, 0.040);
    // No force beyond the excitation's peak (0.75 N per axis; no overspeed brake), and no
    // velocity the limit would brake (a hands-off pen display under 0.75 N, even through the
    // stall, stays well below 1 m/s).
    double peak_force_n = 0.0, peak_speed_mps = 0.0;
    for (std::size_t i = 0; i < log.rows(); ++i) {
        peak_force_n = std::max(peak_force_n, std::abs(f[i]));
        peak_speed_mps = std::max(peak_speed_mps, std::abs(v[i]));
    }
    EXPECT_LE(peak_force_n, 0.75 + 1e-9);
    EXPECT_LT(peak_speed_mps, 1.0);  // max_speed: its brake never acted (7 m/s before the fix)
}

TEST(HilServoSafety, TheSoftStartRampBoundsTheForceInsideAWall) {
    constexpr double kMaxForceN = 20.0, kRampS = 0.5, kRateHz = 1000.0;
    const ScratchDir dir;
    // config/hapticd.toml, the demo, with its wall moved to offset = 1.0: the handle at
    // x = -0.01 starts 0.99 m inside it.
    std::ifstream in(std::string(HAPTICD_SOURCE_DIR) + "/config/hapticd.toml");
    std::string config((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string scene_line = "file = \"scenes/demo-wall.toml\"";
    ASSERT_NE(config.find(scene_line), std::string::npos);
    config.replace(config.find(scene_line), scene_line.size(), "file = \"scene.toml\"");
    const DaemonRun run = run_hapticd(
        dir, {.config_toml = config,
              .scene_toml = "[scene]\nname = \"deep\"\naxes = 1\n[[wall]]\nnormal = [-1.0]\n"
                            "offset = 1.0\nstiffness = 2.0e4\ndamping = 5.0\n",
              .duration_s = 1.5});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const auto& f = run.log.column("f0_n");
    std::size_t first = 0;
    while (first < run.log.rows() && f[first] == 0.0) ++first;
    ASSERT_LT(first + 600, run.log.rows());
    // Tick k of the ramp (k = 1 ... 500) commands at most k T/ramp x max_force.
    for (std::size_t k = 1; k <= 500; ++k) {
        const double bound = kMaxForceN * static_cast<double>(k) / (kRampS * kRateHz);
        ASSERT_LE(std::abs(f[first + k - 1]), bound + 1e-9) << "ramp tick " << k;
    }
    EXPECT_NEAR(std::abs(f[first + 99]), kMaxForceN * 0.2, 1e-6);  // saturated, scaled
    EXPECT_NEAR(std::abs(f[first + 550]), kMaxForceN, 1e-9);       // the ramp is over
}

}  // namespace
}  // namespace hapticd::testing
