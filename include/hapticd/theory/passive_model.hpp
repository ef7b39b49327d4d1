// The `passive` stability model (docs/architecture.md §1.3, §7.9): Colgate and Schenkel's
// sampled-data passivity condition at the device port, with the loop's delay, worst-cased over
// every passive environment. The derivation is in docs/stability-models.md; in short:
//
// The device (10) m dv/dt + b v = F_h - F_d is sampled at t = nT; a linear discrete
// controller H(z) computes F[n] from the samples, and F[n] acts on [nT + D, (n+1)T + D),
// D = (q + φ) T, q whole periods and 0 <= φ < 1 (D = 0 is the plain zero-order hold). Write
// H(z) = Z(z) (1 - z⁻¹)/T, Z the impedance the controller puts on the backward-difference
// velocity. Folding the human's velocity onto its aliases ω_k = (θ + 2πk)/T and minimising the
// energy the damping b takes out (Σ b|V_k|²) for a given sampled position gives, at each θ:
//
//   the port is passive iff  b >= λ(ζ),   ζ = -Z(e^{jθ}) e^{-j(1+q)θ},
//   λ(ζ) = ( Re(ζρ) + sqrt( Re(ζρ)² + |ζ|² (1 - |ρ|²) ) ) / 2,   ρ = (1 - φ) + φ e^{-jθ}.
//
// ρ is Σ_k e^{-jω_kφT}/ω_k² over Σ_k 1/ω_k²: the aliases' weights of the shifted hold, which sum
// in closed form to the linear interpolation between 1 and e^{-jθ}. For a whole-period delay
// (φ = 0) λ(ζ) = max(Re ζ, 0), which is Colgate and Schenkel's condition
//     b >= (T/2) Re{(1 - e^{-jθ}) H(e^{jθ}) z^{-q}} / (1 - cos θ)
// (a virtual wall K, B with no delay: b >= K T/2 + B). For φ > 0 the shifted hold leaks the
// force of one alias into the others, and λ is larger than the naive e^{-j(1+q+φ)θ}.
//
// In series with an environment (17), Z = 1/(1/Z_c + Y_e). Over every passive environment
// (Re Y_e >= 0, any reactance: a lossless one realises any value at one frequency) the worst
// λ is, with c = Re(1/Z_c),
//     max λ = M(θ) / (2c),   M(θ) = max over |u - 1| <= 1 of λ(-u e^{-j(1+q)θ})
// (λ is positively homogeneous), so the condition has the form of (21):
//     Re(1/Z_c) >= M(θ) / (2b).
// For φ = 0, M(θ) = 1 - cos((1 + q)θ): (21) with the hold term e^{-j(1+q)θ}, the whole alias
// sum, of which the `encoder` model's e^{-jθ} sinc²(θ/2) keeps one term. For φ > 0, M is a
// one-dimensional maximum, found numerically; as θ -> 0, M ~ τ² θ²/2 with
//     τ² = (1 + q + φ)² + φ (1 - φ).
#pragma once

#include <cmath>
#include <numbers>
#include <type_traits>
#include <utility>
#include <vector>

#include "hapticd/theory/unit_circle.hpp"

