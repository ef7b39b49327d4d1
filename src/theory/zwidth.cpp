#include "hapticd/theory/zwidth.hpp"

namespace hapticd::theory {

Complex perceived_impedance(const DeviceModel& device, const SpringDamperCoupling& coupling,
                            const LoopModel& model, Complex environment_impedance, double theta,
                            double sample_period_s) {
    const Complex zc = coupling_impedance(coupling, theta, sample_period_s);
    return device_impedance(device, model.hold, theta, sample_period_s) +
           zc * hold_term(model, theta) * environment_impedance / (zc + environment_impedance);
}

Complex impedance_display_zmin(const DeviceModel& device, const LoopModel& model, double theta,
                               double sample_period_s) {
    return device_impedance(device, model.hold, theta, sample_period_s);
}

Complex impedance_display_zmax(const DeviceModel& device, const SpringDamperCoupling& coupling,
                               const LoopModel& model, double theta, double sample_period_s) {
    return device_impedance(device, model.hold, theta, sample_period_s) +
           coupling_impedance(coupling, theta, sample_period_s) * hold_term(model, theta);
}

Complex perceived_admittance(const DeviceModel& device, const PiVelocityLoop& loop,
                             const MassDamperCoupling& coupling, HoldModel model,
                             Complex environment_admittance, double theta, double sample_period_s) {
    const Complex zca = 1.0 / coupling_admittance(coupling, theta, sample_period_s);
    return 1.0 / admittance_display_impedance(device, loop, model, theta, sample_period_s) +
           velocity_tracking(device, loop, model, theta, sample_period_s) * environment_admittance /
               (1.0 + zca * environment_admittance);
}

Complex admittance_display_zmin(const DeviceModel& device, const PiVelocityLoop& loop,
                                const MassDamperCoupling& coupling, HoldModel model, double theta,
                                double sample_period_s) {
    const Complex zca = 1.0 / coupling_admittance(coupling, theta, sample_period_s);
    const Complex zda = admittance_display_impedance(device, loop, model, theta, sample_period_s);
    return zca / (velocity_tracking(device, loop, model, theta, sample_period_s) + zca / zda);
}

Complex admittance_display_zmax(const DeviceModel& device, const PiVelocityLoop& loop,
                                HoldModel model, double theta, double sample_period_s) {
    return admittance_display_impedance(device, loop, model, theta, sample_period_s);
}

}  // namespace hapticd::theory
