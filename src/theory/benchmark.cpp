#include "hapticd/theory/benchmark.hpp"

#include <limits>

namespace hapticd::theory {

std::string_view to_string(HoldModel model) {
    switch (model) {
        case HoldModel::paper:
            return "paper";
        case HoldModel::encoder:
            return "encoder";
        case HoldModel::passive:
            return "passive";
    }
    return "unknown";
}

std::optional<HoldModel> parse_hold_model(std::string_view name) {
    for (HoldModel model : {HoldModel::paper, HoldModel::encoder, HoldModel::passive}) {
        if (name == to_string(model)) return model;
    }
    return std::nullopt;
}

Complex device_impedance(const DeviceModel& device, double theta, double sample_period_s) {
    const Complex s = tustin_s(unit_circle_point(theta), sample_period_s);
    return device.mass_kg * s + device.damping_n_s_per_m;  // (12)
}

Complex device_impedance(const DeviceModel& device, HoldModel model, double theta,
                         double sample_period_s) {
    if (model == HoldModel::paper) return device_impedance(device, theta, sample_period_s);
    return Complex(device.damping_n_s_per_m, device.mass_kg * theta / sample_period_s);
}

Complex coupling_impedance(const SpringDamperCoupling& coupling, double theta,
                           double sample_period_s) {
    const Complex z = unit_circle_point(theta);
    const Complex s = backward_difference_s(z, sample_period_s);
    if (coupling.velocity_filter_hz > 0.0) {
        // The damper on the filtered velocity: b_c (1 - a)/(1 - a z⁻¹) (velocity_filter.hpp).
        const double a = velocity_filter_pole(coupling.velocity_filter_hz, sample_period_s);
        return coupling.damping_n_s_per_m * (1.0 - a) / (1.0 - a / z) +
               coupling.stiffness_n_per_m / s;
    }
    return coupling.damping_n_s_per_m + coupling.stiffness_n_per_m / s;  // (16)
}

Complex hold_term(const LoopModel& model, double theta) {
    const Complex z = unit_circle_point(theta);
    const Complex delay = std::polar(1.0, -model.delay_periods * theta);
    if (model.hold == HoldModel::paper) return 0.5 * (z + 1.0) / z * delay;  // (13)
    if (model.hold == HoldModel::passive) return std::polar(1.0, -theta) * delay;
    const double s = sinc(theta / 2.0);
    return std::polar(s * s, -theta) * delay;
}

double hold_delay_samples(const LoopModel& model) {
    switch (model.hold) {
        case HoldModel::paper:
            return 0.5 + model.delay_periods;
        case HoldModel::encoder:
            return 1.0 + model.delay_periods;
        case HoldModel::passive:
            break;
    }
    return passive_delay_samples(model.delay_periods);
}

TwoPort impedance_display(const DeviceModel& device, const LoopModel& model, double theta,
                          double sample_period_s) {
    // (14): [F_h, -v_d*] = [[Z_dI, ZOH], [-1, 0]] [v_h, F_d*].
    return {ImmittanceForm::hybrid, device_impedance(device, model.hold, theta, sample_period_s),
            hold_term(model, theta), -1.0, 0.0};
}

TwoPort coupling_network(const SpringDamperCoupling& coupling, double theta,
                         double sample_period_s) {
    // (17): [F_d*, -v_e*] = [[0, 1], [-1, 1/Z_cI]] [v_d*, F_e*].
    return {ImmittanceForm::hybrid, 0.0, 1.0, -1.0,
            1.0 / coupling_impedance(coupling, theta, sample_period_s)};
}

TwoPort impedance_interface(const DeviceModel& device, const SpringDamperCoupling& coupling,
                            const LoopModel& model, double theta, double sample_period_s) {
    // (18): the cascade of (14) and (17) changes only the lower-right term.
    TwoPort network = impedance_display(device, model, theta, sample_period_s);
    network.p22 = 1.0 / coupling_impedance(coupling, theta, sample_period_s);
    return network;
}

double coupling_margin(const DeviceModel& device, const SpringDamperCoupling& coupling,
                       const LoopModel& model, double theta, double sample_period_s) {
    const double bound = conductance_bound(model, device.damping_n_s_per_m, theta);
    return relative_margin(coupling_conductance(coupling, theta, sample_period_s), bound);
}

std::vector<double> conductance_bounds(const LoopModel& model, double device_damping_n_s_per_m,
                                       const std::vector<double>& thetas) {
    std::vector<double> bounds;
    bounds.reserve(thetas.size());
    for (double theta : thetas) {
        bounds.push_back(conductance_bound(model, device_damping_n_s_per_m, theta));
    }
    return bounds;
}

double coupling_margin_at_dc(const DeviceModel& device, const SpringDamperCoupling& coupling,
                             const LoopModel& model, double sample_period_s) {
    const double k_t = coupling.stiffness_n_per_m * sample_period_s;
    if (k_t <= 0.0) return std::numeric_limits<double>::infinity();  // a damper alone
    const double tau = hold_delay_samples(model);
    const double resistance = coupling.damping_n_s_per_m + k_t / 2.0;
    return 4.0 * device.damping_n_s_per_m * resistance / (k_t * k_t * tau * tau) - 1.0;
}

}  // namespace hapticd::theory
