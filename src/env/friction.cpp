#include "hapticd/env/friction.hpp"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

namespace hapticd::env {

PenaltyForce StickSlipFriction::evaluate(const Vec3& tool_position_m,
                                         const Vec3& /*tool_velocity_mps*/) const noexcept {
    PenaltyForce out;
    const Vec3 stretch_m = tool_position_m - anchor_m;
    const double stretch_length_m = glm::length(stretch_m);
    const double limit_n = slipping ? kinetic_limit_n() : static_limit_n();
    if (stiffness_n_per_m * stretch_length_m <= limit_n) {  // stuck
        out.force_n = -stiffness_n_per_m * stretch_m;
        out.stiffness_n_per_m = Mat3(stiffness_n_per_m);
        return out;
    }
    // Slipping: |f| = F_k along -ẑ. ∂ẑ/∂x = (I - ẑẑᵀ)/|z|.
    const Vec3 direction = stretch_m / stretch_length_m;
    const double kinetic_n = kinetic_limit_n();
    out.force_n = -kinetic_n * direction;
    out.stiffness_n_per_m =
        (kinetic_n / stretch_length_m) * (Mat3(1.0) - glm::outerProduct(direction, direction));
    return out;
}

void StickSlipFriction::commit(const Vec3& tool_position_m,
                               const Vec3& /*tool_velocity_mps*/) noexcept {
    const Vec3 stretch_m = tool_position_m - anchor_m;
    const double stretch_length_m = glm::length(stretch_m);
    const double limit_n = slipping ? kinetic_limit_n() : static_limit_n();
    if (stiffness_n_per_m * stretch_length_m <= limit_n) {
        slipping = false;
        return;
    }
    slipping = true;
    // Drag the anchor along z until the spring carries exactly F_k.
    const double slipped_stretch_m = kinetic_limit_n() / stiffness_n_per_m;
    anchor_m = tool_position_m - (slipped_stretch_m / stretch_length_m) * stretch_m;
}

void StickSlipFriction::reset(const Vec3& tool_position_m) noexcept {
    anchor_m = tool_position_m;
    slipping = false;
}

}  // namespace hapticd::env
