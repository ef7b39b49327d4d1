// Judges stability from a trajectory, as an experimenter would from a scope trace: the
// oscillation about the operating point either dies out or grows. The HIL tests judge
// their runs with it, haptic-tune plot-run a user's log, and the evidence maps every point.
//
// The trace is cut into windows; in each, the straight line through the samples (the slowly
// moving operating point: a push ramp, a creeping set-point) is removed and what is left is
// measured peak to peak. The amplitude is never taken below `floor_m`, a few encoder counts:
// a still handle and one dithering by a count or two (quantisation in a loop with little
// damping to spare) are the same to an encoder, and without the floor the logarithm of a
// perfectly still window would swamp the fit.
#pragma once

#include <cstddef>
#include <vector>

namespace hapticd::tune {

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

/// Least-squares slope of y against x over [begin, end); 0 for fewer than two points.
double least_squares_slope(const std::vector<double>& x, const std::vector<double>& y,
                           std::size_t begin, std::size_t end);

/// x[begin, begin + count) with its least-squares line removed.
std::vector<double> detrended(const std::vector<double>& x, std::size_t begin, std::size_t count);

/// Peak-to-peak of x[begin, begin + count) after removing its least-squares line.
double detrended_peak_to_peak(const std::vector<double>& x, std::size_t begin, std::size_t count);

/// The least-squares growth rate of log(amplitude) over the windows [begin, end) of `trend`.
double growth_per_s(const OscillationTrend& trend, std::size_t begin, std::size_t end);

/// The growth rate of the envelope over its linear phase: least squares through
/// log(amplitude) of the windows from the first on, up to (not including) the first whose
/// amplitude is <= low_m (decayed into the encoder's dither) or >= high_m (grown into a
/// nonlinearity: the wall letting go, saturation). `windows` is how many were fitted.
double linear_phase_growth_per_s(const OscillationTrend& trend, double low_m, double high_m,
                                 std::size_t& windows);

/// Splits x (sampled every `period_s`, from time 0) from sample `start` on into windows of
/// `window` samples and fits the trend of their amplitudes (see the file comment).
OscillationTrend oscillation_trend(const std::vector<double>& x, double period_s, std::size_t start,
                                   std::size_t window, double floor_m);

}  // namespace hapticd::tune
