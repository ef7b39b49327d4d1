// The optional first-order low-pass filter on the coupling damper's velocity
// (docs/stability-models.md, "A velocity filter on the damper"). With the cutoff f_c > 0 the
// damper of (16) acts on
//
//   u[n] = a u[n-1] + (1 - a) (v_d[n] - v_e[n]),   a = exp(-2π f_c T),
//   F[n] = k_c (x_d[n] - x_e[n]) + b_c u[n],
//
// v_d, v_e the backward differences of (16). f_c = 0 is no filter (a = 0, u = v_d - v_e).
// In z the coupling's impedance on the backward-difference velocity becomes
//
//   Z_c(z) = k_c T / (1 - z⁻¹) + b_c B(z),   B(z) = (1 - a) / (1 - a z⁻¹),
//
// and on the unit circle z = e^{jθ}, with 1 - a cos θ = (1 - a) + 2a sin²(θ/2) and
// |1 - a e^{-jθ}|² = (1 - a)² + 4a sin²(θ/2) (both kept exact as θ -> 0):
//
//   Re B = (1 - a) ((1 - a) + 2a sin²(θ/2)) / ((1 - a)² + 4a sin²(θ/2)),
//   Im B = -(1 - a) a sin θ / ((1 - a)² + 4a sin²(θ/2)),
//   Re(1/B) = 1 + 2a sin²(θ/2) / (1 - a).
//
// B(1) = 1: the damper keeps b_c at DC; B(-1) = (1 - a)/(1 + a) at Nyquist. B is positive
// real (Re B > 0 for 0 <= a < 1), so a filtered coupling is still a passive impedance.
#pragma once

#include <cmath>
#include <numbers>

namespace hapticd::theory {

/// a = exp(-2π f_c T); 0 for f_c <= 0 (no filter). The servo and every model use this one
/// expression, so that the runtime and the analysis hold the same coefficient to the bit.
inline double velocity_filter_pole(double cutoff_hz, double period_s) noexcept {
    return cutoff_hz > 0.0 ? std::exp(-2.0 * std::numbers::pi * cutoff_hz * period_s) : 0.0;
}

/// B(e^{jθ}) of the file comment, in real arithmetic (templated for Ceres jets in θ).
template <typename S>
struct FilterResponse {
    S re;
    S im;
};

template <typename S>
FilterResponse<S> velocity_filter_response(double pole, const S& theta) {
    using std::sin;
    const double a = pole;
    const S half_sine = sin(theta / 2.0);
    const S h2 = half_sine * half_sine;
    const S denominator = (1.0 - a) * (1.0 - a) + 4.0 * a * h2;
    return {(1.0 - a) * ((1.0 - a) + 2.0 * a * h2) / denominator,
            -(1.0 - a) * a * sin(theta) / denominator};
}

/// Re(1/B(e^{jθ})) = 1 + 2a sin²(θ/2)/(1 - a): the filtered damper alone, b_c B, has the
/// conductance Re(1/(b_c B)) = this / b_c (>= 1/b_c, the unfiltered damper's).
inline double velocity_filter_conductance_gain(double pole, double theta) {
    const double half_sine = std::sin(theta / 2.0);
    return 1.0 + 2.0 * pole * half_sine * half_sine / (1.0 - pole);
}

}  // namespace hapticd::theory
