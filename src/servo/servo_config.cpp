#include "hapticd/servo/servo_config.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace hapticd::servo {

namespace {

using input::invalid;
using input::out_of_range;

std::string field(const char* name) { return std::string("servo config: ") + name; }

}  // namespace

std::int64_t ServoConfig::period_ns() const noexcept {
    return static_cast<std::int64_t>(std::llround(1e9 / rate_hz));
}

bool ServoConfig::is_valid(std::string* error) const {
    if (!kRateRange.contains(rate_hz)) {
        return invalid(error, out_of_range(field("rate_hz"), rate_hz, kRateRange));
    }
    if (axes < 1 || axes > kMaxAxes)
        return invalid(error, out_of_range(field("axes"), axes, "1..3"));
    if (!(counts_per_meter > 0.0) || !std::isfinite(counts_per_meter)) {
        return invalid(error,
                       out_of_range(field("counts_per_meter"), counts_per_meter, "finite and > 0"));
    }
    const double k_c = coupling.stiffness_n_per_m;
    const double b_c = coupling.damping_n_s_per_m;
    if (!(k_c >= 0.0) || !std::isfinite(k_c)) {
        return invalid(error,
                       out_of_range(field("coupling.stiffness_n_per_m"), k_c, "finite and >= 0"));
    }
    if (!(b_c >= 0.0) || !std::isfinite(b_c)) {
        return invalid(error,
                       out_of_range(field("coupling.damping_n_s_per_m"), b_c, "finite and >= 0"));
    }
    const double f_c = coupling.velocity_filter_hz;
    if (!(f_c >= 0.0 && f_c < rate_hz / 2.0)) {  // false for NaN
        return invalid(error, out_of_range(field("coupling.velocity_filter_hz"), f_c,
                                           "0 (none) or > 0 and below rate_hz/2"));
    }
    if (coupling_enabled && coupling.renders_nothing()) {
        return invalid(error, out_of_range(field("coupling.stiffness_n_per_m"), k_c,
                                           "> 0 or damping > 0 (a coupling of zero renders "
                                           "nothing)"));
    }
    if (solver.max_evaluations < 1) {
        return invalid(
            error, out_of_range(field("solver.max_evaluations"), solver.max_evaluations, ">= 1"));
    }
    if (!(solver.force_tolerance_n > 0.0)) {
        return invalid(error, out_of_range(field("solver.force_tolerance_n"),
                                           solver.force_tolerance_n, "> 0"));
    }
    if (overrun.max_consecutive_overruns < 0 ||
        overrun.max_consecutive_overruns > kMaxOverrunBudget) {
        return invalid(error, out_of_range(field("overrun.max_consecutive_overruns"),
                                           overrun.max_consecutive_overruns, "0..1000000"));
    }
    if (overrun.max_missed_periods < 0 || overrun.max_missed_periods > kMaxOverrunBudget) {
        return invalid(error,
                       out_of_range(field("overrun.max_missed_periods"),
                                    static_cast<double>(overrun.max_missed_periods), "0..1000000"));
    }
    if (telemetry_backpressure && !device_paces_loop) {
        return invalid(error, field("telemetry_backpressure") +
                                  " needs a device that paces the loop (lockstep); a "
                                  "wall-clock loop must never wait for its logger");
    }
    std::string part;
    if (!link_recovery.is_valid(&part) || !safety.is_valid(&part) || !realtime.is_valid(&part)) {
        return invalid(error, field(part.c_str()));
    }
    return true;
}

void ServoConfig::validate() const {
    std::string error;
    if (!is_valid(&error)) throw std::invalid_argument(error);
}

}  // namespace hapticd::servo
