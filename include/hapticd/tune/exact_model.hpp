// The `exact` stability model (docs/architecture.md §7.9, docs/stability-models.md): the
// sampled-data closed loop of the continuous device (10) under an exact zero-order hold, a
// sampled encoder and a backward-difference velocity, with the spring-damper virtual coupling
// (16), judged by the eigenvalues of the discrete closed-loop state matrix against a sweep of
// passive human operators and passive environments. It is the ground truth the `paper` and
// `encoder` models are held against.
//
// One servo tick n, as modelled (and as the runtime must implement it):
//   x_d[n]  sampled encoder position (no quantisation); the force F[n] computed from it acts
//           from t = nT + D and is held until (n+1)T + D, the exact ZOH shifted by the loop
//           delay D = (q + φ) T (q whole periods, 0 <= φ < 1; D = 0 by default). Within a
//           period the plant sees F[n-q-1] for φT, then F[n-q]: both pieces are sampled
//           exactly (two matrix exponentials);
//   v_d[n] = (x_d[n] - x_d[n-1]) / T                                     backward difference
//   F[n]   = k_c (x_d[n] - x_e[n]) + b_c (v_d[n] - v_e[n])               coupling (16)
//   or, with the damper's velocity filter (cutoff f_c > 0, theory/velocity_filter.hpp),
//   u[n]   = a u[n-1] + (1 - a) (v_d[n] - v_e[n]),   a = exp(-2π f_c T)  one more state
//   F[n]   = k_c (x_d[n] - x_e[n]) + b_c u[n]
//   the device obeys  m dv/dt + b v = F_h - F[n]  (10): positive F pushes the handle back,
//   and the same F pulls the environment toward the handle (+F on it along +x).
//
// Environments (discrete, in the tick; all passive, see Definition 2):
//   rigid wall:    x_e = v_e = 0 (persistent contact, linearised), F = k_c x_d + b_c v_d
//                  (filtered: F = k_c x_d + b_c u[n], u[n] = a u[n-1] + (1 - a) v_d[n]).
//   lossless mass-spring: m_e, k_e (and b_e) integrated by the trapezoidal rule, i.e. the
//     impedance m_e s + b_e + k_e/s with s -> (2/T)(z-1)/(z+1) on the backward-difference
//     v_e: Re Z_e = b_e on the unit circle, so with b_e = 0 it stores and returns every
//     joule (the worst passive environments are lossless; passive_model.hpp);
//   mass-spring:   virtual mass m_e on a spring k_e to ground with damper b_e, driven by F.
//     It is integrated by implicit (backward) Euler, with the coupling force taken at the
//     END of the step, i.e. solved together with the environment:
//       m_e (v_e[n] - v_e[n-1]) / T = F[n] - k_e x_e[n] - b_e v_e[n]
//       x_e[n] = x_e[n-1] + T v_e[n]
//     Substituting F[n] and x_e[n] gives the update the servo computes each tick:
//       D      = m_e + T (b_c + b_e) + T² (k_c + k_e)
//       v_e[n] = ( m_e v_e[n-1] + T [ k_c (x_d[n] - x_e[n-1]) + b_c v_d[n] - k_e x_e[n-1] ] ) / D
//       x_e[n] = x_e[n-1] + T v_e[n],   then F[n] from (16) as above.
//     With the velocity filter, F[n] = k_c (x_d[n] - x_e[n]) + (1 - a) b_c (v_d[n] - v_e[n])
//     + a b_c u[n-1]: the damper weighs this tick's velocities by (1 - a) b_c and its memory
//     a b_c u[n-1] is a known force, so the same substitution gives
//       D      = m_e + T ((1 - a) b_c + b_e) + T² (k_c + k_e)
//       v_e[n] = ( m_e v_e[n-1] + T [ k_c (x_d[n] - x_e[n-1]) + (1 - a) b_c v_d[n]
//                                     + a b_c u[n-1] - k_e x_e[n-1] ] ) / D
//       x_e[n] = x_e[n-1] + T v_e[n],   u[n] = a u[n-1] + (1 - a)(v_d[n] - v_e[n]),
//       F[n]   = k_c (x_d[n] - x_e[n]) + b_c u[n],
//     which is the unfiltered update with b_c -> (1 - a) b_c and v_d -> v_d + a u[n-1]/(1 - a):
//     what the servo hands an admittance environment (servo/environment_port.hpp), so its
//     virtual mass needs no filter of its own. The environment's admittance Y_e is unchanged.
//     This makes the environment the implicit-Euler admittance
//       Y_e(z) = 1 / ( m_e (1 - z⁻¹)/T + b_e + k_e T/(1 - z⁻¹) ),
//     which is positive real (its impedance has Re = b_e + m_e(1 - cos θ)/T + k_e T/2 on
//     the unit circle),
//     and v_e, x_e obey the same x[n] = x[n-1] + T v[n] that (16) assumes. Taking F[n-1]
//     instead (an explicit coupling force) would multiply Y_e by z⁻¹: for a pure mass that
//     has Re Y_e = -T/(2 m_e) < 0, an active environment, so it is not used.
//
// Operators (continuous, attached at the handle, passive; a set-point does not change
// stability, so springs act around 0):
//   hands-off:      nothing attached.
//   heavy hand:     mass m_h rigidly on the handle, damper b_h to ground.
//   stiff grasp:    mass m_h rigidly on the handle, spring k_h and damper b_h to ground.
//   two-mass grasp: handle --(skin k_s, b_s)-- hand mass m_h --(arm k_a, b_a)-- ground.
//   multi-mode grasp: a rigid mass m_h with k_h, b_h to ground, and absorbers on the handle,
//                   handle --(k_i, b_i)-- m_i: any lossless operator is such a network
//                   (Foster's reactance theorem, mechanically). Built by synthesis in
//                   operator_synthesis.hpp, with its modes on the aliases of a frequency.
//
// Default sweep (log-spaced grids; the zero dampings are the classic worst cases):
//   heavy hand      m_h 0.1..10 kg (9), b_h {0, 0.3, 1, 3, 10} N s/m                    45
//   stiff grasp     m_h 0.1..10 kg (5), k_h 10..1e4 N/m (7), b_h {0, 1, 10} N s/m      105
//   tuned steel grip  a stiff grasp with m_h = b_h = 0 and k_h = m (r π rate)², which
//                   makes the handle resonate at r = {1/8, 1/4, 1/2, 3/4, 0.9, 1} of the
//                   Nyquist frequency: the lossless spring cancels the device's mass
//                   reactance there, so Re(1/Z_handle) reaches its passive maximum 1/b.
//                   r = 1 is the worst passive operator for the coupling damping (at
//                   k_h ≈ 1e6 N/m for m = 0.1 kg at 1 kHz: no hand does that, but
//                   unconditional stability, Definition 4, is about every passive one)  6
//   two-mass grasp  k_s 1e2..1e5 N/m (4), b_s {0, 1, 10} N s/m, m_h 0.1..10 kg (5),
//                   k_a {0, 1e2, 1e3, 1e4} N/m, b_a {0, 10} N s/m                      480
//   plus hands-off: 637 operators.
//   environments    rigid wall, and mass-spring with m_e = m·{0.01, 0.1, 1, 10, 100}
//                   (m the device mass), k_e 1..1e6 N/m (7), b_e {0, 1, 30} N s/m:     106
//   637 x 106 = 67522 cases. The environments are grounded (k_e > 0) and the wall grounds
//   the handle through k_c, so no eigenvalue sits on the unit circle unless k_c = 0 leaves
//   the handle free (a simple z = 1).
//
// What the sweep finds (tests/tune/exact_model_test.cpp): the loop is stable against all
// of it iff, to within a fraction of a percent,
//   k_c T/2 < b + b_c           low frequency, heavy hands: the hold's half-sample delay
//                               turns k_c into a negative damping k_c T/2 (Colgate &
//                               Schenkel's k_c < 2b/T at b_c = 0);
//   k_c T/2 < (π²/8) b - b_c    z = -1, the steel grip tuned to Nyquist. The hold's two
//                               alias branches at ±π/T fold onto z = -1 and add; the
//                               `encoder` model's e^{-jθ} sinc²(θ/2) keeps one of them and
//                               allows b_c + k_c T/2 up to (π²/4) b there, twice as much.
// The `paper` model (13) allows k_c up to 8b/T at b_c = 0.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "hapticd/theory/benchmark.hpp"
#include "hapticd/theory/unit_circle.hpp"
#include "hapticd/tune/operator_model.hpp"

