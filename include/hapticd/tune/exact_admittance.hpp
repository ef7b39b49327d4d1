// The `exact` stability model of the admittance display (27)-(43): the sampled-data closed
// loop of the continuous device (10) under an exact zero-order hold, a force sensor at the
// handle sampled each tick, a PI velocity loop (27) on the backward-difference velocity, and
// the series mass-damper coupling (32) with a virtual environment, judged by the eigenvalues
// of the discrete closed-loop state matrix against a sweep of passive human operators (the
// impedance display's OperatorModel, exact_model.hpp) and passive virtual environments.
//
// Signs (the paper's): the device obeys (10) m dv/dt + b v = F_h - F_d, F_h the force the
// operator applies to the handle (what the force sensor reads), F_d the actuator's force as
// in (27), positive opposing +x. With the operator's force -Z_h v on the handle,
//   F_h = m dv/dt + b v + F_d  =  -m_h a - b_h v - k_h x - Σ_i [k_i (x - x_i) + b_i (v - v_i)]
// for the rigid-hand families (a = dv/dt), -k_s (x - x_h) - b_s (v - v_h) for the two-mass
// grasp, and 0 hands-off: with a force sensor a hands-off operator gives F_h = 0, the virtual
// side is not driven, and the device runs open-loop under the PI loop.
//
// One servo tick n, as modelled (and as the runtime implements it: read, compute, write):
//   x_d[n]    the encoder position at t = nT;
//   F_h[n]    the force sensor at t = nT⁻, before the new command: a rigid hand mass m_h makes
//             it depend on the force being held then, F[n-q-1] (through a = dv/dt):
//               F_h[n] = C_h s[n] + D_h F[n-q-1],   D_h = m_h/(m + m_h) for a rigid hand;
//             with a force-sensor filter H_aa the plant gains its states x_f, driven by the
//             continuous F_h = C_h s + D_h F_d(t), ẋ_f = A_f x_f + B_f F_h, and the sensor reads
//             F_f[n] = C_f x_f(nT) (continuous: no feedthrough);
//   v_d[n]  = (x_d[n] - x_d[n-1]) / T                                backward difference
//   v_com[n]  from the coupling (32) and the environment, solved together in the tick: both
//             share the velocity v_com (the coupling is a shunt element, (33)/(38)), and the
//             measured force divides between them, F_h = F_c + F_e:
//               coupling (32) as a difference equation, Y_cA(z) = 1/b_c + T z/((z - 1) m_c):
//                 v_com[n] = F_c[n]/b_c + u[n],   u[n] = u[n-1] + (T/m_c) F_c[n]
//                 (u the coupling mass's velocity, implicit Euler as (32)'s s -> (z-1)/(Tz));
//               environment as an impedance on v_com, F_e[n] = z_e v_com[n] + r[n-1]
//                 (r a linear function of the environment's memory, below);
//             so with g = 1/b_c + T/m_c (the coupling's compliance per tick),
//                 v_com[n] = (g F_h[n] - g r[n-1] + u[n-1]) / (1 + g z_e).
//             This realises v_com = F_h / (Z_cA(z) + Z_e(z)), the paper's (39) terminated
//             (Y_P = 1/Z_dA + T/(Z_cA + Z_e)).
//   e[n]    = v_d[n] - v_com[n],   I[n] = I[n-1] + T e[n]
//   F[n]    = k_p e[n] + k_i I[n]                                    (27), K_PI = k_p + k_i T
//   z/(z-1) F[n] acts on [nT + D, (n+1)T + D), D = (q + φ) T (q whole periods, 0 <= φ < 1), the
//   exact ZOH shifted by the loop delay, sampled exactly (two matrix exponentials for φ > 0), as in
//   the impedance exact model.
//
// Environments (all passive; z_e and r as above):
//   free space       F_e = 0 (z_e = 0): the operator feels the coupling alone, (41)-(42);
//                    the paper's worst case for the admittance display (section IV, 4).
//   rigid wall       v_com = 0 (Z_e = ∞): the coupling drops out, the PI loop holds the
//                    handle, the operator feels Z_dA (43).
//   mass-spring      m_e dv_e/dt = F_e - b_e v_e - k_e x_e by implicit Euler on v_e = v_com:
//                      z_e = m_e/T + b_e + k_e T,  r = -(m_e/T) v_e[n-1] + k_e x_e[n-1],
//                      x_e[n] = x_e[n-1] + T v_com[n]
//                    Z_e(z) = m_e (1 - z⁻¹)/T + b_e + k_e T/(1 - z⁻¹), positive real; k_e = 0
//                    is the virtual mass of env/virtual_mass.
//   lossless mass-spring  the trapezoidal impedance m_e s + b_e + k_e/s, s -> (2/T)(z-1)/(z+1)
//                    (Re Z_e = b_e on the unit circle: with b_e = 0 it stores and returns
//                    every joule, and realises any reactance at one frequency; the adversary
//                    synthesis of operator_synthesis.hpp builds them):
//                      F_m[n] = -F_m[n-1] + (2 m_e/T)(v_com[n] - v_com[n-1]),
//                      x_e[n] = x_e[n-1] + (T/2)(v_com[n] + v_com[n-1]),
//                      z_e = 2m_e/T + b_e + k_e T/2,
//                      r = -F_m[n-1] - (2m_e/T) v_com[n-1] + k_e (x_e[n-1] + (T/2) v_com[n-1]).
//   The memory a case does not need is left out (no u for a pure damper m_c = ∞, no x_e for
//   k_e = 0, no I for k_i = 0): a state that integrates without feeding back would add a
//   spurious eigenvalue at z = 1, and a coasting virtual mass with such an integrator would
//   make it a Jordan block, which rounding splits into 1 ± 1e-8.
//
// Closed loop: the state (s[n], x_d[n-1], I[n-1], u[n-1], environment memory, F[n-1], ...,
// F[n-q-1]) one tick on is linear; its eigenvalues decide. An operator that does not ground
// the handle (no k_h, no arm spring) leaves the loop invariant under a translation of every
// position (plant positions and x_d[n-1]): that eigenvalue z = 1 (where the handle sits) is
// deflated exactly before the eigenvalues are taken, and is not reported.
//
// Default sweep: the impedance exact model's operators (default_operator_sweep: hands-off,
// heavy hands, stiff grasps, steel grips tuned to fractions of Nyquist, two-mass grasps), and
// environments free space, rigid wall, virtual masses m_e = m·{0.01, 0.1, 1, 10, 100} (k_e = 0,
// b_e {0, 1, 30} N s/m) and mass-springs with k_e 1..1e6 N/m (7), b_e {0, 30} N s/m.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "hapticd/servo/rate.hpp"
#include "hapticd/theory/admittance.hpp"
#include "hapticd/theory/force_sensor_filter.hpp"
#include "hapticd/tune/exact_model.hpp"

