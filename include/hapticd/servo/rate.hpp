// The servo rate ([servo] rate_hz, T = 1/rate_hz): its one range and its one default. Plain
// data, so that every layer that takes a rate (the config, the device's DeviceConfig, the
// tune layer's requests, haptic-tune's --rate) holds it to the servo's own range and starts
// from the servo's own default.
#pragma once

#include "hapticd/input/range.hpp"

namespace hapticd::servo {

/// 10 ms to 50 us periods.
inline constexpr input::Range kRateRange{.lo = 100.0, .hi = 20000.0, .unit = "Hz"};
/// 1 kHz.
inline constexpr double kDefaultRateHz = 1000.0;

}  // namespace hapticd::servo
