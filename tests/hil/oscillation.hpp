// Judges stability from a trajectory, as an experimenter would from a scope trace: the
// oscillation about the final operating point either dies out or grows.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace hapticd::testing {

struct OscillationTrend {
    double first_amplitude_m = 0.0;  ///< peak-to-peak in the first analysed window
    double last_amplitude_m = 0.0;   ///< peak-to-peak in the last window
    /// Growth of the peak-to-peak amplitude per second, from a least-squares line through
    /// log(amplitude) of every window: > 0 grows, < 0 decays.
    double growth_per_s = 0.0;
};

/// Splits x (sampled every `period_s`) from `start` on into windows of `window` samples
/// and fits the trend of their peak-to-peak amplitudes.
inline OscillationTrend oscillation_trend(const std::vector<double>& x, double period_s,
                                          std::size_t start, std::size_t window) {
    std::vector<double> t;
    std::vector<double> log_amplitude;
    OscillationTrend trend;
    for (std::size_t begin = start; begin + window <= x.size(); begin += window) {
        const auto [lo, hi] = std::minmax_element(x.begin() + begin, x.begin() + begin + window);
        const double amplitude = std::max(*hi - *lo, 1e-12);
        if (t.empty()) trend.first_amplitude_m = amplitude;
        trend.last_amplitude_m = amplitude;
        t.push_back((begin + window / 2) * period_s);
        log_amplitude.push_back(std::log(amplitude));
    }
    const double n = static_cast<double>(t.size());
    if (n < 2) return trend;
    double st = 0, sy = 0, stt = 0, sty = 0;
    for (std::size_t i = 0; i < t.size(); ++i) {
        st += t[i];
        sy += log_amplitude[i];
        stt += t[i] * t[i];
        sty += t[i] * log_amplitude[i];
    }
    trend.growth_per_s = (n * sty - st * sy) / (n * stt - st * st);
    return trend;
}

}  // namespace hapticd::testing
