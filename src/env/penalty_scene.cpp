#include "hapticd/env/penalty_scene.hpp"

#include <algorithm>
#include <utility>

namespace hapticd::env {
namespace {

void accumulate(PenaltyForce& sum, const PenaltyForce& term) noexcept {
    sum.force_n += term.force_n;
    sum.stiffness_n_per_m += term.stiffness_n_per_m;
    sum.damping_n_s_per_m += term.damping_n_s_per_m;
}

template <typename Objects>
void accumulate_all(PenaltyForce& sum, const Objects& objects, const Vec3& x,
                    const Vec3& v) noexcept {
    for (const auto& object : objects) accumulate(sum, object.evaluate(x, v));
}

}  // namespace

PenaltyScene::PenaltyScene(PenaltyObjects objects, int axes)
    : objects_(std::move(objects)), axes_(std::clamp(axes, 1, 3)) {}

PenaltyForce PenaltyScene::evaluate(const Vec3& tool_position_m,
                                    const Vec3& tool_velocity_mps) const noexcept {
    PenaltyForce sum;
    accumulate_all(sum, objects_.walls, tool_position_m, tool_velocity_mps);
    accumulate_all(sum, objects_.springs, tool_position_m, tool_velocity_mps);
    accumulate_all(sum, objects_.dampers, tool_position_m, tool_velocity_mps);
    accumulate_all(sum, objects_.detents, tool_position_m, tool_velocity_mps);
    accumulate_all(sum, objects_.frictions, tool_position_m, tool_velocity_mps);
    // Components beyond the scene's axes are zero (GLM matrices are column-major: m[col][row]).
    for (int i = axes_; i < 3; ++i) {
        sum.force_n[i] = 0.0;
        for (int j = 0; j < 3; ++j) {
            sum.stiffness_n_per_m[i][j] = sum.stiffness_n_per_m[j][i] = 0.0;
            sum.damping_n_s_per_m[i][j] = sum.damping_n_s_per_m[j][i] = 0.0;
        }
    }
    return sum;
}

void PenaltyScene::commit(const Vec3& tool_position_m, const Vec3& tool_velocity_mps) noexcept {
    for (auto& friction : objects_.frictions) friction.commit(tool_position_m, tool_velocity_mps);
}

void PenaltyScene::reset(const Vec3& tool_position_m) noexcept {
    for (auto& friction : objects_.frictions) friction.reset(tool_position_m);
}

}  // namespace hapticd::env
