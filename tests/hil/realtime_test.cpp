// HilRealtime: one short run of the daemon's real-time loop (not lockstep): the servo
// thread sleeps to absolute deadlines (clock_nanosleep, TIMER_ABSTIME) at 1 kHz and the sim
// plugin's physics follows CLOCK_MONOTONIC. realtime = "warn": SCHED_FIFO, mlockall and the
// CPU latency request are asked for, and a refusal is only a warning, so the test also runs
// where they are not granted. The bounds are loose on purpose (this is a shared VM, not an
// RT kernel): they catch a loop that does not pace, drifts, busy-waits badly or loses
// telemetry, not a few hundred microseconds of jitter. Run serially (ctest RUN_SERIAL).
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <string>

#include "hapticd_run.hpp"
#include "operators.hpp"
#include "pen_display.hpp"
#include "tuned_gains.hpp"
#include "wall_contact.hpp"

namespace hapticd::testing {
namespace {

constexpr double kDurationS = 2.5;

TEST(HilRealtime, PacesAt1kHzWithACompleteLog) {
    DaemonConfig config;
    config.coupling = coupling_table(size_coupling("encoder"), "encoder");
    config.sim_clock = "realtime";
    config.realtime = "warn";
    config.initial_position = "-0.001";
    // Pressed into the wall from 0.8 s on, so that the ticks render a contact.
    config.humans = human_table(stiff_grasp(push_toml(0.005, 0.8, 0.3, 100.0)));
    const ScratchDir dir;
    const DaemonRun run = run_hapticd(dir, {.config_toml = config.toml(),
                                            .scene_toml = wall_contact_scene(1e5),
                                            .duration_s = kDurationS,
                                            .lockstep = false});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const nlohmann::json& s = run.summary;
    const double ticks = s.at("ticks").get<double>();
    std::cout << "[hil] real time: " << ticks << " ticks in " << s.at("run_time_s") << " s, "
              << s.at("overruns") << " overruns (" << s.at("missed_periods")
              << " periods missed); wake latency us " << s.at("wake_latency_us").dump()
              << "; tick compute us " << s.at("tick_compute_us").dump() << "; realtime "
              << s.at("realtime").dump() << "\n";

    EXPECT_EQ(s.at("exit"), "duration");
    EXPECT_EQ(s.at("lockstep"), false);
    EXPECT_EQ(s.at("rate_hz").get<double>(), kRateHz);
    // Every period is either ticked or counted as missed (skip ahead, never burst).
    EXPECT_NEAR(ticks + s.at("missed_periods").get<double>(), kDurationS * kRateHz,
                0.03 * kDurationS * kRateHz);
    EXPECT_LT(s.at("wake_latency_us").at("p50").get<double>(), 1000.0);
    EXPECT_GT(s.at("wake_latency_us").at("max").get<double>(), 0.0);  // it really slept
    EXPECT_LT(s.at("tick_compute_us").at("p50").get<double>(), 50.0);
    EXPECT_EQ(fault_list(run), "");
    EXPECT_EQ(s.at("telemetry_dropped").get<double>(), 0.0);
    EXPECT_EQ(s.at("telemetry_records").get<double>(), ticks);
    EXPECT_EQ(s.at("realtime").at("mode"), "warn");
    EXPECT_GT(s.at("max_force_n").get<double>(), 1.0);  // the contact was rendered

    // The log: one row per tick, numbered 0, 1, 2, ... with no gap, and scheduled times
    // that advance by one period per tick plus any missed periods.
    ASSERT_EQ(static_cast<double>(run.log.rows()), ticks);
    const auto& tick = run.log.column("tick");
    const auto& t = run.log.column("t_s");
    std::size_t gaps = 0;
    for (std::size_t i = 0; i < run.log.rows(); ++i) {
        ASSERT_EQ(tick[i], static_cast<double>(i)) << "row " << i;
        if (i > 0 && std::abs(t[i] - t[i - 1] - kPeriodS) > 1e-9) ++gaps;
    }
    EXPECT_LE(gaps, s.at("overruns").get<std::size_t>());
}

}  // namespace
}  // namespace hapticd::testing