namespace hapticd::tune {

/// Eigenvalues of the discrete closed-loop state matrix, one tick to the next.
struct ClosedLoopPoles {
    double spectral_radius = 0.0;        ///< max |λ|; < 1 asymptotically stable
    double dominant_frequency_hz = 0.0;  ///< |arg λ|/(2π T) of the largest |λ|, 0..rate/2
    std::vector<theory::Complex> eigenvalues;
};

/// The closed loop of device + operator + coupling + environment, with a loop delay of
/// `delay_periods` (0 <= d < 10) beyond the hold. Throws std::invalid_argument naming the
/// offending value for non-physical input.
ClosedLoopPoles closed_loop_poles(const theory::DeviceModel& device,
                                  const theory::SpringDamperCoupling& coupling, double rate_hz,
                                  const OperatorModel& human, const EnvironmentModel& environment,
                                  double delay_periods = 0.0);

/// A spectral radius up to 1 + this counts as stable: the only unit-circle eigenvalue the
/// models produce is the simple z = 1 of a free handle (k_c = 0), marginal and therefore
/// stable by Definition 1. Past it, a case whose growth is under kDecisiveGrowthPerTick and
/// does not move when the coupling's gains drop by 1 % counts as marginal too: the rounding
/// of lossless modes folded onto one alias (a near-multiple eigenvalue, good to about the
/// square root of the rounding: 2e-8 per tick at 20 kHz), not a growth of the design.
inline constexpr double kMarginalTolerance = 1e-8;

/// The worst case of a sweep. When the loop is stable, worst_margin is tiny (1e-9..1e-7 for
/// the default sweep) and worst_frequency_hz belongs to a lightly damped operator mode,
/// e.g. an undamped 10 kg hand on a 100 N/m skin at 0.5 Hz, which the coupling barely
/// touches: 1 - ρ is not a distance to instability. When it is unstable, both describe the
/// growing mode (ρ per tick, its frequency).
struct ExactCheck {
    /// worst_margin >= -kMarginalTolerance, or every case past it is rounding (above).
    bool stable = false;
    /// Stable only within the tolerance (or the rounding above): worst_margin < 0. Said so
    /// wherever the check is reported; never called a margin.
    bool marginal() const { return stable && worst_margin < 0.0; }
    double worst_spectral_radius = 0.0;
    double worst_margin = 0.0;        ///< 1 - worst_spectral_radius; >= 0 stable
    double worst_frequency_hz = 0.0;  ///< dominant frequency of the worst case
    OperatorModel worst_operator;
    EnvironmentModel worst_environment;
    int cases_checked = 0;
    double delay_periods = 0.0;  ///< the loop delay the check assumed
};

/// Keeps the larger of two checks (`into` on a tie: the first case found stays the worst) and
/// adds up their cases.
void merge(ExactCheck& into, const ExactCheck& other);

/// The tuned steel grips depend on the device mass and the rate (see the file comment).
std::vector<OperatorModel> default_operator_sweep(const theory::DeviceModel& device,
                                                  double rate_hz);
/// Environment masses scale with the device mass (see the file comment).
std::vector<EnvironmentModel> default_environment_sweep(const theory::DeviceModel& device);

/// Worst case of closed_loop_poles over every operator x environment pair. The first
/// case with the largest spectral radius is reported.
ExactCheck check_exact(const theory::DeviceModel& device,
                       const theory::SpringDamperCoupling& coupling, double rate_hz,
                       const std::vector<OperatorModel>& operators,
                       const std::vector<EnvironmentModel>& environments,
                       double delay_periods = 0.0);

/// A case that grows by this much per tick (|z| - 1) ends a search for a witness: the
/// verdict is no, and it names that case (not necessarily the worst).
inline constexpr double kDecisiveGrowthPerTick = 1e-6;

/// What a search is for. The worst case: every case is checked and the worst is named (a
/// verdict). A witness: whether the design fails at all (size's operator past a proven
/// limit, a bisection's rejection); the cases built for this design go first and the first
/// that grows by kDecisiveGrowthPerTick ends the search. Where nothing grows decisively both
/// check the same cases and agree.
enum class SearchFor { worst_case, witness };

/// check_exact over the default sweep, plus the adversaries synthesised for this design
/// (operator_synthesis.hpp): the worst lossless environment at each frequency where the
/// passive bound binds (and a spread of others), met by the default operators, and
/// multi-mode grasps with their modes on the aliases of those frequencies, met by the rigid
/// wall and those environments.
ExactCheck check_exact(const theory::DeviceModel& device,
                       const theory::SpringDamperCoupling& coupling, double rate_hz,
                       double delay_periods = 0.0, SearchFor search = SearchFor::worst_case);

/// Whether a check has found a case that grows by kDecisiveGrowthPerTick.
inline bool decisive(const ExactCheck& check) {
    return check.worst_spectral_radius > 1.0 + kDecisiveGrowthPerTick;
}

}  // namespace hapticd::tune
