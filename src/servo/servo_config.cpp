#include "hapticd/servo/servo_config.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace hapticd::servo {

namespace {

[[noreturn]] void reject(const char* field, double value, const char* expected) {
    std::ostringstream message;
    message << "servo config: " << field << " must be " << expected << ", got " << value;
    throw std::invalid_argument(message.str());
}

}  // namespace

std::int64_t ServoConfig::period_ns() const noexcept {
    return static_cast<std::int64_t>(std::llround(1e9 / rate_hz));
}

void ServoConfig::validate() const {
    if (!(rate_hz >= 1.0 && rate_hz <= 100'000.0)) reject("rate_hz", rate_hz, "in 1..100000 Hz");
    if (axes < 1 || axes > kMaxAxes) reject("axes", axes, "in 1..3");
    if (!(counts_per_meter > 0.0) || !std::isfinite(counts_per_meter)) {
        reject("counts_per_meter", counts_per_meter, "a finite number > 0");
    }
    const double k_c = coupling.stiffness_n_per_m;
    const double b_c = coupling.damping_n_s_per_m;
    if (!(k_c >= 0.0) || !std::isfinite(k_c))
        reject("coupling.stiffness_n_per_m", k_c, "finite, >= 0");
    if (!(b_c >= 0.0) || !std::isfinite(b_c))
        reject("coupling.damping_n_s_per_m", b_c, "finite, >= 0");
    const double f_c = coupling.velocity_filter_hz;
    if (!(f_c >= 0.0 && f_c < rate_hz / 2.0)) {  // false for NaN
        reject("coupling.velocity_filter_hz", f_c, "0 (none) or > 0 and below rate_hz/2");
    }
    if (coupling_enabled && k_c == 0.0 && b_c == 0.0) {
        reject("coupling.stiffness_n_per_m", k_c,
               "> 0 or damping > 0 (a coupling of zero renders nothing)");
    }
    if (solver.max_evaluations < 1)
        reject("solver.max_evaluations", solver.max_evaluations, ">= 1");
    if (!(solver.force_tolerance_n > 0.0)) {
        reject("solver.force_tolerance_n", solver.force_tolerance_n, "> 0");
    }
    if (overrun.max_consecutive_overruns < 0) {
        reject("overrun.max_consecutive_overruns", overrun.max_consecutive_overruns, ">= 0");
    }
    if (overrun.max_missed_periods < 0) {
        reject("overrun.max_missed_periods", static_cast<double>(overrun.max_missed_periods),
               ">= 0");
    }
    if (telemetry_backpressure && !device_paces_loop) {
        throw std::invalid_argument(
            "servo config: telemetry_backpressure needs a device that paces the loop "
            "(lockstep); a wall-clock loop must never wait for its logger");
    }
    link_recovery.validate();
    // The safety limits and the realtime request validate themselves where they are used
    // (SafetySupervisor's constructor, RealtimeSession::apply).
}

}  // namespace hapticd::servo
