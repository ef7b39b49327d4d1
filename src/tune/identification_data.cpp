#include "identification_data.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <sstream>
#include <utility>

#include "hapticd/input/range.hpp"
#include "hapticd/servo/telemetry.hpp"
#include "hapticd/tune/input_checks.hpp"

namespace hapticd::tune::detail {
namespace {

// A step of t_s may differ from a whole number of periods by this fraction of a period.
constexpr double kTimeTolerance = 0.05;
// Half-width of the Savitzky-Golay window of the starting guess, s.
constexpr double kSmoothingHalfWidthS = 0.01;
// The handle must move at least this many encoder steps.
constexpr double kMinMotionSteps = 20.0;

std::uint32_t bit_mask(const TelemetryLog& log, const std::vector<double>& column, std::size_t row,
                       std::string_view name) {
    const double value = column[row];
    if (!(value >= 0.0 && value <= 4294967295.0 && std::floor(value) == value)) {
        refuse(RefusalReason::missing_column,
               log.where(row, name) + " = " + format(value, 17) +
                   " is not a bit mask (a whole number in 0 .. 2^32-1): is this the daemon's " +
                   std::string(name) + " column?");
    }
    return static_cast<std::uint32_t>(value);
}

/// Time: increasing in whole periods (gaps allowed: segments break there).
void check_time(const TelemetryLog& log, AxisData& data) {
    const std::vector<double>& t = *data.t;
    const std::size_t n = t.size();
    std::vector<double> steps(n - 1);
    for (std::size_t i = 0; i + 1 < n; ++i) {
        steps[i] = t[i + 1] - t[i];
        if (!(steps[i] > 0.0)) {
            refuse(RefusalReason::non_uniform_time,
                   log.where(i + 1, "t_s") + ": time does not increase (t_s = " +
                       format(t[i + 1], 10) + " s after " + format(t[i], 10) + " s)");
        }
    }
    const double median_step = median(std::move(steps));  // reordered: not read again
    data.gap_after.assign(n, 0);
    double total_periods = 0.0;
    for (std::size_t i = 0; i + 1 < n; ++i) {
        const double step = t[i + 1] - t[i];
        const double periods = step / median_step;
        const double whole = std::round(periods);
        if (std::abs(periods - whole) > kTimeTolerance) {
            refuse(RefusalReason::non_uniform_time,
                   log.where(i + 1, "t_s") + ": t_s steps by " + format(step, 6) +
                       " s, not a whole number of periods of the log's median step " +
                       format(median_step, 6) + " s (tolerance " + percent(kTimeTolerance) +
                       "); the model replays each row's force through a hold of one period");
        }
        if (whole > 1.0) {
            data.gap_after[i] = 1;
            data.gaps += static_cast<std::size_t>(whole) - 1;
        }
        total_periods += whole;
    }
    // The period over the whole log: free of the rounding in any one step.
    data.period_s = (t[n - 1] - t[0]) / total_periods;
    data.duration_s = t[n - 1] - t[0];
}

/// Status columns: faults refuse the log; stale or dropped samples are excluded.
void check_status(const TelemetryLog& log, AxisData& data, const IdentificationOptions& options) {
    const std::size_t n = log.rows();
    data.masked.assign(n, 0);
    constexpr std::uint32_t kBrokenStatus =
        servo::kStatusDisconnected | servo::kStatusJump | servo::kStatusDeviceFault;
    constexpr std::uint32_t kNotFresh = servo::kStatusStale | servo::kStatusDropped;
    if (const std::vector<double>* faults = log.column("faults")) {
        for (std::size_t i = 0; i < n; ++i) {
            if (const std::uint32_t mask = bit_mask(log, *faults, i, "faults"); mask != 0) {
                refuse(RefusalReason::faults,
                       log.where(i, "faults") + ": the daemon latched a fault (mask " +
                           std::to_string(mask) +
                           ") and zeroed the force: this is not a clean excitation run; "
                           "trim the log before the fault or record it again");
            }
        }
    }
    if (const std::vector<double>* status = log.column("status")) {
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint32_t mask = bit_mask(log, *status, i, "status");
            if (mask & kBrokenStatus) {
                refuse(RefusalReason::faults,
                       log.where(i, "status") + ": device status " + std::to_string(mask) +
                           " (disconnected, encoder jump or device fault): the positions "
                           "cannot be trusted; trim the log or record it again");
            }
            if (mask & kNotFresh) data.masked[i] = 1;
        }
    }
    std::size_t saturated = 0;
    std::size_t first_saturated = n;
    if (const std::vector<double>* flags = log.column("tick_flags")) {
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint32_t mask = bit_mask(log, *flags, i, "tick_flags");
            if (mask & servo::kFlagNoSample) data.masked[i] = 1;
            if (mask & servo::kFlagSaturated) {
                ++saturated;
                first_saturated = std::min(first_saturated, i);
            }
        }
    }
    const double saturated_fraction = static_cast<double>(saturated) / static_cast<double>(n);
    if (saturated_fraction > options.max_saturated_fraction) {
        refuse(RefusalReason::saturated,
               "the daemon's force saturation acted on " + std::to_string(saturated) + " rows (" +
                   percent(saturated_fraction) + ", first at " + log.where(first_saturated) +
                   "; allowed " + percent(options.max_saturated_fraction) +
                   "): the excitation was clipped; lower its amplitude");
    }
    data.masked_count =
        static_cast<std::size_t>(std::count(data.masked.begin(), data.masked.end(), 1));
    const double masked_fraction = static_cast<double>(data.masked_count) / static_cast<double>(n);
    if (masked_fraction > options.max_masked_fraction) {
        refuse(RefusalReason::faults,
               std::to_string(data.masked_count) + " rows (" + percent(masked_fraction) +
                   ") hold no fresh encoder sample (stale, dropped, no sample; allowed " +
                   percent(options.max_masked_fraction) +
                   "): fix the link first (haptic-tune diag)");
    }
}

