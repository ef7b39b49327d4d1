#include "hapticd/theory/force_sensor_filter.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace hapticd::theory {
namespace {

constexpr double kPi = std::numbers::pi;

/// The companion form of the file comment: A_f, B_f (C_f = [1 0]); order 1 uses the
/// top-left entry only.
void companion(const ForceSensorFilter& f, double a[2][2], double b[2]) {
    const double w = 2.0 * kPi * f.cutoff_hz;
    if (f.order == 1) {
        a[0][0] = -w, a[0][1] = 0.0, a[1][0] = 0.0, a[1][1] = 0.0;
        b[0] = w, b[1] = 0.0;
        return;
    }
    a[0][0] = 0.0, a[0][1] = 1.0, a[1][0] = -w * w, a[1][1] = -2.0 * f.damping_ratio * w;
    b[0] = 0.0, b[1] = w * w;
}

}  // namespace

std::string ForceSensorFilter::describe() const {
    std::ostringstream s;
    s << (order == 1 ? "1st" : "2nd") << "-order low-pass, f_aa = " << cutoff_hz << " Hz";
    if (order == 2) s << ", ζ = " << damping_ratio;
    return s.str();
}

void check_force_sensor_filter(const ForceSensorFilter& f, double rate_hz) {
    const double highest = kMaxForceFilterCutoffPerRate * rate_hz;
    if (!(f.cutoff_hz > 0.0 && f.cutoff_hz <= highest)) {
        std::ostringstream s;
        s << "force-sensor filter cutoff f_aa = " << f.cutoff_hz << " Hz is outside (0, " << highest
          << "] Hz (0 < f_aa <= " << kMaxForceFilterCutoffPerRate << " x the servo rate)";
        throw std::invalid_argument(s.str());
    }
    if (f.order != 1 && f.order != 2) {
        std::ostringstream s;
        s << "force-sensor filter order " << f.order << " is not 1 or 2";
        throw std::invalid_argument(s.str());
    }
    if (!(f.damping_ratio > 0.0 && f.damping_ratio <= kMaxForceFilterDampingRatio)) {
        std::ostringstream s;
        s << "force-sensor filter damping ratio ζ = " << f.damping_ratio << " is outside (0, "
          << kMaxForceFilterDampingRatio << "]";
        throw std::invalid_argument(s.str());
    }
}

Complex force_filter_response(const ForceSensorFilter& f, double omega_rad_s) {
    const double w = 2.0 * kPi * f.cutoff_hz;
    const Complex s(0.0, omega_rad_s);
    if (f.order == 1) return w / (s + w);
    return w * w / (s * s + 2.0 * f.damping_ratio * w * s + w * w);
}

FilterSampling sample_force_filter(const ForceSensorFilter& f, double step_s) {
    double a[2][2], b[2];
    companion(f, a, b);
    FilterSampling out{};
    if (f.order == 1) {
        // Φ = e^{-ω t}, Γ = 1 - e^{-ω t}.
        out.phi[0][0] = std::exp(a[0][0] * step_s);
        out.gamma[0] = -std::expm1(a[0][0] * step_s);
        return out;
    }
    // e^{At} = e^{λ̄t}[cosh(μt) I + sinh(μt)/μ (A - λ̄ I)], λ̄ = tr A/2, μ² = λ̄² - det A;
    // both e^{(λ̄ ± μ)t} decay (the eigenvalues), so neither overflows.
    const double mean = (a[0][0] + a[1][1]) / 2.0;
    const double det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    const Complex mu = std::sqrt(Complex(mean * mean - det, 0.0));
    const Complex up = std::exp((mean + mu) * step_s), down = std::exp((mean - mu) * step_s);
    const Complex cosh_part = (up + down) / 2.0;
    Complex sinh_over_mu;
    if (std::abs(mu * step_s) < 1e-3) {
        const Complex x2 = mu * mu * step_s * step_s;
        sinh_over_mu = std::exp(mean * step_s) * step_s * (1.0 + x2 / 6.0 + x2 * x2 / 120.0);
    } else {
        sinh_over_mu = (up - down) / (2.0 * mu);
    }
    for (int i = 0; i < 2; ++i) {
        for (int j = 0; j < 2; ++j) {
            out.phi[i][j] = sinh_over_mu * (a[i][j] - (i == j ? mean : 0.0)) +
                            (i == j ? cosh_part : Complex(0.0));
        }
    }
    // Γ = A^{-1} (Φ - I) B (A is invertible: det = ω_a² > 0).
    const Complex r0 = out.phi[0][0] * b[0] + out.phi[0][1] * b[1] - b[0];
    const Complex r1 = out.phi[1][0] * b[0] + out.phi[1][1] * b[1] - b[1];
    out.gamma[0] = (a[1][1] * r0 - a[0][1] * r1) / det;
    out.gamma[1] = (-a[1][0] * r0 + a[0][0] * r1) / det;
    return out;
}

Complex force_filter_hold_equivalent(const ForceSensorFilter& f, double theta,
                                     double sample_period_s, double delay_fraction) {
    const FilterSampling whole = sample_force_filter(f, sample_period_s);
    const FilterSampling late = sample_force_filter(f, (1.0 - delay_fraction) * sample_period_s);
    const FilterSampling early = sample_force_filter(f, delay_fraction * sample_period_s);
    const Complex z = std::polar(1.0, theta), z_inv = 1.0 / z;
    // Γ_new + Γ_old z^{-1}, Γ_old = e^{A(1-φ)T} Γ(φT).
    Complex g[2];
    for (int i = 0; i < 2; ++i) {
        const Complex old = late.phi[i][0] * early.gamma[0] + late.phi[i][1] * early.gamma[1];
        g[i] = late.gamma[i] + old * z_inv;
    }
    // C (zI - Φ)^{-1} g with C = [1 0]: the first row of the inverse.
    const Complex m00 = z - whole.phi[0][0], m01 = -whole.phi[0][1];
    const Complex m10 = -whole.phi[1][0], m11 = z - whole.phi[1][1];
    const Complex det = m00 * m11 - m01 * m10;
    return (m11 * g[0] - m01 * g[1]) / det;
}

double force_filter_alias_sum(const ForceSensorFilter& f, double theta, double sample_period_s,
                              int terms) {
    double sum = 0.0;
    for (int k = -terms; k <= terms; ++k) {
        sum += std::abs(force_filter_response(f, (theta + 2.0 * kPi * k) / sample_period_s));
    }
    return sum;
}

FilterAliasTail force_filter_alias_tail(const ForceSensorFilter& f, double sample_period_s,
                                        int terms) {
    const double inf = std::numeric_limits<double>::infinity();
    const double w = 2.0 * kPi * f.cutoff_hz;
    const double n = terms - 0.5;
    const double w_n = 2.0 * kPi * n / sample_period_s;  // the lowest |ω_k| beyond the sum
    if (f.order == 1 || terms < 1 || w_n <= w) return {inf, inf};
    // |H| <= ω_a²/(ω² - ω_a²) <= ω_a²/(ω² (1 - ω_a²/ω_N²)) for |ω| >= ω_N; two aliases per
    // |k| = n > N with |θ_k| >= 2π(n - 1/2); Σ_{n>N} (n - 1/2)^{-p} <= ∫_N^∞ (x - 1/2)^{-p} dx.
    const double scale =
        2.0 * w * w / (1.0 - (w / w_n) * (w / w_n)) * std::pow(sample_period_s / (2.0 * kPi), 2);
    return {scale / n, scale / (2.0 * kPi) / (2.0 * n * n)};
}

}  // namespace hapticd::theory
