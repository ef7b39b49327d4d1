// Internal to identification.cpp: one axis of a telemetry log made ready for the fit, with
// every check that can refuse a log before fitting (time, status columns, saturation,
// excitation), the shooting segments and the equation-error starting guess.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "hapticd/tune/identification.hpp"
#include "hapticd/tune/identification_model.hpp"

namespace hapticd::tune::detail {

/// Throws IdentificationRefused(reason, "cannot identify: " + why).
[[noreturn]] void refuse(RefusalReason reason, const std::string& why);
/// A number for messages, with `digits` significant digits.
std::string format(double value, int digits = 4);
/// "12.3 %" for 0.123.
std::string percent(double fraction);
/// The upper median (the middle of an odd count); 0 for none.
double median(std::vector<double> values);

/// The rows [start, start + length) of the log, simulated from their own initial state.
struct SegmentRange {
    std::size_t start = 0;
    std::size_t length = 0;
};

/// One axis of the log after the checks.
struct AxisData {
    std::string x_name;  ///< "x0_m"
    std::string f_name;  ///< "f0_n"
    const std::vector<double>* t = nullptr;
    const std::vector<double>* x = nullptr;  ///< logged position, m
    const std::vector<double>* f = nullptr;  ///< logged force command, N
    std::vector<char> masked;                ///< the row's position is not a fresh sample
    std::vector<char> gap_after;             ///< more than one period from this row to the next
    std::size_t gaps = 0;                    ///< periods missing in all
    std::size_t masked_count = 0;
    double period_s = 0.0;
    double duration_s = 0.0;
    double resolution_m = 0.0;  ///< 0: the positions are not quantised
    bool resolution_estimated = true;
    HoldDelay delay;  ///< IdentificationOptions::delay_s at the log's period
};

/// Columns, time, status columns, saturation, resolution and excitation of `axis`; throws
/// IdentificationRefused naming the reason (and the file, line and column where one row is
/// to blame). The log must outlive the result (it points into it).
AxisData prepare_axis(const TelemetryLog& log, int axis, const IdentificationOptions& options);

/// Fewest samples in a shooting segment; shorter runs between gaps are not used.
inline constexpr std::size_t kMinSegmentSamples = 10;

/// The runs between gaps, each cut into segments of about `target` samples; segments with
/// fewer than three fresh samples are dropped. A run's first `delay.history()` rows start no
/// segment: the forces acting in them were commanded before the run (in a gap, or before the
/// log). Refuses a log left with none.
std::vector<SegmentRange> make_segments(const AxisData& data, std::size_t target);

struct StartingGuess {
    double mass_kg = 0.1;
    double damping_n_s_per_m = 1.0;
    double coulomb_n = 0.0;
    double offset_n = 0.0;
};
/// Least squares of  F = m a + b v + F_c sign(v) - F_0  on quadratic Savitzky-Golay estimates
/// of v and a (the force smoothed alike) over windows that hold no gap and no excluded sample.
/// Non-physical values (m <= 0, b <= 0) are replaced by harmless ones: it is a start only.
StartingGuess starting_guess(const AxisData& data, const std::vector<SegmentRange>& segments);

/// Half-width, in samples, of the starting guess' smoothing window (10 ms, at least 3).
int smoothing_half_width(const AxisData& data);

/// Least-squares slope of x over the first samples of a segment (its initial velocity),
/// never exactly 0 (which would start the segment "at rest").
double initial_velocity(const AxisData& data, const SegmentRange& segment);
/// The first fresh position of a segment.
double initial_position(const AxisData& data, const SegmentRange& segment);

/// Fraction of the force's variance above `corner_hz` (one-pole high-pass), for messages.
double force_power_above(const AxisData& data, double corner_hz);
/// RMS of the force about its mean, N.
double force_rms(const AxisData& data);

}  // namespace hapticd::tune::detail
