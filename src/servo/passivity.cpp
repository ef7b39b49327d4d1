#include "hapticd/servo/passivity.hpp"

#include <algorithm>
#include <glm/geometric.hpp>

namespace hapticd::servo {

Vec3 PassivityObserver::control(const Vec3& handle_force_n, const Vec3& handle_velocity_mps,
                                double period_s) noexcept {
    damping_n_s_per_m_ = 0.0;
    if (settings_.mode != PassivityMode::control) return handle_force_n;
    // Energy after this tick if the force were commanded unchanged.
    const double predicted_j = energy_j_ - glm::dot(handle_force_n, handle_velocity_mps) * period_s;
    const double speed_squared = glm::dot(handle_velocity_mps, handle_velocity_mps);
    if (predicted_j >= 0.0 || speed_squared < settings_.min_speed_mps * settings_.min_speed_mps) {
        return handle_force_n;
    }
    // alpha |v|^2 T dissipates exactly the deficit -predicted_j.
    const double alpha =
        std::min(-predicted_j / (speed_squared * period_s), settings_.max_damping_n_s_per_m);
    damping_n_s_per_m_ = alpha;
    return handle_force_n - alpha * handle_velocity_mps;
}

void PassivityObserver::record(const Vec3& commanded_handle_force_n,
                               const Vec3& handle_velocity_mps, double period_s) noexcept {
    if (settings_.mode == PassivityMode::off) return;
    energy_j_ -= glm::dot(commanded_handle_force_n, handle_velocity_mps) * period_s;
}

}  // namespace hapticd::servo
