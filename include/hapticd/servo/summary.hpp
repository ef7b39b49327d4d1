// The servo loop's summary: the fields of hapticd's --summary JSON (docs/architecture.md §4.6,
// docs/daemon.md "Summary") plus a few more counters. The daemon serialises it.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hapticd/servo/tick_stats.hpp"

namespace hapticd::servo {

struct WakeLatencySummaryUs {
    double p50 = 0.0, p99 = 0.0, p999 = 0.0, max = 0.0;
};

struct TickComputeSummaryUs {
    double p50 = 0.0, p99 = 0.0, max = 0.0;
};

/// The percentiles of a run's histograms (TickStats::wake_latency, TickStats::compute), as the
/// summary and the live status both report them. No allocation: a walk of the buckets.
WakeLatencySummaryUs wake_latency_summary(const DurationHistogram& wake_latency) noexcept;
TickComputeSummaryUs tick_compute_summary(const DurationHistogram& compute) noexcept;

/// The overrun that latched overrun_budget, beside the budget it broke (ServoConfig::overrun).
struct OverrunBudgetBreach {
    double late_ms = 0.0;             ///< how late the tick woke
    std::int64_t missed_periods = 0;  ///< periods that one overrun missed
    int consecutive_overruns = 0;     ///< overrunning ticks in a row, this one included
    std::int64_t max_missed_periods = 0;
    int max_consecutive_overruns = 0;
};

struct Summary {
    std::uint64_t ticks = 0;
    std::uint64_t overruns = 0;
    std::uint64_t missed_periods = 0;
    double rate_hz = 0.0;
    WakeLatencySummaryUs wake_latency_us{};  ///< empty (zeros) when the device paces the loop
    TickComputeSummaryUs tick_compute_us{};
    double max_force_n = 0.0;
    std::vector<std::string> faults;  ///< every fault latched during the run, by name
    std::uint64_t telemetry_dropped = 0;
    std::uint64_t read_timeouts = 0;
    std::uint64_t solver_not_converged = 0;
    std::uint64_t saturated_ticks = 0;
    std::uint64_t link_recoveries = 0;  ///< link faults cleared once the device came back
    double passivity_energy_j = 0.0;
    std::uint64_t intervals_unknown = 0;  ///< samples with no known time since the last one
    std::optional<OverrunBudgetBreach> overrun_budget;  ///< set when overrun_budget latched
};

/// "woke 55.0 ms late (55 periods missed); the budget is 20 periods in one overrun
/// ([safety] max_missed_periods) and 5 overruns in a row ([safety] max_consecutive_overruns)".
std::string describe(const OverrunBudgetBreach& breach);

struct OverrunBudget;  // servo_config.hpp

/// `faults_seen` is a Fault mask; an overrun_budget fault among them is described against
/// `budget` (Summary::overrun_budget).
Summary make_summary(const TickStats& stats, double rate_hz, std::uint32_t faults_seen,
                     std::uint64_t telemetry_dropped, double passivity_energy_j,
                     const OverrunBudget& budget);

}  // namespace hapticd::servo
