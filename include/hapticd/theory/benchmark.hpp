// The paper's benchmark impedance display, (10)-(21): a 1-DOF device of mass m and
// damping b, sampled with a zero-order hold, coupled to the virtual environment by the
// spring-damper virtual coupling (16).
//
// The hold term is where the stability models differ (docs/stability-models.md):
//   HoldModel::paper   ZOH(z) = (1/2)(z + 1)/z, (13) as printed;
//   HoldModel::encoder e^{-jθ/2} sinc(θ/2), the exact zero-order hold, times the same
//                      factor again for the backward-difference velocity, which averages
//                      the true velocity over the last period:  e^{-jθ} sinc²(θ/2);
//   HoldModel::passive e^{-j(1+d)θ}: the whole alias sum of the hold, Colgate and Schenkel's
//                      sampled-data passivity condition worst-cased over every passive
//                      environment (passive_model.hpp; exact for whole-period delays, and
//                      for a fraction of a period through M(θ) there).
// A loop delay of d periods beyond the hold (sample to force) multiplies the hold term by
// e^{-jdθ} for `paper` and `encoder`; `passive` treats it exactly.
// All functions take the normalised frequency θ = ωT, 0 < θ <= π.
#pragma once

#include <cmath>
#include <limits>
#include <optional>
#include <string_view>
#include <vector>

#include "hapticd/theory/passive_model.hpp"
#include "hapticd/theory/spring_damper_coupling.hpp"
#include "hapticd/theory/twoport.hpp"
#include "hapticd/theory/unit_circle.hpp"
#include "hapticd/theory/velocity_filter.hpp"

