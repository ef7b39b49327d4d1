#include "hapticd/env/virtual_mass.hpp"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <utility>

namespace hapticd::env {
namespace {

bool finite(const Vec3& v) noexcept {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Relative slack for rounding in the passivity check, J per J stored.
constexpr double kEnergyRoundingSlack = 1e-12;

}  // namespace

VirtualMass::VirtualMass(const VirtualMassParameters& parameters, ConstraintSet constraints,
                         int axes)
    : parameters_(parameters), constraints_(std::move(constraints)), axes_(std::clamp(axes, 1, 3)) {
    parameters_.anchor_m = mask(parameters_.anchor_m);
    reset(parameters_.anchor_m);
}

Vec3 VirtualMass::mask(const Vec3& v) const noexcept {
    Vec3 out = v;
    for (int i = axes_; i < 3; ++i) out[i] = 0.0;
    return out;
}

double VirtualMass::energy_j(const Vec3& x, const Vec3& v) const noexcept {
    const Vec3 stretch_m = x - parameters_.anchor_m;
    return 0.5 * parameters_.mass_kg * glm::dot(v, v) +
           0.5 * parameters_.stiffness_n_per_m * glm::dot(stretch_m, stretch_m);
}

double VirtualMass::energy_j() const noexcept { return energy_j(position_m_, velocity_mps_); }

Vec3 VirtualMass::step(const Vec3& device_position_m, const Vec3& device_velocity_mps,
                       const CouplingGains& gains, double period_s) noexcept {
    if (!finite(device_position_m) || !finite(device_velocity_mps) || !(period_s > 0.0)) {
        return position_m_;
    }
    const Vec3 x_d = mask(device_position_m);
    const Vec3 v_d = mask(device_velocity_mps);
    const double T = period_s;
    const double m_e = parameters_.mass_kg;
    const double k_e = parameters_.stiffness_n_per_m;
    const double b_e = parameters_.damping_n_s_per_m;
    const double k_c = gains.stiffness_n_per_m;
    const double b_c = gains.damping_n_s_per_m;
    const Vec3 x_prev = position_m_;
    const Vec3 v_prev = velocity_mps_;

    // Implicit Euler with the coupling force at the end of the step (tune/exact_model.hpp).
    const double D = m_e + T * (b_c + b_e) + T * T * (k_c + k_e);
    Vec3 v = (m_e * v_prev +
              T * (k_c * (x_d - x_prev) + b_c * v_d - k_e * (x_prev - parameters_.anchor_m))) /
             D;
    Vec3 x = x_prev + T * v;

    // Inelastic constraints: project out, drop the velocity into the surface.
    for (int round = 0; round < kProjectionRounds && !constraints_.is_free(x); ++round) {
        for (const auto& plane : constraints_.planes) {
            if (gap_m(plane, x) >= 0.0) continue;
            x = project_to_surface(plane, x);
            const Vec3 n = free_normal(plane, x);
            v -= std::min(0.0, glm::dot(v, n)) * n;
        }
        for (const auto& sphere : constraints_.spheres) {
            if (gap_m(sphere, x) >= 0.0) continue;
            x = project_to_surface(sphere, x);
            const Vec3 n = free_normal(sphere, x);
            v -= std::min(0.0, glm::dot(v, n)) * n;
        }
    }
    x = mask(x);
    v = mask(v);

    // Passivity, checked against the work the coupling force did this step. A projection
    // onto a curved surface moves the mass along a chord, against the force pressing it on,
    // and can leave it with slightly more energy than it was given: take that excess out of
    // its kinetic energy (a little friction along curved walls). If that is not enough, or
    // the constraints are still violated, stop the mass where it was.
    const double energy_prev_j = energy_j(x_prev, v_prev);
    const double slack_j = kEnergyRoundingSlack * (energy_prev_j + 1e-9);
    auto excess_j = [&](const Vec3& v_now) {
        const Vec3 coupling_force_n = k_c * (x_d - x) + b_c * (v_d - v_now);
        return energy_j(x, v_now) - energy_prev_j - glm::dot(coupling_force_n, x - x_prev);
    };
    const double excess = excess_j(v);
    const double kinetic_j = 0.5 * m_e * glm::dot(v, v);
    if (excess > slack_j && kinetic_j > 0.0) {
        v *= std::sqrt(std::max(0.0, 1.0 - excess / kinetic_j));
    }
    if (!constraints_.is_free(x) || excess_j(v) > slack_j || !finite(x) || !finite(v)) {
        x = x_prev;
        v = Vec3(0.0);
        ++stopped_steps_;
    }
    position_m_ = x;
    velocity_mps_ = v;
    return position_m_;
}

void VirtualMass::reset(const Vec3& position_m) noexcept {
    velocity_mps_ = Vec3(0.0);
    if (!finite(position_m)) return;
    Vec3 start = mask(position_m);
    if (constraints_.project_to_free(start) || !constraints_.is_free(position_m_)) {
        position_m_ = mask(start);
    }
}

}  // namespace hapticd::env
