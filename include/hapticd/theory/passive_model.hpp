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
// In series with an environment (17), Z = 1/(1/Z_c + Y_e). Over every passive operator and
// every passive environment (Re Y_e >= 0) the loop has no pole at e^{jθ} iff
//     Re(1/Z_c) > M(θ) / (2b),   M(θ) = 1 - Re(e^{-j(1+q)θ} ρ)
//                                     = (1 - φ)(1 - cos((1 + q)θ)) + φ (1 - cos((2 + q)θ)),
// the shape of (21) (docs/stability-models.md, "Every passive environment"): the sampled
// velocity is Ĝ = Σ_k c_k Y(jω_k) times the force, with alias weights c_k of total modulus 1
// and phases -(1 + q)θ - φ(θ + 2πk), and a passive device-plus-operator admittance Y can sit
// anywhere in the disk |Y - 1/(2b)| <= 1/(2b) at each alias; the worst sum is
// Σ_k c_k (1 - e^{-j arg c_k})/(2b) = (e^{-j(1+q)θ} ρ - 1)/(2b). M is the linear interpolation,
// in φ, between the whole-period bounds 1 - cos((1 + q)θ) and 1 - cos((2 + q)θ): (21) with the
// hold term e^{-j(1+q)θ} for whole periods, of which the `encoder` model's e^{-jθ} sinc²(θ/2)
// keeps one term. It equals the worst of b >= λ(ζ) over the environments (held against a brute
// force over 200,000 lossless environments and the lifted computation in
// tests/theory/passive_model_test.cpp). As θ -> 0, M ~ τ² θ²/2 with
//     τ² = (1 + q + φ)² + φ (1 - φ).
#pragma once

#include <cmath>
#include <complex>

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

/// M(θ) of the file comment: twice the least device damping, times Re(1/Z_c), that keeps the
/// loop stable against every passive operator and every passive environment at θ. Templated
/// so that the sizing solver can differentiate it with Ceres jets. 1 - cos x is written
/// 2 sin²(x/2) to keep its precision as θ -> 0.
template <typename S>
S passive_hold_numerator(const S& theta, double delay_periods) {
    using std::sin;
    const LoopDelay d = split_delay(delay_periods);
    const S now = sin((1.0 + d.whole_periods) * theta / 2.0);
    const S next = sin((2.0 + d.whole_periods) * theta / 2.0);
    return 2.0 * ((1.0 - d.fraction) * now * now + d.fraction * next * next);
}

/// The sum of the alias weights, e^{-j(1+q)θ} ρ: the sampled velocity per unit force of a
/// device-plus-operator admittance that is the same real number at every alias, and what
/// the worst passive operator's sum is measured from, (e^{-j(1+q)θ} ρ - 1)/(2b).
Complex passive_alias_weight_sum(double theta, double delay_periods);

/// τ with M(θ) ~ τ² θ²/2 as θ -> 0: τ² = (1 + q + φ)² + φ(1 - φ). τ = 1 with no delay.
double passive_delay_samples(double delay_periods);

}  // namespace hapticd::theory
