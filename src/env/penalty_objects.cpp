#include "hapticd/env/penalty_objects.hpp"

#include <cmath>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <numbers>

namespace hapticd::env {

double Wall::penetration_m(const Vec3& tool_position_m) const noexcept {
    return offset_m - glm::dot(normal_in_free_space, tool_position_m);
}

PenaltyForce Wall::evaluate(const Vec3& tool_position_m,
                            const Vec3& tool_velocity_mps) const noexcept {
    PenaltyForce out;
    const double penetration = penetration_m(tool_position_m);
    if (penetration <= 0.0) return out;
    const Vec3& n = normal_in_free_space;
    const double normal_velocity_mps = glm::dot(n, tool_velocity_mps);
    const double push_n = stiffness_n_per_m * penetration - damping_n_s_per_m * normal_velocity_mps;
    if (push_n <= 0.0) return out;  // would pull: the wall lets go instead
    out.force_n = push_n * n;
    const Mat3 nnT = glm::outerProduct(n, n);
    out.stiffness_n_per_m = stiffness_n_per_m * nnT;
    out.damping_n_s_per_m = damping_n_s_per_m * nnT;
    return out;
}

PenaltyForce Spring::evaluate(const Vec3& tool_position_m,
                              const Vec3& /*tool_velocity_mps*/) const noexcept {
    PenaltyForce out;
    out.force_n = -stiffness_n_per_m * (tool_position_m - anchor_m);
    out.stiffness_n_per_m = Mat3(stiffness_n_per_m);
    return out;
}

PenaltyForce Damper::evaluate(const Vec3& /*tool_position_m*/,
                              const Vec3& tool_velocity_mps) const noexcept {
    PenaltyForce out;
    out.force_n = -damping_n_s_per_m * tool_velocity_mps;
    out.damping_n_s_per_m = Mat3(damping_n_s_per_m);
    return out;
}

PenaltyForce Detent::evaluate(const Vec3& tool_position_m,
                              const Vec3& /*tool_velocity_mps*/) const noexcept {
    PenaltyForce out;
    const double s_m = glm::dot(axis, tool_position_m - center_m);
    if (!periodic && std::abs(s_m) >= 0.5 * period_m) return out;
    const double wavenumber_per_m = 2.0 * std::numbers::pi / period_m;
    const double phase = wavenumber_per_m * s_m;
    out.force_n = -peak_force_n * std::sin(phase) * axis;
    out.stiffness_n_per_m =
        (peak_force_n * wavenumber_per_m * std::cos(phase)) * glm::outerProduct(axis, axis);
    return out;
}

}  // namespace hapticd::env
