// The excitation signal of `hapticd --identify` (docs/identification.md, "Excitation"): a
// periodic multisine, one period tabulated per axis at the servo rate.
//
//   u_a[n] = sum over the lines i of axis a of  A cos(2π h_i n / L + φ_i),   n = 0, 1, ...
//
// - Period L samples (T_p = L / rate): every line is a whole harmonic h_i of 1/T_p, so each
//   period is exactly the same and a DFT over whole periods sees the lines and nothing else
//   (no leakage); periods can be averaged.
// - Quasi-logarithmic grid: from the first harmonic >= band_low, each next harmonic is
//   max(h + 1, round(h r)) with r = 10^(1 / (lines_per_decade axes)), up to band_high. Equal
//   power per decade (the same share below and above the device's corner b/(2π m)), and the
//   harmonics left out show any nonlinear distortion (Coulomb friction) as energy off the
//   excited lines.
// - Several axes: the grid's lines are dealt to the axes in turn (line i to axis i mod
//   axes), so the axes' signals are orthogonal over a period: a cross-coupling shows up at
//   the other axes' lines, never mixed with an axis's own response.
// - Equal amplitude A on every line of an axis, and phases chosen for a low crest factor
//   (peak / rms), so that a force limit admits as much excitation power as it can: first
//   Schroeder's phases (Schroeder 1970, for unequal powers, absent harmonics at zero power),
//       φ_i = -2π sum_{l < i} (h_i - h_l) / N      (N: the axis's lines),
//   which sweep the lines like a chirp within each period (crest factor 2.7 on the default
//   14-line grid: a sparse grid is not the dense one Schroeder's formula assumes), then
//   refined by clipping and restoring (Van der Ouderaa, Schoukens and Renneboog 1988): 1.86
//   on the same grid, against sqrt(2 N) = 5.3 with equal phases. A is then chosen so that
//   each axis's table peaks at exactly `peak_force_n`. Deterministic: the same settings
//   always give the same table (no seed).
//
// sample() is real-time safe (a table look-up); everything else runs at construction.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace hapticd::env {

struct MultisineSettings {
    double sample_rate_hz = 1000.0;  ///< one table sample per servo tick, > 0
    int axes = 1;                    ///< 1..3
    double band_low_hz = 1.0;        ///< every line is >= this (to rounding), > 0
    double band_high_hz = 30.0;      ///< every line is <= this, > band_low, < rate / 2
    double period_s = 4.0;           ///< T_p, rounded to whole samples; lines are k / T_p
    double lines_per_decade = 10.0;  ///< per axis, > 0
    double peak_force_n = 1.0;       ///< each axis's max |u_a[n]|, > 0
};

/// One excited line of one axis: A cos(2π h n / L + φ).
struct MultisineLine {
    int harmonic = 0;  ///< h: the line is at h / T_p
    double frequency_hz = 0.0;
    double amplitude_n = 0.0;  ///< A
    double phase_rad = 0.0;    ///< φ
};

class Multisine {
  public:
    /// Throws std::invalid_argument naming the setting and its value, also when an axis
    /// would get fewer than two lines (widen the band, lengthen the period or add lines).
    explicit Multisine(const MultisineSettings& settings);

    [[nodiscard]] const MultisineSettings& settings() const noexcept { return settings_; }
    [[nodiscard]] int axes() const noexcept { return settings_.axes; }
    /// L, samples per period.
    [[nodiscard]] std::size_t period_samples() const noexcept { return period_samples_; }
    /// T_p = L / rate, s.
    [[nodiscard]] double period_s() const noexcept;
    /// The lines of `axis` (0-based, < axes()), lowest first.
    [[nodiscard]] const std::vector<MultisineLine>& lines(int axis) const;

    /// u_axis[n], N, for any integer n (periodic in L). Real-time safe; axis < axes().
    [[nodiscard]] double sample(int axis, std::int64_t n) const noexcept {
        const auto length = static_cast<std::int64_t>(period_samples_);
        std::int64_t index = n % length;
        if (index < 0) index += length;
        return tables_[static_cast<std::size_t>(axis)][static_cast<std::size_t>(index)];
    }

    /// The same from the line list, by the formula above (for tests and checks), N.
    [[nodiscard]] double evaluate_lines(int axis, std::int64_t n) const;

    /// Peak over rms of one period of `axis` (sqrt(2) for one line).
    [[nodiscard]] double crest_factor(int axis) const;
    /// max over n of |(u_0[n], u_1[n], u_2[n])|, N: the largest force vector the table asks.
    [[nodiscard]] double peak_vector_norm_n() const noexcept { return peak_vector_norm_n_; }

    /// The periodic steady-state displacement of the device model m dv/dt + b v = u_a (the
    /// benchmark device (10), one per axis) under this signal: max over the axes and over a
    /// period of |x_a(t)| at the sample instants, m, with x_a the zero-mean periodic
    /// solution. How far the handle swings about where it started (the fade-in keeps any
    /// drift of that centre small). mass > 0, damping >= 0.
    [[nodiscard]] double steady_state_excursion_m(double mass_kg, double damping_n_s_per_m) const;

  private:
    MultisineSettings settings_;
    std::size_t period_samples_ = 0;
    std::vector<std::vector<MultisineLine>> lines_;  ///< per axis
    std::vector<std::vector<double>> tables_;        ///< per axis, L samples
    double peak_vector_norm_n_ = 0.0;
};

}  // namespace hapticd::env
