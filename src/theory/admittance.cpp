#include "hapticd/theory/admittance.hpp"

#include <cmath>
#include <limits>

namespace hapticd::theory {

Complex pi_gain(const PiVelocityLoop& loop, double theta, double sample_period_s) {
    const Complex s = backward_difference_s(unit_circle_point(theta), sample_period_s);
    return loop.proportional_gain_n_s_per_m + loop.integral_gain_n_per_m / s;
}

Complex velocity_tracking(const DeviceModel& device, const PiVelocityLoop& loop, HoldModel model,
                          double theta, double sample_period_s) {
    const Complex forward = hold_term(model, theta) * pi_gain(loop, theta, sample_period_s);
    return forward / (device_impedance(device, model, theta, sample_period_s) + forward);  // (29)
}

Complex admittance_display_impedance(const DeviceModel& device, const PiVelocityLoop& loop,
                                     HoldModel model, double theta, double sample_period_s) {
    return device_impedance(device, model, theta, sample_period_s) +
           pi_gain(loop, theta, sample_period_s) * hold_term(model, theta);  // (30)
}

TwoPort admittance_display(const DeviceModel& device, const PiVelocityLoop& loop, HoldModel model,
                           double theta, double sample_period_s) {
    // (28): [v_h, F_meas*] = [[1/Z_dA, -T], [1, 0]] [F_h, -v_com*].
    return {ImmittanceForm::alternate_hybrid,
            1.0 / admittance_display_impedance(device, loop, model, theta, sample_period_s),
            -velocity_tracking(device, loop, model, theta, sample_period_s), 1.0, 0.0};
}

Complex coupling_admittance(const MassDamperCoupling& coupling, double theta,
                            double sample_period_s) {
    const Complex s = backward_difference_s(unit_circle_point(theta), sample_period_s);
    return 1.0 / coupling.damping_n_s_per_m + 1.0 / (coupling.mass_kg * s);  // (32)
}

TwoPort admittance_interface(const DeviceModel& device, const PiVelocityLoop& loop,
                             const MassDamperCoupling& coupling, HoldModel model, double theta,
                             double sample_period_s) {
    // (34): only the lower-right term changes from (28).
    TwoPort network = admittance_display(device, loop, model, theta, sample_period_s);
    network.p22 = 1.0 / coupling_admittance(coupling, theta, sample_period_s);
    return network;
}

double admittance_display_conductance(const DeviceModel& device, const PiVelocityLoop& loop,
                                      HoldModel model, double theta, double sample_period_s) {
    return (1.0 / admittance_display_impedance(device, loop, model, theta, sample_period_s)).real();
}

double admittance_coupling_bound(const DeviceModel& device, const PiVelocityLoop& loop,
                                 HoldModel model, double theta, double sample_period_s) {
    const Complex t = velocity_tracking(device, loop, model, theta, sample_period_s);
    // 1 - cos∠T = 2 sin²(∠T/2), kept precise as θ -> 0.
    const double half_angle_sine = std::sin(std::arg(t) / 2.0);
    const double numerator = 2.0 * half_angle_sine * half_angle_sine * std::abs(t);
    const double conductance =
        admittance_display_conductance(device, loop, model, theta, sample_period_s);
    if (conductance <= 0.0) {
        return numerator > 0.0 ? std::numeric_limits<double>::infinity() : 0.0;
    }
    return numerator / (2.0 * conductance);  // (37)
}

}  // namespace hapticd::theory
