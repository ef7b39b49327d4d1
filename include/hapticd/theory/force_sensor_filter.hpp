// The analog anti-aliasing filter on the admittance display's force sensor (the sensor's
// conditioning amplifier): a continuous low-pass H_aa(s) between the handle force F_h and the
// sample the servo reads each tick. docs/stability-models.md, "The anti-aliasing filter".
//
//   order 2:  H_aa(s) = ω_a² / (s² + 2 ζ_a ω_a s + ω_a²),  ω_a = 2π f_aa  (ζ_a = 1/√2: Butterworth)
//   order 1:  H_aa(s) = ω_a / (s + ω_a)
//
// In state space (companion form, output the first state) ẋ_f = A_f x_f + B_f F_h,
// F_f = C_f x_f, with no feedthrough: the filtered force is continuous, so its sample at nT
// has no jump to take off (the unfiltered sensor's rigid-hand μ term of the passive model
// disappears). Its ZOH equivalent under the loop's hold, shifted by φ of a period,
//   H_hold(z) = C_f (zI - Φ_f)^{-1} (Γ_new + Γ_old z^{-1}),
//   Φ_f = e^{A_f T},  Γ_new = ∫_0^{(1-φ)T} e^{A_f τ} dτ B_f,
//   Γ_old = e^{A_f (1-φ)T} ∫_0^{φT} e^{A_f τ} dτ B_f,
// is the alias sum (1 - e^{-jθ}) Σ_k H_aa(jω_k) e^{-jθ_k φ}/(jθ_k) in closed form (the sample
// of the filter's response to the held command); with φ = 0 it is (1 - z^{-1}) Z{H_aa(s)/s}.
#pragma once

#include <string>

#include "hapticd/theory/unit_circle.hpp"

namespace hapticd::theory {

struct ForceSensorFilter {
    double cutoff_hz = 0.0;                         ///< f_aa, 0 < f_aa <= 100 f_s
    double damping_ratio = 0.70710678118654752440;  ///< ζ_a in (0, 10]; order 2 only
    int order = 2;                                  ///< 1 or 2

    /// For example "2nd-order low-pass, f_aa = 100 Hz, ζ = 0.707".
    std::string describe() const;
};

/// The highest cutoff accepted, in multiples of the servo rate: beyond it the filter is a wire
/// for every alias the loop resolves.
inline constexpr double kMaxForceFilterCutoffPerRate = 100.0;
inline constexpr double kMaxForceFilterDampingRatio = 10.0;

/// Throws std::invalid_argument naming the value and its allowed range.
void check_force_sensor_filter(const ForceSensorFilter& filter, double rate_hz);

/// H_aa(jω), ω in rad/s (signed).
Complex force_filter_response(const ForceSensorFilter& filter, double omega_rad_s);

/// The closed form H_hold(e^{jθ}) of the file comment (matrix exponentials of A_f), delay
/// fraction 0 <= φ < 1. The whole periods of delay are not in it.
Complex force_filter_hold_equivalent(const ForceSensorFilter& filter, double theta,
                                     double sample_period_s, double delay_fraction = 0.0);

/// Φ_f, Γ_new, Γ_old of the file comment for a step of `step_s` (exposed for the exact loop's
/// test; the loop samples the filter together with the plant).
struct FilterSampling {
    Complex phi[2][2];
    Complex gamma[2];
};
FilterSampling sample_force_filter(const ForceSensorFilter& filter, double step_s);

/// Σ_{|k| <= terms} |H_aa(jω_k)|, ω_k = (θ + 2πk)/T: the sensor part of Σ |β_k| without the
/// device's weights. It converges for order 2 (|H| ~ 1/k²) and grows like log(terms) for
/// order 1 (|H| ~ 1/k), which is why a first-order filter sizes no coupling.
double force_filter_alias_sum(const ForceSensorFilter& filter, double theta, double sample_period_s,
                              int terms);

/// Bounds on the tails Σ_{|k|>N} |H_aa(jω_k)| and Σ_{|k|>N} |H_aa(jω_k)|/|θ_k| (order 2; +inf
/// for order 1, or while ω_N = 2π(N - 1/2)/T <= ω_a): |θ_k| >= 2π(|k| - 1/2) and
/// |H| <= ω_a²/(ω² - ω_a²) for ω > ω_a, summed against an integral.
struct FilterAliasTail {
    double response = 0.0;            ///< >= Σ_{|k|>N} |H_k|
    double response_per_alias = 0.0;  ///< >= Σ_{|k|>N} |H_k|/|θ_k|
};
FilterAliasTail force_filter_alias_tail(const ForceSensorFilter& filter, double sample_period_s,
                                        int terms);

}  // namespace hapticd::theory
