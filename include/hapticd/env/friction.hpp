// Stick-slip friction as a stiction spring to a sliding anchor (the "spring-anchor" model
// of Hayward & Armstrong and of Salcudean & Vlaar's static friction, with Karnopp's two
// limits). The tool is tied to an anchor w by a stiff spring k_f, z = x - w:
//   sticking: f = -k_f z while |k_f z| <= F_limit;
//   slipping: the anchor is dragged behind the tool so that |f| = F_k = μ_k N, f = -F_k ẑ.
// F_limit is the static limit F_s = μ_s N while stuck and the kinetic limit F_k while
// slipping, so the force breaks away at F_s, drops to F_k, and the tool re-sticks (limit
// back to F_s) as soon as it no longer stretches the spring past F_k. N is a fixed normal
// force (a parameter of the object, not a contact force).
// The anchor is the state: evaluate() reads it, commit() moves it. Passive: the stored
// energy is k_f |z|²/2 and the anchor only ever moves to shorten z (never stores energy).
// Isotropic in the scene's axes (the unused components of x stay zero, and so does z).
//
// Note for the coupling solve (17): at break-away the force drops from F_s to F_k, a
// discontinuity; the solve may land on either side, both of which are physical.
#pragma once

#include "hapticd/env/environment.hpp"

namespace hapticd::env {

struct StickSlipFriction {
    double normal_force_n = 0.0;       ///< N > 0
    double static_coefficient = 0.0;   ///< μ_s > 0
    double kinetic_coefficient = 0.0;  ///< 0 < μ_k <= μ_s
    double stiffness_n_per_m = 0.0;    ///< k_f > 0, the stiction spring

    // State (set by reset/commit).
    Vec3 anchor_m{0.0};
    bool slipping = false;

    [[nodiscard]] double static_limit_n() const noexcept {
        return static_coefficient * normal_force_n;
    }
    [[nodiscard]] double kinetic_limit_n() const noexcept {
        return kinetic_coefficient * normal_force_n;
    }
    [[nodiscard]] PenaltyForce evaluate(const Vec3& tool_position_m,
                                        const Vec3& tool_velocity_mps) const noexcept;
    /// Accept the tick's tool position: the anchor slips if the spring exceeds the limit.
    void commit(const Vec3& tool_position_m, const Vec3& tool_velocity_mps) noexcept;
    /// Stuck, with the anchor at the tool.
    void reset(const Vec3& tool_position_m) noexcept;
};

}  // namespace hapticd::env
