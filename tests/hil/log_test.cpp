// HilLog: the telemetry CSV of a lockstep run is complete and means what
// docs/architecture.md §4.5 says: the header is exactly the public column names, there is one
// row per tick numbered from 0 without a gap (the run is longer than the telemetry ring, so the
// loop must have waited for the writer: lockstep backpressure, §3.5), the summary's counts
// agree, t_s is virtual time, and v is the backward difference of x that the coupling (16)
// uses.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "hapticd_run.hpp"
#include "operators.hpp"
#include "pen_display.hpp"
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

    EXPECT_EQ(
        run.log_header,
        "tick,t_s,x0_m,v0_mps,xe0_m,f0_n,status,flags,faults,state,wake_latency_us,compute_us,"
        "energy_j");
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
        ASSERT_NEAR(t[i], static_cast<double>(i) * kPeriodS, 1e-9) << "row " << i;
        // x is a whole number of encoder counts, v its backward difference.
        ASSERT_NEAR(x[i] / kCountM, std::round(x[i] / kCountM), 1e-6) << "row " << i;
        if (i > 0) {
            ASSERT_NEAR(v[i], (x[i] - x[i - 1]) / kPeriodS, 1e-9) << "row " << i;
        }
        max_force_n = std::max(max_force_n, std::abs(f[i]));
    }
    EXPECT_NEAR(max_force_n, run.summary.at("max_force_n").get<double>(), 1e-12);
    EXPECT_GT(max_force_n, 1.0);  // the push into the wall is in the log
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
              "tick,t_s,x0_m,v0_mps,xe0_m,f0_n,x1_m,v1_mps,xe1_m,f1_n,x2_m,v2_mps,xe2_m,f2_n,"
              "status,flags,faults,state,wake_latency_us,compute_us,energy_j");
    EXPECT_EQ(run.log.rows(), 500u);
}

}  // namespace
}  // namespace hapticd::testing
