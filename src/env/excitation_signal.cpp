#include "hapticd/env/excitation_signal.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "hapticd/input/range.hpp"

namespace hapticd::env {
namespace {

// A table longer than this (32 MiB per axis) is a configuration mistake, not a signal.
constexpr std::size_t kMaxPeriodSamples = std::size_t{1} << 22;

void validate(const MultisineSettings& s) {
    if (!(s.sample_rate_hz > 0.0) || !std::isfinite(s.sample_rate_hz)) {
        input::reject_out_of_range("multisine: sample_rate_hz", s.sample_rate_hz, "finite and > 0");
    }
    if (s.axes < 1 || s.axes > 3) input::reject_out_of_range("multisine: axes", s.axes, "1..3");
    if (!(s.band_low_hz > 0.0) || !std::isfinite(s.band_low_hz)) {
        input::reject_out_of_range("multisine: band_low_hz", s.band_low_hz, "finite and > 0");
    }
    if (!(s.band_high_hz > s.band_low_hz) || !(s.band_high_hz < 0.5 * s.sample_rate_hz)) {
        input::reject_out_of_range("multisine: band_high_hz", s.band_high_hz,
                                   "> band_low_hz and < half the sample rate");
    }
    if (!(s.period_s > 0.0) || !std::isfinite(s.period_s)) {
        input::reject_out_of_range("multisine: period_s", s.period_s, "finite and > 0");
    }
    if (!(s.lines_per_decade > 0.0) || !std::isfinite(s.lines_per_decade)) {
        input::reject_out_of_range("multisine: lines_per_decade", s.lines_per_decade,
                                   "finite and > 0");
    }
    if (!(s.peak_force_n > 0.0) || !std::isfinite(s.peak_force_n)) {
        input::reject_out_of_range("multisine: peak_force_n", s.peak_force_n, "finite and > 0");
    }
}

// The quasi-logarithmic grid of harmonics of 1/T_p within [band_low, band_high].
std::vector<int> harmonic_grid(const MultisineSettings& s, double period_s) {
    const double ratio = std::pow(10.0, 1.0 / (s.lines_per_decade * s.axes));
    constexpr double kSlack = 1e-9;  // a band edge that is a harmonic up to rounding counts
    const double first = std::max(1.0, std::ceil(s.band_low_hz * period_s * (1.0 - kSlack)));
    const double last = std::floor(s.band_high_hz * period_s * (1.0 + kSlack));
    std::vector<int> grid;
    for (double h = first; h <= last;) {
        grid.push_back(static_cast<int>(h));
        h = std::max(h + 1.0, std::round(h * ratio));
    }
    return grid;
}

// Lowers the crest factor of one axis's equal-amplitude lines from the Schroeder start by
// clipping and restoring (Van der Ouderaa, Schoukens and Renneboog 1988): clip one period
// at a level below its peak (rising from 60 % to 98 % of it over the iterations), take the clipped
// signal's phases at the lines (its DFT there), put the unit amplitudes back, repeat; the best
// period seen is kept. Deterministic. The work is bounded (iterations x lines x samples), so a long
// table refines less.
void refine_phases(std::vector<MultisineLine>& lines, std::size_t length) {
    constexpr double kTwoPi = 2.0 * std::numbers::pi;
    constexpr double kClipFirst = 0.6;
    constexpr double kClipLast = 0.98;
    constexpr double kWorkBudget = 2e8;  // multiply-adds: well under a second
    const double work_per_iteration = 2.0 * static_cast<double>(lines.size() * length);
    const int iterations =
        static_cast<int>(std::clamp(kWorkBudget / work_per_iteration, 0.0, 200.0));
    if (iterations == 0) return;
    std::vector<double> cos_table(length), sin_table(length);
    for (std::size_t m = 0; m < length; ++m) {
        const double angle = kTwoPi * static_cast<double>(m) / static_cast<double>(length);
        cos_table[m] = std::cos(angle);
        sin_table[m] = std::sin(angle);
    }
    std::vector<double> u(length);
    std::vector<double> cos_phase(lines.size()), sin_phase(lines.size());
    auto synthesise = [&]() {
        for (std::size_t i = 0; i < lines.size(); ++i) {
            cos_phase[i] = std::cos(lines[i].phase_rad);
            sin_phase[i] = std::sin(lines[i].phase_rad);
        }
        double peak = 0.0;
        for (std::size_t n = 0; n < length; ++n) {
            double sum = 0.0;
            for (std::size_t i = 0; i < lines.size(); ++i) {
                const std::size_t m = (static_cast<std::size_t>(lines[i].harmonic) * n) % length;
                sum += cos_table[m] * cos_phase[i] - sin_table[m] * sin_phase[i];
            }
            u[n] = sum;
            peak = std::max(peak, std::abs(sum));
        }
        return peak;
    };
    std::vector<double> best_phases(lines.size());
    for (std::size_t i = 0; i < lines.size(); ++i) best_phases[i] = lines[i].phase_rad;
    double best_peak = synthesise();
    double peak = best_peak;
    for (int iteration = 0; iteration < iterations; ++iteration) {
        // The clip level rises from 60 % to 98 % of the current peak: deep clips first move
        // the phases far, shallow ones then polish.
        const double progress = static_cast<double>(iteration) / iterations;
        const double level = (kClipFirst + (kClipLast - kClipFirst) * progress) * peak;
        for (double& value : u) value = std::clamp(value, -level, level);
        for (MultisineLine& line : lines) {
            double re = 0.0, im = 0.0;
            for (std::size_t n = 0; n < length; ++n) {
                const std::size_t m = (static_cast<std::size_t>(line.harmonic) * n) % length;
                re += u[n] * cos_table[m];
                im -= u[n] * sin_table[m];
            }
            line.phase_rad = std::atan2(im, re);
        }
        peak = synthesise();
        if (peak < best_peak) {
            best_peak = peak;
            for (std::size_t i = 0; i < lines.size(); ++i) best_phases[i] = lines[i].phase_rad;
        }
    }
    for (std::size_t i = 0; i < lines.size(); ++i) lines[i].phase_rad = best_phases[i];
}

}  // namespace

Multisine::Multisine(const MultisineSettings& settings) : settings_(settings) {
    validate(settings_);
    const double samples = std::round(settings_.period_s * settings_.sample_rate_hz);
    if (samples < 4.0 || samples > static_cast<double>(kMaxPeriodSamples)) {
        std::ostringstream m;
        m << "multisine: period_s = " << settings_.period_s << " at " << settings_.sample_rate_hz
          << " Hz is " << samples << " samples: allowed 4.." << kMaxPeriodSamples;
        throw std::invalid_argument(m.str());
    }
    period_samples_ = static_cast<std::size_t>(samples);
    const double period = period_s();

    // The grid, dealt to the axes in turn.
    const std::vector<int> grid = harmonic_grid(settings_, period);
    const auto axes = static_cast<std::size_t>(settings_.axes);
    lines_.assign(axes, {});
    for (std::size_t i = 0; i < grid.size(); ++i) {
        MultisineLine line;
        line.harmonic = grid[i];
        line.frequency_hz = grid[i] / period;
        lines_[i % axes].push_back(line);
    }
    for (std::size_t axis = 0; axis < axes; ++axis) {
        if (lines_[axis].size() < 2) {
            std::ostringstream m;
            m << "multisine: the band " << settings_.band_low_hz << ".." << settings_.band_high_hz
              << " Hz with a period of " << period << " s and " << settings_.lines_per_decade
              << " lines per decade gives axis " << axis << " " << lines_[axis].size()
              << " line(s), fewer than 2: widen the band, lengthen the period or add lines";
            throw std::invalid_argument(m.str());
        }
    }

    // Schroeder phases for equal powers 1/N on a sparse grid.
    constexpr double kTwoPi = 2.0 * std::numbers::pi;
    for (std::vector<MultisineLine>& lines : lines_) {
        const double n = static_cast<double>(lines.size());
        for (std::size_t i = 0; i < lines.size(); ++i) {
            double sum = 0.0;
            for (std::size_t l = 0; l < i; ++l) sum += lines[i].harmonic - lines[l].harmonic;
            lines[i].phase_rad = std::remainder(-kTwoPi * sum / n, kTwoPi);
        }
        refine_phases(lines, period_samples_);
    }

    // One period per axis with unit amplitude, then scaled to peak at peak_force_n.
    const std::size_t length = period_samples_;
    tables_.assign(axes, std::vector<double>(length, 0.0));
    for (std::size_t axis = 0; axis < axes; ++axis) {
        std::vector<MultisineLine>& lines = lines_[axis];
        for (MultisineLine& line : lines) line.amplitude_n = 1.0;
        std::vector<double>& table = tables_[axis];
        for (std::size_t n = 0; n < length; ++n)
            table[n] = evaluate_lines(static_cast<int>(axis), static_cast<std::int64_t>(n));
        double peak = 0.0;
        for (const double u : table) peak = std::max(peak, std::abs(u));
        const double scale = settings_.peak_force_n / peak;
        for (double& u : table) u *= scale;
        for (MultisineLine& line : lines) line.amplitude_n = scale;
    }
    for (std::size_t n = 0; n < length; ++n) {
        double squared = 0.0;
        for (std::size_t axis = 0; axis < axes; ++axis)
            squared += tables_[axis][n] * tables_[axis][n];
        peak_vector_norm_n_ = std::max(peak_vector_norm_n_, std::sqrt(squared));
    }
}

double Multisine::period_s() const noexcept {
    return static_cast<double>(period_samples_) / settings_.sample_rate_hz;
}

const std::vector<MultisineLine>& Multisine::lines(int axis) const {
    return lines_.at(static_cast<std::size_t>(axis));
}

double Multisine::evaluate_lines(int axis, std::int64_t n) const {
    const auto length = static_cast<std::int64_t>(period_samples_);
    double u = 0.0;
    for (const MultisineLine& line : lines(axis)) {
        // The phase of sample n, reduced exactly in integers before it becomes an angle.
        std::int64_t turn = (line.harmonic * (n % length)) % length;
        if (turn < 0) turn += length;
        const double angle =
            2.0 * std::numbers::pi * static_cast<double>(turn) / static_cast<double>(length);
        u += line.amplitude_n * std::cos(angle + line.phase_rad);
    }
    return u;
}

double Multisine::crest_factor(int axis) const {
    const std::vector<double>& table = tables_.at(static_cast<std::size_t>(axis));
    double peak = 0.0, squares = 0.0;
    for (const double u : table) {
        peak = std::max(peak, std::abs(u));
        squares += u * u;
    }
    return peak / std::sqrt(squares / static_cast<double>(table.size()));
}

double Multisine::steady_state_excursion_m(double mass_kg, double damping_n_s_per_m) const {
    if (!(mass_kg > 0.0) || !(damping_n_s_per_m >= 0.0)) {
        throw std::invalid_argument("multisine: the excursion needs mass > 0 and damping >= 0");
    }
    const auto length = static_cast<std::int64_t>(period_samples_);
    double excursion = 0.0;
    for (int axis = 0; axis < axes(); ++axis) {
        // X = U / (jω (b + jω m)) per line: x[n] = Re(c e^{j 2π h n / L}).
        std::vector<std::complex<double>> coefficients;
        for (const MultisineLine& line : lines(axis)) {
            const double w = 2.0 * std::numbers::pi * line.frequency_hz;
            const std::complex<double> impedance(damping_n_s_per_m, w * mass_kg);
            coefficients.push_back(std::polar(line.amplitude_n, line.phase_rad) /
                                   (std::complex<double>(0.0, w) * impedance));
        }
        for (std::int64_t n = 0; n < length; ++n) {
            double x = 0.0;
            for (std::size_t i = 0; i < coefficients.size(); ++i) {
                const std::int64_t turn = (lines(axis)[i].harmonic * n) % length;
                const double angle = 2.0 * std::numbers::pi * static_cast<double>(turn) /
                                     static_cast<double>(length);
                x += coefficients[i].real() * std::cos(angle) -
                     coefficients[i].imag() * std::sin(angle);
            }
            excursion = std::max(excursion, std::abs(x));
        }
    }
    return excursion;
}

}  // namespace hapticd::env
