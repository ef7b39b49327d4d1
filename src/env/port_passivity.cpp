#include "hapticd/env/port_passivity.hpp"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>

namespace hapticd::env {

Vec3 PortPassivity::limit(const Vec3& wanted_m, const Vec3& previous_m,
                          const Vec3& device_position_m, const Vec3& device_velocity_mps,
                          const CouplingGains& gains, double period_s) noexcept {
    acted_ = false;
    if (mode_ == PassivityMode::off) return wanted_m;
    // f_c = f0 - kappa d for the step d (the header's algebra).
    const Vec3 f0 = gains.stiffness_n_per_m * (device_position_m - previous_m) +
                    gains.damping_n_s_per_m * device_velocity_mps;
    const double kappa = gains.stiffness_n_per_m + gains.damping_n_s_per_m / period_s;
    const auto energy_of = [&](const Vec3& d) noexcept {
        return glm::dot(f0, d) - kappa * glm::dot(d, d);
    };
    // What the world's own motion in this tick would take out beyond the port's energy.
    const double motion_shortfall_j =
        std::max(0.0, -(energy_j_ + energy_of(wanted_m - previous_wanted_m_)));
    previous_wanted_m_ = wanted_m;
    Vec3 step = wanted_m - previous_m;
    const double wanted_energy_j = energy_of(step);
    if (mode_ == PassivityMode::control && kappa > 0.0 && !(energy_j_ + wanted_energy_j >= 0.0)) {
        // The point of the ball nearest the wanted step, the radius a hair inside so that the
        // energy stays >= 0 through rounding. The wanted step is outside the ball and the
        // centre inside, so the direction between them is defined.
        const Vec3 centre = f0 / (2.0 * kappa);
        const double radius =
            std::sqrt(std::max(0.0, (energy_j_ + glm::dot(f0, f0) / (4.0 * kappa)) / kappa)) *
            (1.0 - 1e-9);
        const Vec3 from_centre = step - centre;
        const double distance = std::sqrt(glm::dot(from_centre, from_centre));
        step = distance > 0.0 ? centre + from_centre * (radius / distance) : Vec3(0.0);
        if (!(energy_j_ + energy_of(step) >= 0.0)) step = Vec3(0.0);  // rounding at the edge
        acted_ = true;
        removed_j_ += motion_shortfall_j;
    }
    energy_j_ += energy_of(step);
    return previous_m + step;
}

}  // namespace hapticd::env