/// Force at its limit: by the given limit, or a continuous signal with flat tops.
void check_saturation(const TelemetryLog& log, const AxisData& data,
                      const IdentificationOptions& options) {
    const std::vector<double>& f = *data.f;
    const std::size_t n = f.size();
    const auto fraction_at = [&](double limit, std::size_t* first) {
        std::size_t count = 0;
        *first = n;
        for (std::size_t i = 0; i < n; ++i) {
            if (std::abs(f[i]) >= limit * (1.0 - 1e-9)) {
                ++count;
                *first = std::min(*first, i);
            }
        }
        return static_cast<double>(count) / static_cast<double>(n);
    };
    std::size_t first = n;
    if (options.force_limit_n) {
        const double fraction = fraction_at(*options.force_limit_n, &first);
        if (fraction > options.max_saturated_fraction) {
            refuse(RefusalReason::saturated,
                   percent(fraction) + " of the samples of " + data.f_name +
                       " are at the force limit " + format(*options.force_limit_n) +
                       " N (first at " + log.where(first) + "; allowed " +
                       percent(options.max_saturated_fraction) +
                       "): the excitation was clipped; lower its amplitude");
        }
    }
    // Without a known limit: a signal that takes many values but sits at ±max|f| for more
    // than the allowed fraction has been clipped. A two- or three-level signal (PRBS) sits
    // at its peak by design and is not judged this way.
    std::vector<double> magnitudes;
    magnitudes.reserve(n);
    for (double value : f) magnitudes.push_back(std::abs(value));
    std::sort(magnitudes.begin(), magnitudes.end());
    const double peak = magnitudes.back();
    if (peak == 0.0) return;
    const auto levels = std::unique(magnitudes.begin(), magnitudes.end()) - magnitudes.begin();
    const double fraction = fraction_at(peak, &first);
    if (levels > 3 && fraction > options.max_saturated_fraction) {
        refuse(RefusalReason::saturated,
               percent(fraction) + " of the samples of " + data.f_name + " sit at ±" +
                   format(peak) +
                   " N, the largest force in the log, while the rest vary (first at " +
                   log.where(first) + "; allowed " + percent(options.max_saturated_fraction) +
                   "): the excitation looks clipped by a force limit; lower its amplitude, or "
                   "give the device's limit with --force-limit if this is by design");
    }
}

