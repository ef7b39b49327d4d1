#include "hapticd/tune/oscillation.hpp"

#include <algorithm>
#include <cmath>

namespace hapticd::tune {

double least_squares_slope(const std::vector<double>& x, const std::vector<double>& y,
                           std::size_t begin, std::size_t end) {
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

std::vector<double> detrended(const std::vector<double>& x, std::size_t begin, std::size_t count) {
    std::vector<double> index(count);
    std::vector<double> value(x.begin() + static_cast<std::ptrdiff_t>(begin),
                              x.begin() + static_cast<std::ptrdiff_t>(begin + count));
    for (std::size_t i = 0; i < count; ++i) index[i] = static_cast<double>(i);
    const double b = least_squares_slope(index, value, 0, count);
    double mean_index = 0.0, mean_value = 0.0;
    for (std::size_t i = 0; i < count; ++i) {
        mean_index += index[i] / static_cast<double>(count);
        mean_value += value[i] / static_cast<double>(count);
    }
    for (std::size_t i = 0; i < count; ++i) value[i] -= mean_value + b * (index[i] - mean_index);
    return value;
}

double detrended_peak_to_peak(const std::vector<double>& x, std::size_t begin, std::size_t count) {
    const std::vector<double> residual = detrended(x, begin, count);
    if (residual.empty()) return 0.0;
    const auto [lo, hi] = std::minmax_element(residual.begin(), residual.end());
    return *hi - *lo;
}

double growth_per_s(const OscillationTrend& trend, std::size_t begin, std::size_t end) {
    end = std::min(end, trend.amplitude_m.size());
    if (end <= begin + 1) return 0.0;
    std::vector<double> log_amplitude(trend.amplitude_m.size());
    for (std::size_t i = 0; i < log_amplitude.size(); ++i) {
        log_amplitude[i] = std::log(trend.amplitude_m[i]);
    }
    return least_squares_slope(trend.window_mid_s, log_amplitude, begin, end);
}

double linear_phase_growth_per_s(const OscillationTrend& trend, double low_m, double high_m,
                                 std::size_t& windows) {
    windows = 0;
    while (windows < trend.amplitude_m.size() && trend.amplitude_m[windows] > low_m &&
           trend.amplitude_m[windows] < high_m) {
        ++windows;
    }
    return growth_per_s(trend, 0, windows);
}

OscillationTrend oscillation_trend(const std::vector<double>& x, double period_s, std::size_t start,
                                   std::size_t window, double floor_m) {
    OscillationTrend trend;
    trend.window_s = static_cast<double>(window) * period_s;
    trend.floor_m = floor_m;
    for (std::size_t begin = start; window > 1 && begin + window <= x.size(); begin += window) {
        trend.amplitude_m.push_back(std::max(detrended_peak_to_peak(x, begin, window), floor_m));
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

}  // namespace hapticd::tune