namespace hapticd::theory {

/// Device (10): m dv/dt + b v = F_h - F_d.
struct DeviceModel {
    double mass_kg = 0.0;
    double damping_n_s_per_m = 0.0;
};

/// Virtual coupling (16): a spring k_c in parallel with a damper b_c, the damper optionally
/// on a first-order low-pass of the velocity (velocity_filter.hpp). Every model takes the
/// filter through Z_c: coupling_impedance and coupling_conductance.
/// Which hold term stands in for (13).
enum class HoldModel { paper, encoder, passive };

/// "paper", "encoder", "passive".
std::string_view to_string(HoldModel model);
std::optional<HoldModel> parse_hold_model(std::string_view name);

/// A frequency-domain stability model of the impedance display: the hold term, and the
/// loop's delay beyond the hold in periods (from the encoder sample to the force taking
/// effect; 0 <= d < 10, validated by the caller). A bare HoldModel means no delay.
struct LoopModel {
    HoldModel hold = HoldModel::passive;
    double delay_periods = 0.0;
    LoopModel(HoldModel hold_model = HoldModel::passive, double delay = 0.0)  // NOLINT: implicit
        : hold(hold_model), delay_periods(delay) {}
};

/// (12): Z_dI(z) = (m s + b) with s -> (2/T)(z-1)/(z+1). Its real part is b on the
/// unit circle, which is why Tustin preserves passivity.
Complex device_impedance(const DeviceModel& device, double theta, double sample_period_s);

/// The device impedance each model uses: (12) for HoldModel::paper; for the encoder model
/// m jω + b at the true frequency, consistent with its exact (unwarped) hold term. Both
/// have real part b, so (21) is the same either way; the admittance display (29)-(30)
/// sees the difference near Nyquist, where Tustin's warping sends |Z_dI| to infinity.
Complex device_impedance(const DeviceModel& device, HoldModel model, double theta,
                         double sample_period_s);

/// (16): Z_cI(z) = b_c + k_c T z/(z - 1); with a velocity filter,
/// b_c (1 - a)/(1 - a z⁻¹) + k_c T z/(z - 1) (velocity_filter.hpp).
Complex coupling_impedance(const SpringDamperCoupling& coupling, double theta,
                           double sample_period_s);

/// The hold term: (13) for HoldModel::paper, e^{-jθ} sinc²(θ/2) for HoldModel::encoder,
/// e^{-jθ} for HoldModel::passive; times e^{-jdθ} for a delay of d periods.
Complex hold_term(const LoopModel& model, double theta);

/// (14): hybrid matrix of the sampled impedance display without a coupling.
TwoPort impedance_display(const DeviceModel& device, const LoopModel& model, double theta,
                          double sample_period_s);

/// (17): hybrid matrix of the virtual coupling network alone.
TwoPort coupling_network(const SpringDamperCoupling& coupling, double theta,
                         double sample_period_s);

/// (18): hybrid matrix of the haptic interface, display and coupling in cascade.
TwoPort impedance_interface(const DeviceModel& device, const SpringDamperCoupling& coupling,
                            const LoopModel& model, double theta, double sample_period_s);

// ---- (21) in real arithmetic ---------------------------------------------------------
// The sizing solver differentiates these with Ceres jets, so they are templates on the
// scalar type and use only +, -, *, /, sin, cos, tan, sqrt.

/// (1 - cos∠H)|H|, the numerator of the right side of (21), for the hold term H; for the
/// passive model M(θ) of passive_model.hpp, which is that with H = e^{-j(1+d)θ} when the
/// delay is a whole number of periods.
template <typename S>
S hold_bound_numerator(const LoopModel& model, const S& theta) {
    using std::cos;
    using std::sin;
    const double d = model.delay_periods;
    // 1 - cos(x) is written 2 sin²(x/2) to keep its precision as θ -> 0.
    if (model.hold == HoldModel::paper) {
        // ∠ZOH = -θ/2 - dθ, |ZOH| = cos(θ/2).
        const S s = sin((0.5 + d) * theta / 2.0);
        return 2.0 * s * s * cos(theta / 2.0);
    }
    if (model.hold == HoldModel::encoder) {
        // ∠H = -(1 + d)θ, |H| = sinc²(θ/2).
        const S s = sin((1.0 + d) * theta / 2.0);
        const S sc = sinc(S(theta / 2.0));
        return 2.0 * s * s * sc * sc;
    }
    return passive_hold_numerator(theta, d);
}

/// Group delay of the hold term in samples: the numerator of (21) behaves like τ² θ²/2 as
/// θ -> 0. τ = 1/2 + d for (13), 1 + d for the encoder model, and passive_delay_samples(d)
/// (1 with no delay) for the passive model.
double hold_delay_samples(const LoopModel& model);

/// Right side of (21): the least coupling conductance Re(1/Z_c) the device needs,
///   (1 - cos∠H)|H| / (2 Re Z_dI),  with Re Z_dI = b.
template <typename S>
S conductance_bound(const LoopModel& model, double device_damping_n_s_per_m, const S& theta) {
    return hold_bound_numerator(model, theta) / (2.0 * device_damping_n_s_per_m);
}

/// Left side of (21): Re(1/Z_cI) for the coupling (16). With z = e^{jθ},
/// z/(z-1) = 1/2 - (j/2)cot(θ/2), so Z_cI = R - jX with R = b_c + k_c T/2 and
/// X = (k_c T/2) cot(θ/2), and Re(1/Z_cI) = R/(R² + X²). With a velocity filter of cutoff
/// `velocity_filter_hz` the damper is b_c B (velocity_filter.hpp): R = b_c Re B + k_c T/2 and
/// X = (k_c T/2) cot(θ/2) - b_c Im B (Im B < 0: the filter's lag adds to the spring's
/// reactance). velocity_filter_hz = 0 is the unfiltered expression, to the bit.
template <typename S>
S coupling_conductance(const S& stiffness_n_per_m, const S& damping_n_s_per_m, const S& theta,
                       double sample_period_s, double velocity_filter_hz = 0.0) {
    using std::tan;
    const S half_kt = stiffness_n_per_m * (sample_period_s / 2.0);
    if (velocity_filter_hz > 0.0) {
        const FilterResponse<S> filter = velocity_filter_response(
            velocity_filter_pole(velocity_filter_hz, sample_period_s), theta);
        const S resistance = damping_n_s_per_m * filter.re + half_kt;
        const S reactance = half_kt / tan(theta / 2.0) - damping_n_s_per_m * filter.im;
        return resistance / (resistance * resistance + reactance * reactance);
    }
    const S resistance = damping_n_s_per_m + half_kt;
    const S reactance = half_kt / tan(theta / 2.0);
    return resistance / (resistance * resistance + reactance * reactance);
}

/// coupling_conductance of `coupling` (its gains and its velocity filter).
inline double coupling_conductance(const SpringDamperCoupling& coupling, double theta,
                                   double sample_period_s) {
    return coupling_conductance(coupling.stiffness_n_per_m, coupling.damping_n_s_per_m, theta,
                                sample_period_s, coupling.velocity_filter_hz);
}

/// The right side of (21) on an increasing grid of frequencies: conductance_bound at each,
/// with the passive model's M(θ) tabulated by passive_hold_numerators (warm-started maxima
/// for a fraction of a period of delay).
std::vector<double> conductance_bounds(const LoopModel& model, double device_damping_n_s_per_m,
                                       const std::vector<double>& thetas);

/// Re(1/Z_c) / bound - 1, +inf where the bound is zero: the relative margin of (21).
inline double relative_margin(double conductance, double bound) {
    return bound <= 0.0 ? std::numeric_limits<double>::infinity() : conductance / bound - 1.0;
}

/// Relative margin of (21) at θ: Re(1/Z_c) / bound - 1. Equal to the Llewellyn margin of
/// (18) (tested); >= 0 means (21) holds at θ. +inf where the bound is zero.
double coupling_margin(const DeviceModel& device, const SpringDamperCoupling& coupling,
                       const LoopModel& model, double theta, double sample_period_s);

/// Limit of coupling_margin as θ -> 0+, where both sides of (21) vanish like θ²:
///   Re(1/Z_c) ~ (b_c + k_c T/2) θ² / (k_c T)²,  bound ~ τ² θ² / (4 b).
/// A velocity filter does not change it: Re B = 1 - O(θ²) and Im B = O(θ) (velocity_filter.hpp),
/// so R -> the same b_c + k_c T/2 and X = k_c T/θ + O(θ).
double coupling_margin_at_dc(const DeviceModel& device, const SpringDamperCoupling& coupling,
                             const LoopModel& model, double sample_period_s);

}  // namespace hapticd::theory
