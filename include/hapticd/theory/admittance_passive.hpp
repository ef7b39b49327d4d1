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

}  // namespace hapticd::theory