/// The encoder step: the smallest difference between distinct logged positions, if the
/// positions lie on that lattice (else 0: not quantised).
double estimate_resolution(const AxisData& data) {
    std::vector<double> positions;
    positions.reserve(data.x->size());
    for (std::size_t i = 0; i < data.x->size(); ++i) {
        if (!data.masked[i]) positions.push_back((*data.x)[i]);
    }
    std::sort(positions.begin(), positions.end());
    positions.erase(std::unique(positions.begin(), positions.end()), positions.end());
    if (positions.size() < 3) return 0.0;
    const double span = positions.back() - positions.front();
    double step = std::numeric_limits<double>::infinity();
    for (std::size_t i = 1; i < positions.size(); ++i) {
        const double d = positions[i] - positions[i - 1];
        if (d > 1e-12 * span) step = std::min(step, d);
    }
    if (!std::isfinite(step)) return 0.0;
    std::size_t on_lattice = 0;
    for (std::size_t i = 1; i < positions.size(); ++i) {
        const double ratio = (positions[i] - positions[i - 1]) / step;
        if (std::abs(ratio - std::round(ratio)) < 1e-3) ++on_lattice;
    }
    if (on_lattice < (positions.size() - 1) * 9 / 10) return 0.0;
    return span / std::round(span / step);  // over the whole span: free of rounding in one step
}

void check_excitation(const AxisData& data) {
    const std::vector<double>& f = *data.f;
    const auto [f_min, f_max] = std::minmax_element(f.begin(), f.end());
    if (*f_min == *f_max) {
        refuse(RefusalReason::too_little_excitation,
               data.f_name + " is " + format(*f_min) +
                   " N on every row: no force excites the device (record a run with "
                   "hapticd --identify)");
    }
    double x_min = std::numeric_limits<double>::infinity();
    double x_max = -x_min;
    for (std::size_t i = 0; i < data.x->size(); ++i) {
        if (data.masked[i]) continue;
        x_min = std::min(x_min, (*data.x)[i]);
        x_max = std::max(x_max, (*data.x)[i]);
    }
    const double motion = x_max - x_min;
    const double q = data.resolution_m;
    if (!(motion > 0.0) || (q > 0.0 && motion < kMinMotionSteps * q)) {
        refuse(RefusalReason::too_little_excitation,
               "the handle barely moved: " + data.x_name + " spans " + format(motion) + " m" +
                   (q > 0.0 ? " (" + format(motion / q) + " encoder steps of " + format(q) +
                                  " m; needs at least " + format(kMinMotionSteps) + ")"
                            : std::string()) +
                   "; raise the excitation, or check that the device was enabled");
    }
}

}  // namespace

void refuse(RefusalReason reason, const std::string& why) {
    throw IdentificationRefused(reason, "cannot identify: " + why);
}

std::string format(double value, int digits) {
    std::ostringstream text;
    text.precision(digits);
    text << value;
    return text.str();
}

std::string percent(double fraction) { return format(100.0 * fraction, 3) + " %"; }

double median(std::vector<double> values) {
    if (values.empty()) return 0.0;
    const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), mid, values.end());
    return *mid;
}

