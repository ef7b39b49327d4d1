// Evenly stepped values for a test's sweep, first, first + step, ..., last. Each value is
// first + i * step, counted by an integer: a float counter (x += step) gathers one rounding a
// step, so that a long sweep drifts off its grid and may gain or lose its last point.
#pragma once

#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <vector>

namespace hapticd::testing {

/// first, first + step, ..., last; (last - first) / step must be a whole number (to 1e-6).
inline std::vector<double> stepped(double first, double last, double step) {
    const double intervals = (last - first) / step;
    if (!(intervals >= 0.0) || std::abs(intervals - std::round(intervals)) > 1e-6) {
        throw std::invalid_argument("stepped: (last - first) / step is not a whole number");
    }
    const auto count = static_cast<std::size_t>(std::llround(intervals)) + 1;
    std::vector<double> values(count);
    for (std::size_t i = 0; i < count; ++i) values[i] = first + static_cast<double>(i) * step;
    return values;
}

}  // namespace hapticd::testing
