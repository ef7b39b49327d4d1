// What the servo tick needs from a virtual environment, in the two causalities of the paper
// (Section II-A). The env layer implements these (env/environment.hpp); the servo layer
// only sees the shapes below, so it does not depend on env.
//
//   Impedance (penalty based): tool state in, force out. The coupling (16) is in series with
//     it, (17): the servo solves for the massless virtual tool x_e such that
//         k_c (x_d - x_e) + b_c (v_d - v_e) + f_env(x_e, v_e) = 0,
//     with v_e = (x_e - x_e[n-1])/T, using the force and Jacobian from evaluate(); then it
//     calls commit() once with the solution.
//   Admittance (constraint based): force in, position out, (22). step() is handed the
//     device state and the coupling gains and returns the tool position x_e (the god-object
//     returns the constrained point nearest x_d; a virtual mass integrates the coupling
//     force implicitly, with the update written out in tune/exact_model.hpp).
//     With a velocity filter (CouplingGains::velocity_filter_hz) the coupling force is
//     k_c (x_d - x_e) + (1 - a) b_c (v_d - v_e) + a b_c u[n-1], still affine in x_e; the
//     coupling hands step() the unfiltered coupling with the same force in this tick:
//     damping (1 - a) b_c, no filter, and the velocity v_d + a u[n-1]/(1 - a) in place of
//     v_d, so that an environment never sees the filter (VirtualCoupling::step).
//
// Sign convention: every force here is the force ON the virtual tool, in newtons, along
// +x/+y/+z. The coupling's force on the tool is k_c (x_d - x_e) + b_c (v_d - v_e); the force
// on the device handle is its negative. Positions in metres, velocities in m/s.
//
// Real-time contract: evaluate(), commit() and step() run inside the servo tick: no
// allocation, lock, log or throw.
#pragma once

#include <concepts>
#include <cstdint>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include "hapticd/theory/spring_damper_coupling.hpp"

namespace hapticd::servo {

using Vec3 = glm::dvec3;
using Mat3 = glm::dmat3;

/// The coupling (16) gains, the same on every axis: the theory's own type, plain data.
using CouplingGains = theory::SpringDamperCoupling;

/// A penalty force on the tool and its linearisation at the evaluated state.
struct PenaltyForce {
    Vec3 force_n{0.0};            ///< f_env on the tool, N
    Mat3 stiffness_n_per_m{0.0};  ///< -∂f/∂x_e (positive definite for a restoring wall)
    Mat3 damping_n_s_per_m{0.0};  ///< -∂f/∂v_e
};

/// What an environment with a port of its own to watch reports each tick (an external world:
/// env/external_environment.hpp), for the status and the summary. `external` false: nothing.
struct EnvironmentPortReport {
    bool external = false;
    std::uint32_t world_state = 0;       ///< 0 waiting for the world, 1 live, 2 stale
    std::uint64_t update = 0;            ///< the world's update in force (its count)
    std::uint64_t stale_episodes = 0;    ///< times the world went stale
    std::uint64_t rejected_updates = 0;  ///< updates refused (a value not finite)
    double since_update_s = 0.0;         ///< servo time since that update came, s
    double energy_j = 0.0;               ///< the port's energy E[n] since the last reset, J
    double energy_removed_j = 0.0;       ///< what the passivity controller took, J
};

template <typename E>
concept ImpedancePort = requires(E& e, const E& ce, const Vec3& x, const Vec3& v) {
    { ce.evaluate(x, v) } -> std::same_as<PenaltyForce>;
    {e.commit(x, v)};
    {e.reset(x)};
};

template <typename E>
concept AdmittancePort = requires(E& e, const Vec3& x, const Vec3& v, const CouplingGains& g,
                                  double period_s) {
    { e.step(x, v, g, period_s) } -> std::same_as<Vec3>;
    {e.reset(x)};
};

}  // namespace hapticd::servo
