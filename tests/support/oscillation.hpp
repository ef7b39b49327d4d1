// Judges stability from a trajectory, as an experimenter would from a scope trace: the
// oscillation about the operating point either dies out or grows.
//
// The trace is cut into windows; in each, the straight line through the samples (the slowly
// moving operating point: a push ramp, a creeping set-point) is removed and what is left is
// measured peak to peak. The amplitude is never taken below `floor_m`, a few encoder counts:
// a still handle and one dithering by a count or two (quantisation in a loop with little
// damping to spare) are the same to an encoder, and without the floor the logarithm of a
// perfectly still window would swamp the fit.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace hapticd::testing {

struct OscillationTrend {
    double window_s = 0.0;
    std::vector<double> window_mid_s;  ///< the middle of each window, s from the log's start
    std::vector<double> amplitude_m;   ///< detrended peak-to-peak per window, >= the floor
    double floor_m = 0.0;
    double first_amplitude_m = 0.0;  ///< in the first analysed window
    double last_amplitude_m = 0.0;   ///< in the last window
    double peak_amplitude_m = 0.0;   ///< the largest window
    /// Growth of the amplitude per second, from a least-squares line through log(amplitude)
    /// of every window: > 0 grows, < 0 decays; 0 for a trace that stays at the floor.
    double growth_per_s = 0.0;
    /// The same fit over the rise only: from the last window still near the floor (within
    /// twice it; else the first window) before the first window that reaches half the peak,
    /// to that window. This is the growth of an unstable loop from the noise up to its limit
    /// cycle or saturation, which would flatten a fit over every window. 0 when there is no
    /// rise: the trace never leaves the floor, or its peak is in the first window (a decay).
    double rise_growth_per_s = 0.0;

    double rise_factor() const { return peak_amplitude_m / first_amplitude_m; }
};

namespace detail {

/// Least-squares slope of y against x over [begin, end).
inline double slope(const std::vector<double>& x, const std::vector<double>& y, std::size_t begin,
                    std::size_t end) {
    const double n = static_cast<double>(end - begin);
    if (end <= begin + 1) return 0.0;
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (std::size_t i = begin; i < end; ++i) {
        sx += x[i];
        sy += y[i];
        sxx += x[i] * x[i];
        sxy += x[i] * y[i];
    }
    return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

/// x[begin, begin + count) with its least-squares line removed.
inline std::vector<double> detrended(const std::vector<double>& x, std::size_t begin,
                                     std::size_t count) {
    std::vector<double> index(count);
    std::vector<double> value(x.begin() + static_cast<std::ptrdiff_t>(begin),
                              x.begin() + static_cast<std::ptrdiff_t>(begin + count));
    for (std::size_t i = 0; i < count; ++i) index[i] = static_cast<double>(i);
    const double b = slope(index, value, 0, count);
    double mean_index = 0.0, mean_value = 0.0;
    for (std::size_t i = 0; i < count; ++i) {
        mean_index += index[i] / static_cast<double>(count);
        mean_value += value[i] / static_cast<double>(count);
    }
    for (std::size_t i = 0; i < count; ++i) value[i] -= mean_value + b * (index[i] - mean_index);
    return value;
}

/// Peak-to-peak of x[begin, begin + count) after removing its least-squares line.
inline double detrended_peak_to_peak(const std::vector<double>& x, std::size_t begin,
                                     std::size_t count) {
    const std::vector<double> residual = detrended(x, begin, count);
    if (residual.empty()) return 0.0;
    const auto [lo, hi] = std::minmax_element(residual.begin(), residual.end());
    return *hi - *lo;
}

}  // namespace detail

/// The least-squares growth rate of log(amplitude) over the windows [begin, end) of `trend`.
inline double growth_per_s(const OscillationTrend& trend, std::size_t begin, std::size_t end) {
    end = std::min(end, trend.amplitude_m.size());
    if (end <= begin + 1) return 0.0;
    std::vector<double> log_amplitude(trend.amplitude_m.size());
    for (std::size_t i = 0; i < log_amplitude.size(); ++i) {
        log_amplitude[i] = std::log(trend.amplitude_m[i]);
    }
    return detail::slope(trend.window_mid_s, log_amplitude, begin, end);
}

/// The growth rate of the envelope over its linear phase: least squares through
/// log(amplitude) of the windows from the first on, up to (not including) the first whose
/// amplitude is <= low_m (decayed into the encoder's dither) or >= high_m (grown into a
/// nonlinearity: the wall letting go, saturation). `windows` is how many were fitted.
inline double linear_phase_growth_per_s(const OscillationTrend& trend, double low_m, double high_m,
                                        std::size_t& windows) {
    windows = 0;
    while (windows < trend.amplitude_m.size() && trend.amplitude_m[windows] > low_m &&
           trend.amplitude_m[windows] < high_m) {
        ++windows;
    }
    return growth_per_s(trend, 0, windows);
}

/// Splits x (sampled every `period_s`, from time 0) from sample `start` on into windows of
/// `window` samples and fits the trend of their amplitudes (see the file comment).
inline OscillationTrend oscillation_trend(const std::vector<double>& x, double period_s,
                                          std::size_t start, std::size_t window, double floor_m) {
    OscillationTrend trend;
    trend.window_s = static_cast<double>(window) * period_s;
    trend.floor_m = floor_m;
    for (std::size_t begin = start; window > 1 && begin + window <= x.size(); begin += window) {
        trend.amplitude_m.push_back(
            std::max(detail::detrended_peak_to_peak(x, begin, window), floor_m));
        trend.window_mid_s.push_back(
            (static_cast<double>(begin) + 0.5 * static_cast<double>(window)) * period_s);
    }
    if (trend.amplitude_m.empty()) return trend;
    const std::vector<double>& a = trend.amplitude_m;
    trend.first_amplitude_m = a.front();
    trend.last_amplitude_m = a.back();
    trend.peak_amplitude_m = *std::max_element(a.begin(), a.end());
    trend.growth_per_s = growth_per_s(trend, 0, a.size());
    std::size_t half = 0;
    while (a[half] < 0.5 * trend.peak_amplitude_m) ++half;
    std::size_t rise_begin = 0;
    for (std::size_t i = 0; i < half; ++i) {
        if (a[i] <= 2.0 * floor_m) rise_begin = i;
    }
    if (rise_begin < half) trend.rise_growth_per_s = growth_per_s(trend, rise_begin, half + 1);
    return trend;
}

}  // namespace hapticd::testing
