#include "hapticd/tune/input_checks.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace hapticd::tune {
namespace {

[[noreturn]] void reject(std::string_view name, double value, std::string_view unit,
                         std::string_view allowed) {
    std::ostringstream message;
    message << name << " = " << value << (unit.empty() ? "" : " ") << unit << " is out of range: "
            << "allowed " << allowed;
    throw std::invalid_argument(message.str());
}

}  // namespace

void check_positive(std::string_view name, double value, std::string_view unit) {
    if (!(std::isfinite(value) && value > 0.0)) reject(name, value, unit, "finite and > 0");
}

void check_non_negative(std::string_view name, double value, std::string_view unit) {
    if (!(std::isfinite(value) && value >= 0.0)) reject(name, value, unit, "finite and >= 0");
}

void check_positive_or_infinite(std::string_view name, double value, std::string_view unit) {
    if (!(value > 0.0)) reject(name, value, unit, "> 0 (inf for none)");
}

void check_device(const theory::DeviceModel& device) {
    check_positive("device mass m", device.mass_kg, "kg");
    check_positive("device damping b", device.damping_n_s_per_m, "N s/m");
}

void check_rate(double rate_hz) { check_positive("servo rate", rate_hz, "Hz"); }

}  // namespace hapticd::tune
