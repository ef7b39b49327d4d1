// Checks of user-supplied physical parameters. Each failure throws std::invalid_argument
// whose message names the parameter, the value and the allowed range.
#pragma once

#include <string_view>

#include "hapticd/theory/benchmark.hpp"

namespace hapticd::tune {

void check_positive(std::string_view name, double value, std::string_view unit);
void check_non_negative(std::string_view name, double value, std::string_view unit);
void check_positive_or_infinite(std::string_view name, double value, std::string_view unit);
void check_device(const theory::DeviceModel& device);
void check_rate(double rate_hz);

}  // namespace hapticd::tune