namespace hapticd::tune {

/// A passive virtual environment of the admittance display (update in the file comment).
struct AdmittanceEnvironment {
    enum class Kind { free_space, rigid_wall, mass_spring, lossless_mass_spring };
    Kind kind = Kind::free_space;
    double mass_kg = 0.0;            ///< m_e >= 0
    double stiffness_n_per_m = 0.0;  ///< k_e >= 0
    double damping_n_s_per_m = 0.0;  ///< b_e >= 0

    static AdmittanceEnvironment free_space();
    static AdmittanceEnvironment rigid_wall();
    /// Implicit Euler (the servo's own virtual masses): dissipative.
    static AdmittanceEnvironment mass_spring(double mass_kg, double stiffness_n_per_m,
                                             double damping_n_s_per_m = 0.0);
    /// Trapezoidal rule: lossless when b_e = 0.
    static AdmittanceEnvironment lossless_mass_spring(double mass_kg, double stiffness_n_per_m,
                                                      double damping_n_s_per_m = 0.0);
    /// The same environment as the impedance display's (rigid wall, or a mass-spring with the
    /// same discretisation and so the same Z_e(z)).
    static AdmittanceEnvironment from(const EnvironmentModel& environment);

    /// For example "virtual mass (m_e = 2 kg, b_e = 0 N s/m)".
    std::string describe() const;
};

/// An admittance-display design: the device, its PI velocity loop (27), the coupling (32),
/// the servo rate, and the loop delay beyond the hold in periods.
struct AdmittanceDesign {
    theory::DeviceModel device;
    theory::PiVelocityLoop loop;
    theory::MassDamperCoupling coupling;  ///< m_c, b_c in (0, ∞], not both ∞
    double rate_hz = servo::kDefaultRateHz;
    double delay_periods = 0.0;  ///< 0 <= d < kMaxDelayPeriods
    /// An analog low-pass on the force sensor (force_sensor_filter.hpp), none by default: its
    /// two states (one for order 1) are driven by F_h and sampled with the plant by the same
    /// matrix exponential, and the sensor reads the filter's output at nT.
    std::optional<theory::ForceSensorFilter> force_filter = std::nullopt;
};

/// The closed loop of device + operator + force sensor + PI loop + coupling + environment.
/// The translation mode z = 1 of a handle no operator spring grounds is deflated (file
/// comment). Throws std::invalid_argument naming the offending value for non-physical input.
ClosedLoopPoles admittance_closed_loop_poles(const AdmittanceDesign& design,
                                             const OperatorModel& human,
                                             const AdmittanceEnvironment& environment);

/// The worst case of a sweep (as ExactCheck for the impedance display).
struct AdmittanceExactCheck {
    bool stable = false;  ///< worst_margin >= -kMarginalTolerance
    double worst_spectral_radius = 0.0;
    double worst_margin = 0.0;        ///< 1 - worst_spectral_radius
    double worst_frequency_hz = 0.0;  ///< dominant frequency of the worst case
    OperatorModel worst_operator;
    AdmittanceEnvironment worst_environment;
    int cases_checked = 0;
    double delay_periods = 0.0;
};

/// Free space, rigid wall, virtual masses and mass-springs scaled by the device mass (file
/// comment).
std::vector<AdmittanceEnvironment> default_admittance_environment_sweep(
    const theory::DeviceModel& device);

/// Worst case over every operator x environment pair; the first case with the largest
/// spectral radius is reported.
AdmittanceExactCheck check_exact_admittance(const AdmittanceDesign& design,
                                            const std::vector<OperatorModel>& operators,
                                            const std::vector<AdmittanceEnvironment>& environments);

/// check_exact_admittance over default_operator_sweep and the default environments.
AdmittanceExactCheck check_exact_admittance(const AdmittanceDesign& design);

}  // namespace hapticd::tune
