// The paper's benchmark impedance display, (10)-(21): a 1-DOF device of mass m and
// damping b, sampled with a zero-order hold, coupled to the virtual environment by the
// spring-damper virtual coupling (16).
//
// The hold term is where the stability models differ (DESIGN.md):
//   HoldModel::paper   ZOH(z) = (1/2)(z + 1)/z, (13) as printed;
//   HoldModel::encoder e^{-jθ/2} sinc(θ/2), the exact zero-order hold, times the same
//                      factor again for the backward-difference velocity, which averages
//                      the true velocity over the last period:  e^{-jθ} sinc²(θ/2).
// All functions take the normalised frequency θ = ωT, 0 < θ <= π.
#pragma once

#include <cmath>
#include <optional>
#include <string_view>

#include "hapticd/theory/twoport.hpp"
#include "hapticd/theory/unit_circle.hpp"

namespace hapticd::theory {

/// Device (10): m dv/dt + b v = F_h - F_d.
struct DeviceModel {
    double mass_kg = 0.0;
    double damping_n_s_per_m = 0.0;
};

/// Virtual coupling (16): a spring k_c in parallel with a damper b_c.
struct SpringDamperCoupling {
    double stiffness_n_per_m = 0.0;
    double damping_n_s_per_m = 0.0;
};

/// Which hold term stands in for (13).
enum class HoldModel { paper, encoder };

std::string_view to_string(HoldModel model);
std::optional<HoldModel> parse_hold_model(std::string_view name);

/// (12): Z_dI(z) = (m s + b) with s -> (2/T)(z-1)/(z+1). Its real part is b on the
/// unit circle, which is why Tustin preserves passivity.
Complex device_impedance(const DeviceModel& device, double theta, double sample_period_s);

/// The device impedance each model uses: (12) for HoldModel::paper; for the encoder model
/// m jω + b at the true frequency, consistent with its exact (unwarped) hold term. Both
/// have real part b, so (21) is the same either way; the admittance display (29)-(30)
/// sees the difference near Nyquist, where Tustin's warping sends |Z_dI| to infinity.
Complex device_impedance(const DeviceModel& device, HoldModel model, double theta,
                         double sample_period_s);

/// (16): Z_cI(z) = b_c + k_c T z/(z - 1).
Complex coupling_impedance(const SpringDamperCoupling& coupling, double theta,
                           double sample_period_s);

/// The hold term: (13) for HoldModel::paper, e^{-jθ} sinc²(θ/2) for HoldModel::encoder.
Complex hold_term(HoldModel model, double theta);

/// (14): hybrid matrix of the sampled impedance display without a coupling.
TwoPort impedance_display(const DeviceModel& device, HoldModel model, double theta,
                          double sample_period_s);

/// (17): hybrid matrix of the virtual coupling network alone.
TwoPort coupling_network(const SpringDamperCoupling& coupling, double theta,
                         double sample_period_s);

/// (18): hybrid matrix of the haptic interface, display and coupling in cascade.
TwoPort impedance_interface(const DeviceModel& device, const SpringDamperCoupling& coupling,
                            HoldModel model, double theta, double sample_period_s);

// ---- (21) in real arithmetic ---------------------------------------------------------
// The sizing solver differentiates these with Ceres jets, so they are templates on the
// scalar type and use only +, -, *, /, sin, cos, tan, sqrt.

/// (1 - cos∠H)|H|, the numerator of the right side of (21), for the hold term H.
template <typename S>
S hold_bound_numerator(HoldModel model, const S& theta) {
    using std::cos;
    using std::sin;
    // 1 - cos(x) is written 2 sin²(x/2) to keep its precision as θ -> 0.
    if (model == HoldModel::paper) {
        // ∠ZOH = -θ/2, |ZOH| = cos(θ/2).
        const S s = sin(theta / 4.0);
        return 2.0 * s * s * cos(theta / 2.0);
    }
    // ∠H = -θ, |H| = sinc²(θ/2).
    const S s = sin(theta / 2.0);
    const S sc = sinc(S(theta / 2.0));
    return 2.0 * s * s * sc * sc;
}

/// Group delay of the hold term in samples: H ≈ e^{-j τ θ} as θ -> 0, so the numerator of
/// (21) behaves like τ² θ²/2 there. τ = 1/2 for (13), 1 for the encoder model.
double hold_delay_samples(HoldModel model);

/// Right side of (21): the least coupling conductance Re(1/Z_c) the device needs,
///   (1 - cos∠H)|H| / (2 Re Z_dI),  with Re Z_dI = b.
template <typename S>
S conductance_bound(HoldModel model, double device_damping_n_s_per_m, const S& theta) {
    return hold_bound_numerator(model, theta) / (2.0 * device_damping_n_s_per_m);
}

/// Left side of (21): Re(1/Z_cI) for the coupling (16). With z = e^{jθ},
/// z/(z-1) = 1/2 - (j/2)cot(θ/2), so Z_cI = R - jX with R = b_c + k_c T/2 and
/// X = (k_c T/2) cot(θ/2), and Re(1/Z_cI) = R/(R² + X²).
template <typename S>
S coupling_conductance(const S& stiffness_n_per_m, const S& damping_n_s_per_m, const S& theta,
                       double sample_period_s) {
    using std::tan;
    const S half_kt = stiffness_n_per_m * (sample_period_s / 2.0);
    const S resistance = damping_n_s_per_m + half_kt;
    const S reactance = half_kt / tan(theta / 2.0);
    return resistance / (resistance * resistance + reactance * reactance);
}

/// Relative margin of (21) at θ: Re(1/Z_c) / bound - 1. Equal to the Llewellyn margin of
/// (18) (tested); >= 0 means (21) holds at θ. +inf where the bound is zero.
double coupling_margin(const DeviceModel& device, const SpringDamperCoupling& coupling,
                       HoldModel model, double theta, double sample_period_s);

/// Limit of coupling_margin as θ -> 0+, where both sides of (21) vanish like θ²:
///   Re(1/Z_c) ~ (b_c + k_c T/2) θ² / (k_c T)²,  bound ~ τ² θ² / (4 b).
double coupling_margin_at_dc(const DeviceModel& device, const SpringDamperCoupling& coupling,
                             HoldModel model, double sample_period_s);

}  // namespace hapticd::theory
