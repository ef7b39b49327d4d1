// Stateless penalty (impedance) objects: tool state in, force out (the paper's impedance
// environments, Section II-A). Each is a plain struct whose evaluate() returns the force ON
// the virtual tool and its linearisation (servo/environment_port.hpp):
//   stiffness = -∂f/∂x_e,   damping = -∂f/∂v_e   (both 3x3, N/m and N s/m).
// All of them are passive: the spring, wall spring and detent are conservative (they derive
// from a potential), the dampers only dissipate, and the wall never pulls.
// evaluate() is real-time safe: no allocation, lock, log or throw.
//
// Vectors are 3-D; a scene with fewer axes leaves the unused components at zero, and so
// every force and Jacobian below stays zero there (the caller keeps them zero).
#pragma once

#include "hapticd/env/environment.hpp"

namespace hapticd::env {

/// A unilateral spring-damper wall on the half-space boundary n·x = d. `normal_in_free_space`
/// (unit) points from the wall into free space. With the penetration p = d - n·x:
///   p <= 0 (free space):  f = 0;
///   p > 0  (contact):     f = max(0, k p - b (n·v)) n.
/// The clamp makes it push only: the damper may slow an approaching tool (n·v < 0) and a
/// leaving one (n·v > 0), but it never pulls the tool back into the wall ("sticky wall").
/// Passive: with the storage U = k p²/2, the power dissipated is b (n·v)² while unclamped,
/// and (n·v) k p >= 0 while clamped (the clamp only acts when n·v > k p / b >= 0).
struct Wall {
    Vec3 normal_in_free_space{1.0, 0.0, 0.0};  ///< unit
    double offset_m = 0.0;                     ///< d of the plane n·x = d
    double stiffness_n_per_m = 0.0;            ///< k_w > 0
    double damping_n_s_per_m = 0.0;            ///< b_w >= 0

    [[nodiscard]] double penetration_m(const Vec3& tool_position_m) const noexcept;
    [[nodiscard]] PenaltyForce evaluate(const Vec3& tool_position_m,
                                        const Vec3& tool_velocity_mps) const noexcept;
};

/// A linear spring to a fixed anchor: f = -k (x - anchor). Conservative.
struct Spring {
    Vec3 anchor_m{0.0};
    double stiffness_n_per_m = 0.0;  ///< k > 0

    [[nodiscard]] PenaltyForce evaluate(const Vec3& tool_position_m,
                                        const Vec3& tool_velocity_mps) const noexcept;
};

/// A viscous field: f = -b v. Dissipative.
struct Damper {
    double damping_n_s_per_m = 0.0;  ///< b > 0

    [[nodiscard]] PenaltyForce evaluate(const Vec3& tool_position_m,
                                        const Vec3& tool_velocity_mps) const noexcept;
};

/// Detents along a unit axis a through `center_m`: with s = a·(x - center) and the period λ,
///   U(s) = F_peak λ/(2π) (1 - cos(2π s/λ)),   f = -dU/ds a = -F_peak sin(2π s/λ) a.
/// Notches (stable minima) sit at s = jλ; the stiffness at a notch is 2π F_peak/λ and it
/// turns negative (-2π F_peak/λ at worst) half-way between notches, so a servo solving the
/// coupling (17) needs k_c > 2π F_peak/λ for a unique tool position. Conservative.
/// `periodic = false` keeps one notch: the force is zero for |s| >= λ/2, where U is at its
/// maximum and f is already zero, so U and f stay continuous.
struct Detent {
    Vec3 axis{1.0, 0.0, 0.0};  ///< unit
    Vec3 center_m{0.0};
    double period_m = 0.0;      ///< λ > 0
    double peak_force_n = 0.0;  ///< F_peak > 0
    bool periodic = true;

    [[nodiscard]] PenaltyForce evaluate(const Vec3& tool_position_m,
                                        const Vec3& tool_velocity_mps) const noexcept;
};

}  // namespace hapticd::env
