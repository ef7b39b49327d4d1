// The `passive` model of the admittance display: Colgate and Schenkel's sampled-data argument
// (passive_model.hpp) carried to the force-sensing display of (27)-(43), with the continuous
// operator's velocity folded onto its aliases. Derivation in docs/stability-models.md
// ("The admittance display"); in short, with z = e^{jθ}, θ_k = θ + 2πk, and the handle's
// total impedance Z_k = b + j m ω_k + Z_h(jω_k) at the signed alias ω_k = θ_k/T (u_k = 1/Z_k
// fills the disk |u - 1/(2b)| <= 1/(2b) over every passive operator), the tick's signals are
//   v_d*  = -F* e^{-j(1+q)θ} Σ_k s_k u_k,          s_k = 4 sin²(θ/2)/θ_k²,  Σ s_k = 1
//   F_h*  =  F* e^{-jqθ} [ c_h - (1 - e^{-jθ}) Σ_k (m/T + b/(jθ_k)) u_k ],
//            c_h = (1 + e^{-jθ})/2 - μ (1 - e^{-jθ})/2   (the sample at nT⁻; μ = m_h/(m + m_h)
//            for a rigid hand mass m_h, whose inertia makes F_h jump with the held force),
// and the loop F* = K_PI (v_d* - Y_v F_h*), Y_v = 1/(Z_cA + Z_e), sits on the unit circle at
// e^{jθ} exactly when
//   R = Σ_k β_k u_k,   R = 1 + G c_h,   β_k = K_PI e^{-jqθ} [Y_v (1 - e^{-jθ})(m/T + b/(jθ_k))
//                                                     - e^{-jθ} s_k],   G = K_PI Y_v e^{-jqθ}.
// Two consequences, both tight (the exact model reaches them):
//   (P1) at a rigid wall (Y_v = 0) the display is the impedance display with the controller
//        K_PI on the encoder, and it is unconditionally stable iff b >= λ(-K_PI e^{-j(1+q)θ})
//        at every θ (port_damping_needed): with no delay b >= k_p + k_i T/2. This is (35),
//        Re(1/Z_dA) >= 0, with the whole alias sum in place of the hold term;
//   (P2) with Y_v != 0 the force sample weighs every alias alike: β_k -> β_∞ = G (1 - e^{-jθ})
//        m/T as |k| grows, so the values Σ β_k u_k fill the half-plane Re(conj(β̂_∞) w) >=
//        -δ/(2b), δ = Σ_k (|β_k| - Re(conj(β̂_∞) β_k)), and a passive operator with enough
//        free-handle resonances on the aliases reaches R unless Re(conj(β̂_∞) R) < -δ/(2b).
//        In free space (Y_v = Y_cA) that fails for every coupling (32), PI gain and delay: as
//        θ -> 0, Re(conj(β_∞) R) -> -(m/T) θ Im G, and K_PI and Y_cA both lag (Im < 0), so
//        Im G < 0 (a pure damper with k_i = 0 has G real there; with no delay it fails at
//        Nyquist instead, where R = 1 and G(-1) = k_p/b_c > 0, and with q periods where
//        Im G = -(k_p/b_c) sin qθ < 0).
// So no admittance display that samples its force sensor without an anti-aliasing filter is
// unconditionally stable for every passive operator. What remains finite is how many
// resonances it takes: a resonant alias (u_k = 1/b) moves Σ β_k u_k by Re(conj(β̂_∞) β_k)/b
// along β̂_∞, so reaching R takes N(θ) of them, the fewest whose moves add up to
// Re(conj(β̂_∞) R); a heavier coupling mass raises N. At Nyquist the exact loop's alias-tuned
// operators (every resonance at reactance 0) go unstable at exactly that N (tests/tune);
// elsewhere N is an estimate, and they cross within two of it (the non-resonant aliases they
// leave add a little).
#pragma once

#include "hapticd/theory/admittance.hpp"
#include "hapticd/theory/force_sensor_filter.hpp"

