#include "hapticd/tune/environment_assumption.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "hapticd/theory/frequency_grid.hpp"
#include "hapticd/theory/passive_model.hpp"
#include "hapticd/tune/input_checks.hpp"

namespace hapticd::tune {

using theory::Complex;

std::string EnvironmentAssumption::describe() const {
    if (every_passive()) return "every passive environment";
    std::ostringstream out;
    out << "the scene " << scene_name << "'s " << scene.size()
        << (scene.size() == 1 ? " environment: " : " environments: ");
    for (std::size_t i = 0; i < scene.size(); ++i) {
        out << (i ? "; " : "") << scene[i].source << " (" << scene[i].model.describe() << ")";
    }
    return out.str();
}

EnvironmentImpedance environment_impedance(const EnvironmentModel& e, double theta,
                                           double period_s) {
    if (e.kind == EnvironmentModel::Kind::rigid_wall) return {true, {}};
    const Complex z_inv = std::polar(1.0, -theta);
    const Complex difference = (1.0 - z_inv) / period_s;  // the backward difference's "s"
    if (e.kind == EnvironmentModel::Kind::mass_spring) {
        // Implicit Euler: m_e s_b + b_e + k_e/s_b with s_b = (1 - z⁻¹)/T.
        return {false,
                e.mass_kg * difference + e.damping_n_s_per_m + e.stiffness_n_per_m / difference};
    }
    // Trapezoidal: m_e s_t + b_e + k_e/s_t, s_t = (2/T)(1 - z⁻¹)/(1 + z⁻¹), on the same
    // velocity (the recurrence in exact_model.cpp).
    const Complex s = 2.0 / period_s * (1.0 - z_inv) / (1.0 + z_inv);
    return {false, e.mass_kg * s + e.damping_n_s_per_m + e.stiffness_n_per_m / s};
}

Complex port_impedance(const theory::SpringDamperCoupling& coupling, const EnvironmentModel& e,
                       double theta, double period_s) {
    const Complex zc = theory::coupling_impedance(coupling, theta, period_s);
    const EnvironmentImpedance ze = environment_impedance(e, theta, period_s);
    if (ze.rigid) return zc;
    const Complex sum = zc + ze.impedance;
    if (std::abs(sum) == 0.0) return {0.0, 0.0};
    return zc * ze.impedance / sum;
}

SceneCheck check_passive_scene(const theory::DeviceModel& device,
                               const theory::SpringDamperCoupling& coupling, double rate_hz,
                               const std::vector<SceneEnvironment>& scene, double delay_periods,
                               int points) {
    check_device(device);
    check_rate(rate_hz);
    check_coupling_gains(coupling);
    check_delay_periods(delay_periods);
    if (scene.empty()) throw std::invalid_argument("check_passive_scene: the scene is empty");
    if (points < 16) throw std::invalid_argument("check_passive_scene: points must be >= 16");
    const double period = 1.0 / rate_hz;
    SceneCheck check;
    check.delay_periods = delay_periods;
    check.damping_needed = -1.0;
    const std::vector<double> grid = theory::frequency_grid(points);
    for (const SceneEnvironment& env : scene) {
        const auto needed = [&](double theta) {
            return theory::port_damping_needed(port_impedance(coupling, env.model, theta, period),
                                               theta, delay_periods);
        };
        // The worst frequency: a grid resolving the low band and Nyquist, then golden section.
        const theory::GridMinimum worst =
            theory::minimize_on_grid([&](double theta) { return -needed(theta); }, grid);
        if (-worst.value > check.damping_needed) {
            check.damping_needed = -worst.value;
            check.worst_frequency_hz = theory::frequency_hz(worst.theta, period);
            check.worst_environment = env.source + " (" + env.model.describe() + ")";
        }
    }
    check.damping_needed = std::max(check.damping_needed, 0.0);
    const double b = device.damping_n_s_per_m;
    check.margin = (b - check.damping_needed) / b;
    check.stable = check.margin >= 0.0;
    return check;
}

}  // namespace hapticd::tune
