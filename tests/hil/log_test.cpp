// HilLog: the telemetry CSV of a lockstep run is complete and means what
// docs/architecture.md §4.5 says: the header is exactly the public column names, there is one
// row per tick numbered from 0 without a gap (the run is longer than the telemetry ring, so the
// loop must have waited for the writer: lockstep backpressure, §3.5), the summary's counts
// agree, t_s is virtual time, and v is the backward difference of x that the coupling (16)
// uses.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "hapticd_run.hpp"
#include "operators.hpp"
#include "pen_display.hpp"
#include "run_command.hpp"
#include "tuned_gains.hpp"
#include "wall_contact.hpp"

namespace hapticd::testing {
namespace {

// Longer than the daemon's lockstep ring (2^14 records), so a lossy log would show.
constexpr double kDurationS = 30.0;

TEST(HilLog, LockstepLogIsCompleteAndConsistent) {
    DaemonConfig config;
    config.coupling = coupling_table(size_coupling("encoder"), "encoder");
    config.initial_position = "-0.001";
    config.humans = human_table(stiff_grasp(push_toml(0.005, 1.0, 0.2, 2.0)));
    const ScratchDir dir;
    const DaemonRun run = run_hapticd(dir, {.config_toml = config.toml(),
                                            .scene_toml = wall_contact_scene(1e5),
                                            .duration_s = kDurationS});
    ASSERT_EQ(run.exit_code, 0) << run.err;

    EXPECT_EQ(run.log_header,
              "tick,t_s,unix_time_s,x0_m,v0_mps,xe0_m,f0_n,status,tick_flags,faults,state,"
              "wake_latency_us,compute_us,energy_j,mark");
    const auto ticks = run.summary.at("ticks").get<std::size_t>();
    EXPECT_EQ(ticks, static_cast<std::size_t>(kDurationS * kRateHz));
    EXPECT_EQ(run.log.rows(), ticks);
    EXPECT_EQ(run.summary.at("telemetry_records").get<std::size_t>(), ticks);
    EXPECT_EQ(run.summary.at("telemetry_dropped").get<std::size_t>(), 0u);

    const auto& tick = run.log.column("tick");
    const auto& t = run.log.column("t_s");
    const auto& x = run.log.column("x0_m");
    const auto& v = run.log.column("v0_mps");
    const auto& f = run.log.column("f0_n");
    double max_force_n = 0.0;
    for (std::size_t i = 0; i < run.log.rows(); ++i) {
        ASSERT_EQ(tick[i], static_cast<double>(i)) << "row " << i;
        // The time and the position are the doubles nearest their decimals, which the log
        // prints as such (tick 9: 0.009, not 0.009000000000000001), and read back exactly.
        ASSERT_EQ(t[i], static_cast<double>(i) / kRateHz) << "row " << i;
        // x is a whole number of encoder counts, v its backward difference.
        ASSERT_EQ(x[i], std::round(x[i] / kCountM) / std::round(1.0 / kCountM)) << "row " << i;
        if (i > 0) {
            ASSERT_NEAR(v[i], (x[i] - x[i - 1]) / kPeriodS, 1e-9) << "row " << i;
        }
        max_force_n = std::max(max_force_n, std::abs(f[i]));
    }
    EXPECT_NEAR(max_force_n, run.summary.at("max_force_n").get<double>(), 1e-12);
    EXPECT_GT(max_force_n, 1.0);  // the push into the wall is in the log
}

// The preamble names what produced the log: the gains and the verdict the summary has, the
// scene, the device and the config by its SHA-256; the wall clock goes with every row.
TEST(HilLog, ThePreambleNamesTheGainsVerdictSceneAndConfig) {
    DaemonConfig config;
    const CouplingGains gains = size_coupling("encoder");
    config.coupling = coupling_table(gains, "encoder");
    const ScratchDir dir;
    const auto before_s =
        static_cast<double>(std::chrono::duration_cast<std::chrono::microseconds>(
                                std::chrono::system_clock::now().time_since_epoch())
                                .count()) /
        1e6;
    const DaemonRun run = run_hapticd(
        dir,
        {.config_toml = config.toml(), .scene_toml = wall_contact_scene(1e5), .duration_s = 0.5});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const auto after_s =
        static_cast<double>(std::chrono::duration_cast<std::chrono::microseconds>(
                                std::chrono::system_clock::now().time_since_epoch())
                                .count()) /
        1e6;
    EXPECT_EQ(std::stod(run.log.preamble("coupling_stiffness_n_per_m")), gains.stiffness_n_per_m);
    EXPECT_EQ(std::stod(run.log.preamble("coupling_damping_n_s_per_m")), gains.damping_n_s_per_m);
    const std::string verdict = run.summary.at("stability_check").at("verdict").get<std::string>();
    EXPECT_NE(run.log.preamble("stability").find(verdict), std::string::npos)
        << run.log.preamble("stability") << " against " << verdict;
    EXPECT_EQ(run.log.preamble("rate_hz"), "1000");
    EXPECT_EQ(run.log.preamble("scene").rfind(
                  run.summary.at("scene").at("name").get<std::string>() + " (impedance, ", 0),
              0u)
        << run.log.preamble("scene");
    EXPECT_EQ(run.log.preamble("device").rfind("sim", 0), 0u) << run.log.preamble("device");
    EXPECT_EQ(run.log.preamble("version"), run.summary.at("version").get<std::string>());
    // The config by its SHA-256, as sha256sum prints it.
    const CommandResult sum = run_command("sha256sum " + shell_quote(dir.file("cfg.toml")));
    ASSERT_EQ(sum.exit_code, 0) << sum.err;
    EXPECT_EQ(run.log.preamble("config_sha256"), sum.out.substr(0, 64));
    EXPECT_EQ(run.log.preamble("config"), run.summary.at("config_path").get<std::string>());
    const auto& unix_time = run.log.column("unix_time_s");
    EXPECT_GE(unix_time.front(), before_s);
    EXPECT_LE(unix_time.back(), after_s);
    EXPECT_TRUE(std::is_sorted(unix_time.begin(), unix_time.end()));
    const auto& mark = run.log.column("mark");
    EXPECT_TRUE(std::all_of(mark.begin(), mark.end(), [](double m) { return m == 0.0; }));
}

TEST(HilLog, HeaderNamesEveryAxis) {
    DaemonConfig config;
    config.axes = 3;
    config.coupling = coupling_table(size_coupling("encoder"), "encoder");
    config.initial_position = toml_vector({0.0, 0.0, 0.0});
    const ScratchDir dir;
    const DaemonRun run = run_hapticd(dir, {.config_toml = config.toml(),
                                            .scene_toml = "[scene]\nname = \"free\"\naxes = 3\n",
                                            .duration_s = 0.5});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_EQ(run.log_header,
              "tick,t_s,unix_time_s,x0_m,v0_mps,xe0_m,f0_n,x1_m,v1_mps,xe1_m,f1_n,x2_m,v2_mps,"
              "xe2_m,f2_n,status,tick_flags,faults,state,wake_latency_us,compute_us,energy_j,"
              "mark");
    EXPECT_EQ(run.log.rows(), 500u);
}

}  // namespace
}  // namespace hapticd::testing
