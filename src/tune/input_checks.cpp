#include "hapticd/tune/input_checks.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "hapticd/input/range.hpp"

namespace hapticd::tune {
void check_positive(std::string_view name, double value, std::string_view unit) {
    if (!(std::isfinite(value) && value > 0.0))
        input::reject_out_of_range(name, input::format_quantity(value, unit), "finite and > 0");
}

void check_non_negative(std::string_view name, double value, std::string_view unit) {
    if (!(std::isfinite(value) && value >= 0.0))
        input::reject_out_of_range(name, input::format_quantity(value, unit), "finite and >= 0");
}

void check_positive_or_infinite(std::string_view name, double value, std::string_view unit) {
    if (!(value > 0.0))
        input::reject_out_of_range(name, input::format_quantity(value, unit), "> 0 (inf for none)");
}

void check_in_range(std::string_view name, double value, double lo, double hi,
                    std::string_view unit) {
    if (!(value >= lo && value <= hi)) {  // false for NaN
        input::reject_out_of_range(name, input::format_quantity(value, unit),
                                   input::format_number(lo) + " to " + input::format_number(hi));
    }
}

void check_device(const theory::DeviceModel& device) {
    check_in_range("device mass m", device.mass_kg, kMinDeviceMassKg, kMaxDeviceMassKg, "kg");
    check_in_range("device damping b", device.damping_n_s_per_m, kMinDeviceDamping,
                   kMaxDeviceDamping, "N s/m");
}

void check_rate(double rate_hz) {
    if (!servo::kRateRange.contains(rate_hz)) {
        input::reject_out_of_range("servo rate", rate_hz, servo::kRateRange);
    }
}

void check_coupling_gains(const theory::SpringDamperCoupling& coupling) {
    check_in_range("coupling stiffness k_c", coupling.stiffness_n_per_m, 0.0, kMaxCouplingStiffness,
                   "N/m");
    check_in_range("coupling damping b_c", coupling.damping_n_s_per_m, 0.0, kMaxCouplingDamping,
                   "N s/m");
}

void check_delay_periods(double delay_periods) {
    if (!(std::isfinite(delay_periods) && delay_periods >= 0.0 &&
          delay_periods < kMaxDelayPeriods)) {
        input::reject_out_of_range(
            "loop delay", input::format_quantity(delay_periods, "periods"),
            "0 <= delay < " + input::format_quantity(kMaxDelayPeriods, "periods"));
    }
}

void check_velocity_filter(double cutoff_hz, double rate_hz) {
    if (cutoff_hz == 0.0 || (cutoff_hz >= kMinVelocityFilterHz && cutoff_hz < rate_hz / 2.0)) {
        return;
    }
    input::reject_out_of_range(
        "velocity filter cutoff f_c", input::format_quantity(cutoff_hz, "Hz"),
        "0 (no filter) or " + input::format_quantity(kMinVelocityFilterHz, "Hz") + " <= f_c < " +
            input::format_quantity(rate_hz / 2.0, "Hz") + " (below Nyquist, rate/2 at " +
            input::format_quantity(rate_hz, "Hz") + ")");
}

}  // namespace hapticd::tune