AxisData prepare_axis(const TelemetryLog& log, int axis, const IdentificationOptions& options) {
    AxisData data;
    data.x_name = "x" + std::to_string(axis) + "_m";
    data.f_name = "f" + std::to_string(axis) + "_n";
    data.t = log.column("t_s");
    data.x = log.column(data.x_name);
    data.f = log.column(data.f_name);
    if (axis < 0 || data.t == nullptr || data.x == nullptr || data.f == nullptr) {
        std::string columns;
        for (const std::string& name : log.columns) columns += (columns.empty() ? "" : ", ") + name;
        refuse(RefusalReason::missing_column,
               "no " + (data.t == nullptr ? std::string("t_s") : data.x_name + "/" + data.f_name) +
                   " for axis " + std::to_string(axis) + " (the log has " +
                   servo::axes_text(log.axes) + "; its columns: " + columns + ")");
    }
    const std::size_t n = log.rows();
    if (n < 3) {
        refuse(RefusalReason::too_short, "the log has " + std::to_string(n) +
                                             " rows; identification needs at least " +
                                             format(options.min_duration_s) + " s of samples");
    }
    check_time(log, data);
    if (data.duration_s < options.min_duration_s) {
        refuse(RefusalReason::too_short,
               "the log covers " + format(data.duration_s) + " s (" + std::to_string(n) +
                   " samples at " + format(1.0 / data.period_s) +
                   " Hz); identification needs at least " + format(options.min_duration_s) + " s");
    }
    if (!(options.delay_s < kMaxDelayPeriods * data.period_s)) {
        input::reject_out_of_range("identification option delay_s", options.delay_s,
                                   "< " + format(kMaxDelayPeriods * data.period_s) + " s (" +
                                       format(kMaxDelayPeriods) + " periods at the log's " +
                                       format(1.0 / data.period_s) + " Hz)");
    }
    data.delay = split_hold_delay(options.delay_s, data.period_s);
    check_status(log, data, options);
    check_saturation(log, data, options);
    if (options.resolution_m) {
        data.resolution_m = *options.resolution_m;
        data.resolution_estimated = false;
    } else {
        data.resolution_m = estimate_resolution(data);
    }
    check_excitation(data);
    return data;
}

std::vector<SegmentRange> make_segments(const AxisData& data, std::size_t target) {
    std::vector<SegmentRange> segments;
    const std::size_t n = data.x->size();
    std::size_t run_start = data.delay.history();
    for (std::size_t i = 0; i < n; ++i) {
        if (i + 1 < n && !data.gap_after[i]) continue;
        const std::size_t run = i + 1 < run_start ? 0 : i + 1 - run_start;
        if (run >= kMinSegmentSamples) {
            const std::size_t pieces = std::max<std::size_t>(1, run / target);
            for (std::size_t p = 0; p < pieces; ++p) {
                const std::size_t begin = run_start + run * p / pieces;
                const std::size_t end = run_start + run * (p + 1) / pieces;
                segments.push_back({begin, end - begin});
            }
        }
        run_start = i + 1 + data.delay.history();
    }
    // A segment needs more fresh samples than its two initial-state parameters.
    std::erase_if(segments, [&](const SegmentRange& s) {
        const auto first = data.masked.begin() + static_cast<std::ptrdiff_t>(s.start);
        return std::count(first, first + static_cast<std::ptrdiff_t>(s.length), 0) <= 2;
    });
    if (segments.empty()) {
        refuse(RefusalReason::too_short, "no run of at least " +
                                             std::to_string(kMinSegmentSamples) +
                                             " consecutive fresh samples between the gaps in t_s");
    }
    return segments;
}

int smoothing_half_width(const AxisData& data) {
    return std::max(3, static_cast<int>(std::lround(kSmoothingHalfWidthS / data.period_s)));
}