namespace hapticd::theory {

/// The delay D = (q + φ) T beyond the hold, split into whole periods and a fraction.
struct LoopDelay {
    int whole_periods = 0;  ///< q >= 0
    double fraction = 0.0;  ///< φ in [0, 1)
};

/// Splits a delay in periods. The caller validates the range (finite, 0 <= d < 10).
LoopDelay split_delay(double delay_periods);

/// The least device damping b (N s/m) that keeps the device port passive at θ, for a
/// controller that puts the impedance Z(e^{jθ}) on the backward-difference velocity, with a
/// delay of `delay_periods` beyond the hold: λ(ζ) of the file comment.
double port_damping_needed(Complex controller_impedance, double theta, double delay_periods);

namespace passive_detail {

template <typename S>
double scalar_value(const S& x) {
    if constexpr (std::is_arithmetic_v<S>) {
        return static_cast<double>(x);
    } else {
        return x.a;  // a ceres::Jet
    }
}

/// The θ-dependent part of λ on the boundary of the worst environments' disk: p = |ρ|,
/// s² = 1 - |ρ|², and α' = (1 + q)θ - arg ρ (docs/stability-models.md).
template <typename S>
struct ShiftedHold {
    S p, s2, alpha;
    ShiftedHold(const S& theta, double whole_periods, double fraction) {
        using std::atan2;
        using std::cos;
        using std::sin;
        using std::sqrt;
        const S rho_re = (1.0 - fraction) + fraction * cos(theta);
        const S rho_im = -fraction * sin(theta);
        p = sqrt(rho_re * rho_re + rho_im * rho_im);
        const S half_sine = sin(theta / 2.0);
        s2 = 4.0 * fraction * (1.0 - fraction) * half_sine * half_sine;  // 1 - |ρ|², exactly
        alpha = (1.0 + whole_periods) * theta - atan2(rho_im, rho_re);
    }
    /// h(χ) = cos χ (sqrt(p² c² + s²) - p c), c = cos(χ - α'): λ at u = 2 cos χ e^{jχ}.
    S operator()(const S& chi) const {
        using std::cos;
        using std::sqrt;
        const S pc = p * cos(chi - alpha);
        const S root = sqrt(pc * pc + s2);
        // sqrt(p²c² + s²) - pc without cancellation when pc > 0.
        const S g = scalar_value(pc) > 0.0 ? s2 / (root + pc) : root - pc;
        return cos(chi) * g;
    }
};

/// The slope of h for Newton's method, in double: h'(χ) = g φ(χ)/sqrt(p²c² + s²) with
///   φ(χ) = p cos χ sin(χ - α') - sqrt(p²c² + s²) sin χ,
///   φ'(χ) = p cos(2χ - α') + p² c sin(χ - α') sin χ / sqrt(p²c² + s²) - sqrt(p²c² + s²) cos χ,
/// so the maximum is the root of φ where φ' < 0. One sincos and one sqrt per step.
struct ShiftedHoldSlope {
    double p, s2, cos_alpha, sin_alpha;
    explicit ShiftedHoldSlope(const ShiftedHold<double>& h)
        : p(h.p), s2(h.s2), cos_alpha(std::cos(h.alpha)), sin_alpha(std::sin(h.alpha)) {}
    /// φ and φ' at χ.
    std::pair<double, double> operator()(double chi) const {
        const double c0 = std::cos(chi), s0 = std::sin(chi);
        const double c = c0 * cos_alpha + s0 * sin_alpha;   // cos(χ - α')
        const double sd = s0 * cos_alpha - c0 * sin_alpha;  // sin(χ - α')
        const double c2 = c0 * c - s0 * sd;                 // cos(2χ - α')
        const double root = std::sqrt(p * p * c * c + s2);
        const double phi = p * c0 * sd - root * s0;
        const double slope = p * c2 + p * p * c * sd * s0 / root - root * c0;
        return {phi, slope};
    }
};

template <typename S>
S boundary_lambda(const S& theta, double chi, double whole_periods, double fraction) {
    return ShiftedHold<S>(theta, whole_periods, fraction)(S(chi));
}

/// The χ in [-π/2, π/2] that maximises boundary_lambda at θ (a scan, then golden section).
double worst_boundary_angle(double theta, double whole_periods, double fraction);

}  // namespace passive_detail

/// M(θ) of the file comment: twice the least device damping, times Re(1/Z_c), that keeps the
/// port passive against every passive environment at θ. Templated so that the sizing solver
/// can differentiate it with Ceres jets (for φ > 0 the maximiser is found in double and the
/// derivative follows from the envelope theorem).
template <typename S>
S passive_hold_numerator(const S& theta, double delay_periods) {
    using std::sin;
    const LoopDelay d = split_delay(delay_periods);
    if (d.fraction == 0.0) {
        // 1 - cos((1+q)θ), written 2 sin²((1+q)θ/2) to keep its precision as θ -> 0.
        const S s = sin((1.0 + d.whole_periods) * theta / 2.0);
        return 2.0 * s * s;
    }
    const double chi = passive_detail::worst_boundary_angle(passive_detail::scalar_value(theta),
                                                            d.whole_periods, d.fraction);
    return passive_detail::boundary_lambda(theta, chi, d.whole_periods, d.fraction);
}

/// M(θ) on an increasing grid of frequencies, the same values as passive_hold_numerator:
/// for a fraction of a period each maximum starts from the previous frequency's (the
/// maximiser moves continuously with θ), which makes a table of 20,000 frequencies about
/// three times faster than 20,000 separate maxima.
std::vector<double> passive_hold_numerators(const std::vector<double>& thetas,
                                            double delay_periods);

/// τ with M(θ) ~ τ² θ²/2 as θ -> 0: τ² = (1 + q + φ)² + φ(1 - φ). τ = 1 with no delay.
double passive_delay_samples(double delay_periods);

}  // namespace hapticd::theory