namespace hapticd::theory {

/// (P1): the least device damping that keeps the display stable at a rigid wall against
/// every passive operator at θ: λ(-K_PI(e^{jθ}) e^{-j(1+q)θ}) (port_damping_needed).
double velocity_loop_damping_needed(const PiVelocityLoop& loop, double theta,
                                    double sample_period_s, double delay_periods);

/// (P1) over every frequency: b >= this (k_p + k_i T/2 for whole periods of delay q = 0;
/// found on a grid of 4096 frequencies otherwise).
double velocity_loop_damping_bound(const PiVelocityLoop& loop, double sample_period_s,
                                   double delay_periods);

/// (P2) in free space at θ, whole periods of delay q, operators without a rigid hand (μ = 0).
struct AliasReach {
    /// Re(conj(β̂_∞) R) + δ/(2b): >= 0 means a passive operator with resonances on enough
    /// aliases of θ puts a closed-loop pole on the unit circle at e^{jθ}.
    double reach = 0.0;
    /// N(θ): how many resonant aliases (signed: θ + 2πk, k in Z) that takes; 0 when R is not
    /// on β_∞'s side at all.
    double resonant_aliases_needed = 0.0;
};
AliasReach free_space_alias_reach(const DeviceModel& device, const PiVelocityLoop& loop,
                                  const MassDamperCoupling& coupling, double theta,
                                  double sample_period_s, int whole_periods);

// ---- (P2) with an anti-aliasing filter on the force sensor (force_sensor_filter.hpp) ----
// The filtered force is sampled at nT (continuous: no jump), so at alias k the sensor part of
// β_k gains H_k = H_aa(jω_k), the term without u_k becomes the filter's hold equivalent, and
// a fraction φ of a period of delay puts e_k = e^{-jθ_k φ} on every alias:
//   R = 1 + G H_hold,   β_k = K_PI e^{-jqθ} e_k [Y_v (1 - e^{-jθ}) H_k (m/T + b/(jθ_k))
//                                                 - e^{-jθ} s_k],   G = K_PI Y_v e^{-jqθ}.
// Over every passive operator Σ β_k u_k fills the disk centred c = Σ β_k/(2b) with radius
// ρ = Σ |β_k|/(2b) (a Minkowski sum of the aliases' disks), so no passive operator puts a pole
// at e^{jθ} iff |R - c| > ρ. With a second-order filter |β_k| ~ 1/k² and the sums converge
// (the first N = 64.. aliases summed, the rest bounded: force_filter_alias_tail and Σ s_k = 1);
// with a first-order one |β_k| ~ 1/k and ρ = ∞. R, c and the β_k are affine in Y_v, which fills
// the disk of environment_admittance_disk over every passive environment; the margin
//   f(Y) = |R - c| - ρ
// is minimised over that disk by branch and bound (lower bound on a square: the affine |R - c|
// at its centre less |dR/dY - dc/dY| times the half-diagonal, ρ at its centre plus
// Σ |dβ_k/dY|/(2b) times it, and twice the tail).

/// {1/(Z_cA + Z_e) : Re Z_e >= 0} at θ: the disk centred (and of radius) 1/(2 Re Z_cA) on the
/// positive real axis; it holds the rigid wall (0) and free space (Y_cA). Re Z_cA grows with
/// m_c (and with b_c), so a heavier coupling's disk lies inside a lighter one's.
struct EnvironmentAdmittanceDisk {
    double centre = 0.0;  ///< m/(N s), real
    double radius = 0.0;
};
EnvironmentAdmittanceDisk environment_admittance_disk(const MassDamperCoupling& coupling,
                                                      double theta, double sample_period_s);

struct FilteredAliasMargin {
    /// A certified lower bound of min over the disk of f = |R - c| - ρ (tails included); > 0
    /// means no passive operator and environment puts a pole at e^{jθ}.
    double margin = 0.0;
    /// f (truncated sums) at the best point found; margin <= it, within the tolerance when
    /// the search ran to the end.
    double value_at_worst = 0.0;
    std::complex<double> worst_admittance;  ///< Y_v there (m/(N s))
    int evaluations = 0;
};

/// The margin at θ over the disk. decide_only stops as soon as the sign is settled (margin
/// > 0 proved, or a point with f + tails <= 0 found); otherwise the minimum to `tolerance`
/// (absolute, on the dimensionless margin; at most max_evaluations, after which the bound
/// found so far is returned: lower, never optimistic).
/// Throws std::invalid_argument for an unsupported filter.
FilteredAliasMargin filtered_alias_margin(const DeviceModel& device, const PiVelocityLoop& loop,
                                          const ForceSensorFilter& filter,
                                          const EnvironmentAdmittanceDisk& disk, double theta,
                                          double sample_period_s, double delay_periods,
                                          bool decide_only = false, double tolerance = 1e-7,
                                          int max_evaluations = 20000);

/// The large-|Y_v| slope of the margin at θ: |dR/dY - dc/dY| - Σ |dβ_k/dY|/(2b) (first N
/// aliases). f(Y) <= |Y| slope + f(0) + ..., so where it is negative a large enough |Y_v| fails.
/// As θ -> 0 it tends to -θ |K_PI| (m/(2bT)) Σ_{k != 0} |H_aa(j2πk/T)| (to first order), while a
/// coupling with finite m_c lets |Y_v| reach 1/Re Z_cA ~ 2T/(m_c θ²): every finite coupling
/// mass fails at low enough frequency, against a virtual spring resonating with it.
double filtered_alias_slope(const DeviceModel& device, const PiVelocityLoop& loop,
                            const ForceSensorFilter& filter, double theta, double sample_period_s,
                            double delay_periods);

struct FilteredPassiveCheck {
    bool holds = false;  ///< margin > 0 at every frequency checked (and at DC, below)
    double worst_margin = 0.0;
    double worst_frequency_hz = 0.0;
    std::complex<double> worst_admittance;  ///< the binding environment's Y_v
    /// A finite m_c with a negative slope at θ = 1e-6 rad: fails as θ -> 0 (the grid's
    /// lowest frequency may not reach it; filtered_alias_slope).
    bool fails_at_dc = false;
    int frequencies = 0;
};

/// (P2) with the filter over every passive operator and environment, on θ in (0, π]: 4096
/// uniform points, 256 log-spaced from 1e-6 rad to the first, and 64 between the neighbours of
/// the worst. With stop_at_failure each frequency only settles the sign and the first failing
/// one ends the sweep (for a bisection); otherwise each is bounded with 400 evaluations (a
/// lower bound), and the worst once more to 1e-7.
FilteredPassiveCheck check_filtered_admittance_passive(const DeviceModel& device,
                                                       const PiVelocityLoop& loop,
                                                       const ForceSensorFilter& filter,
                                                       const MassDamperCoupling& coupling,
                                                       double sample_period_s, double delay_periods,
                                                       bool stop_at_failure = false);

}  // namespace hapticd::theory