StartingGuess starting_guess(const AxisData& data, const std::vector<SegmentRange>& segments) {
    const std::vector<double>& x = *data.x;
    const std::vector<double>& f = *data.f;
    const double T = data.period_s;
    const int h = smoothing_half_width(data);
    // The force acting around row i was commanded about D earlier (segments start past it).
    const auto lag = static_cast<std::size_t>(
        std::lround(static_cast<double>(data.delay.whole_periods) + data.delay.fraction));
    double sum_j2 = 0.0;
    double sum_j4 = 0.0;
    for (int j = -h; j <= h; ++j) {
        sum_j2 += j * j;
        sum_j4 += static_cast<double>(j) * j * j * j;
    }
    const double width = 2.0 * h + 1.0;
    const double mean_j2 = sum_j2 / width;
    const double sum_centred = sum_j4 - width * mean_j2 * mean_j2;  // Σ (j² - μ)²
    Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
    Eigen::Vector4d rhs = Eigen::Vector4d::Zero();
    for (const SegmentRange& s : segments) {
        for (std::size_t c = s.start + h; c + h < s.start + s.length; ++c) {
            bool usable = true;
            double p0 = 0.0;  // Σ f: the force averaged over the window
            double p1 = 0.0;  // Σ j x: the slope
            double p2 = 0.0;  // Σ (j² - μ) x: the curvature
            for (int j = -h; j <= h && usable; ++j) {
                const std::size_t i = c + j;
                usable = !data.masked[i];
                p0 += f[i - lag];
                p1 += j * x[i];
                p2 += (j * j - mean_j2) * x[i];
            }
            if (!usable) continue;
            const double v = p1 / sum_j2 / T;
            const double a = 2.0 * p2 / sum_centred / (T * T);
            const Eigen::Vector4d row(a, v, v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0), -1.0);
            normal += row * row.transpose();
            rhs += row * (p0 / width);
        }
    }
    StartingGuess guess;
    const Eigen::Vector4d theta = normal.ldlt().solve(rhs);
    if (theta.allFinite()) {
        if (theta[0] > 0.0) guess.mass_kg = theta[0];
        guess.damping_n_s_per_m = theta[1] > 0.0 ? theta[1] : 10.0 * guess.mass_kg;
        guess.coulomb_n = std::max(theta[2], 0.0);
        guess.offset_n = theta[3];
    }
    return guess;
}

double initial_velocity(const AxisData& data, const SegmentRange& s) {
    const std::size_t count = std::min<std::size_t>(
        s.length, 2 * static_cast<std::size_t>(smoothing_half_width(data)) + 1);
    double st = 0.0, sx = 0.0, stt = 0.0, stx = 0.0, used = 0.0;
    for (std::size_t j = 0; j < count; ++j) {
        if (data.masked[s.start + j]) continue;
        const double t = static_cast<double>(j) * data.period_s;
        const double x = (*data.x)[s.start + j];
        st += t, sx += x, stt += t * t, stx += t * x, used += 1.0;
    }
    const double denominator = used * stt - st * st;
    const double v = used >= 2.0 && denominator > 0.0 ? (used * stx - st * sx) / denominator : 0.0;
    return v != 0.0 ? v : 1e-12;
}

double initial_position(const AxisData& data, const SegmentRange& s) {
    for (std::size_t j = 0; j < s.length; ++j) {
        if (!data.masked[s.start + j]) return (*data.x)[s.start + j];
    }
    return (*data.x)[s.start];
}

double force_power_above(const AxisData& data, double corner_hz) {
    const std::vector<double>& f = *data.f;
    double mean = 0.0;
    for (double value : f) mean += value;
    mean /= static_cast<double>(f.size());
    const double rc = 1.0 / (2.0 * std::numbers::pi * corner_hz);
    const double alpha = rc / (rc + data.period_s);
    double y = 0.0;
    double high = 0.0;
    double total = 0.0;
    for (std::size_t i = 1; i < f.size(); ++i) {
        y = alpha * (y + f[i] - f[i - 1]);
        high += y * y;
        total += (f[i] - mean) * (f[i] - mean);
    }
    return total > 0.0 ? high / total : 0.0;
}

double force_rms(const AxisData& data) {
    const std::vector<double>& f = *data.f;
    double mean = 0.0;
    for (double value : f) mean += value;
    mean /= static_cast<double>(f.size());
    double sum = 0.0;
    for (double value : f) sum += (value - mean) * (value - mean);
    return std::sqrt(sum / static_cast<double>(f.size()));
}

}  // namespace hapticd::tune::detail
