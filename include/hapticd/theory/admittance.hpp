// The benchmark admittance display, (27)-(43): the device under a PI velocity loop (27),
// force measured at the handle, coupled to the environment by the series mass-damper
// coupling (32). It is the dual of the impedance display (Table I).
#pragma once

#include "hapticd/theory/benchmark.hpp"

namespace hapticd::theory {

/// (27): F_d* = K_PI(z)(v_d* - v_com*), K_PI(z) = k_p + k_i T z/(z - 1).
struct PiVelocityLoop {
    double proportional_gain_n_s_per_m = 0.0;
    double integral_gain_n_per_m = 0.0;
};

/// (32): a virtual mass m_c in series with a damper b_c. b_c = +inf is a pure mass.
struct MassDamperCoupling {
    double mass_kg = 0.0;
    double damping_n_s_per_m = 0.0;
};

Complex pi_gain(const PiVelocityLoop& loop, double theta, double sample_period_s);

/// (29): T(z) = H K_PI / (Z_dI + H K_PI), the velocity loop's complementary sensitivity,
/// with the hold term H of `model` in place of ZOH(z).
Complex velocity_tracking(const DeviceModel& device, const PiVelocityLoop& loop, HoldModel model,
                          double theta, double sample_period_s);

/// (30): Z_dA = Z_dI + K_PI H, the display's driving-point impedance at the human port.
Complex admittance_display_impedance(const DeviceModel& device, const PiVelocityLoop& loop,
                                     HoldModel model, double theta, double sample_period_s);

/// (28): alternate hybrid matrix of the admittance display without a coupling.
TwoPort admittance_display(const DeviceModel& device, const PiVelocityLoop& loop, HoldModel model,
                           double theta, double sample_period_s);

/// (32): Y_cA(z) = 1/b_c + T z/((z - 1) m_c); Z_cA = 1/Y_cA.
Complex coupling_admittance(const MassDamperCoupling& coupling, double theta,
                            double sample_period_s);

/// (34): alternate hybrid matrix of the display with the coupling (33) in cascade.
TwoPort admittance_interface(const DeviceModel& device, const PiVelocityLoop& loop,
                             const MassDamperCoupling& coupling, HoldModel model, double theta,
                             double sample_period_s);

/// Right side of (37): (1 - cos∠T)|T| / (2 Re(1/Z_dA)). +inf where Re(1/Z_dA) <= 0 and the
/// numerator is positive: there (35) fails and no coupling can help.
double admittance_coupling_bound(const DeviceModel& device, const PiVelocityLoop& loop,
                                 HoldModel model, double theta, double sample_period_s);

/// Re(1/Z_dA), the display's conductance; (35) needs it >= 0 at every frequency.
double admittance_display_conductance(const DeviceModel& device, const PiVelocityLoop& loop,
                                      HoldModel model, double theta, double sample_period_s);

}  // namespace hapticd::theory
