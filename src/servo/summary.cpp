#include "hapticd/servo/summary.hpp"

#include <iomanip>
#include <sstream>

#include "hapticd/servo/faults.hpp"
#include "hapticd/servo/servo_config.hpp"

namespace hapticd::servo {

WakeLatencySummaryUs wake_latency_summary(const DurationHistogram& wake_latency) noexcept {
    return {wake_latency.quantile_us(0.50), wake_latency.quantile_us(0.99),
            wake_latency.quantile_us(0.999), wake_latency.max_us()};
}

TickComputeSummaryUs tick_compute_summary(const DurationHistogram& compute) noexcept {
    return {compute.quantile_us(0.50), compute.quantile_us(0.99), compute.max_us()};
}

Summary make_summary(const TickStats& stats, double rate_hz, std::uint32_t faults_seen,
                     std::uint64_t telemetry_dropped, double passivity_energy_j,
                     const OverrunBudget& budget) {
    Summary summary;
    summary.ticks = stats.ticks;
    summary.overruns = stats.overruns;
    summary.missed_periods = stats.missed_periods;
    summary.rate_hz = rate_hz;
    summary.wake_latency_us = wake_latency_summary(stats.wake_latency);
    summary.tick_compute_us = tick_compute_summary(stats.compute);
    summary.max_force_n = stats.max_force_n;
    for_each_fault(faults_seen, [&](std::string_view name) { summary.faults.emplace_back(name); });
    summary.telemetry_dropped = telemetry_dropped;
    summary.read_timeouts = stats.read_timeouts;
    summary.solver_not_converged = stats.solver_not_converged;
    summary.saturated_ticks = stats.saturated_ticks;
    summary.link_recoveries = stats.link_recoveries;
    summary.passivity_energy_j = passivity_energy_j;
    summary.intervals_unknown = stats.intervals_unknown;
    if ((faults_seen & kFaultOverrunBudget) != 0u) {
        summary.overrun_budget =
            OverrunBudgetBreach{.late_ms = static_cast<double>(stats.budget_overrun_late_ns) * 1e-6,
                                .missed_periods = stats.budget_overrun_missed_periods,
                                .consecutive_overruns = stats.budget_overrun_consecutive,
                                .max_missed_periods = budget.max_missed_periods,
                                .max_consecutive_overruns = budget.max_consecutive_overruns};
    }
    return summary;
}

std::string describe(const OverrunBudgetBreach& b) {
    std::ostringstream out;
    out << std::fixed << std::setprecision(1) << "woke " << b.late_ms << " ms late ("
        << b.missed_periods << (b.missed_periods == 1 ? " period" : " periods") << " missed, "
        << b.consecutive_overruns << (b.consecutive_overruns == 1 ? " overrun" : " overruns")
        << " in a row); the budget is " << b.max_missed_periods
        << " periods in one overrun ([safety] max_missed_periods) and "
        << b.max_consecutive_overruns << " overruns in a row ([safety] max_consecutive_overruns)";
    return out.str();
}

}  // namespace hapticd::servo
