// hapticd's one rule for a percentile (nearest rank): the summary's and the status's
// histograms (tick_stats.hpp), the link diagnosis, the conformance checks, the firmware
// harness's figures and the benchmarks all report the q-quantile of n values as the
// ceil(q n)-th smallest, 1-based, clamped to [1, n].
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace hapticd::servo {

/// The 1-based rank of the q-quantile of n values; 0 when n is 0.
inline std::uint64_t nearest_rank(double q, std::uint64_t n) noexcept {
    if (n == 0) return 0;
    const double rank = std::ceil(std::clamp(q, 0.0, 1.0) * static_cast<double>(n));
    return std::clamp<std::uint64_t>(static_cast<std::uint64_t>(rank), 1, n);
}

/// The q-quantile of `sorted` (ascending); 0 for none.
inline double sorted_quantile(const std::vector<double>& sorted, double q) noexcept {
    if (sorted.empty()) return 0.0;
    return sorted[nearest_rank(q, sorted.size()) - 1];
}

/// The q-quantile of `values` (a sorted copy); 0 for none. It allocates: never on the tick.
inline double quantile(std::vector<double> values, double q) {
    std::sort(values.begin(), values.end());
    return sorted_quantile(values, q);
}

}  // namespace hapticd::servo
