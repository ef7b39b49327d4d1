// A virtual mass with rigid constraints: an admittance environment, (22). The mass m_e,
// with an optional spring k_e to an anchor and a damper b_e to ground, is driven by the
// coupling (16) and integrated by implicit Euler together with it, exactly as the update in
// tune/exact_model.hpp (per axis, with the anchor a):
//   D      = m_e + T (b_c + b_e) + T² (k_c + k_e)
//   v_e[n] = ( m_e v_e[n-1] + T [ k_c (x_d[n] - x_e[n-1]) + b_c v_d[n] - k_e (x_e[n-1] - a) ] ) / D
//   x_e[n] = x_e[n-1] + T v_e[n]
// which is the positive-real admittance 1/(m_e (1 - z⁻¹)/T + b_e + k_e T/(1 - z⁻¹)).
//
// Then the constraints (planes, spheres; constraints.hpp), inelastically: a violated
// surface projects the position back onto it and removes the velocity's component into
// it (the tangential part is kept). With the anchor in free space and convex constraints
// (planes, spherical cavities) both projections are non-expansive, so the stored energy
//   E = m_e |v_e|²/2 + k_e |x_e - a|²/2
// never grows by them. Every step is also checked against the work the coupling force did,
//   E[n] - E[n-1] <= F[n]·(x_e[n] - x_e[n-1]),   F[n] = k_c (x_d - x_e[n]) + b_c (v_d - v_e[n]),
// which implicit Euler satisfies with room to spare (it dissipates b_e T v² + m_e Δv²/2 +
// k_e Δx²/2). A projection onto a curved surface moves the mass along a chord, against
// the force pressing it on, and can break it slightly: the excess is taken out of the
// kinetic energy (a little friction along curved walls). If that is not enough, or the
// constraints are still violated after a few rounds, the mass stops where it was
// (x_e[n] = x_e[n-1], v_e[n] = 0), which satisfies the check and is in free space. So the
// mass is passive and never leaves free space, by construction.
//
// step() is real-time safe (no allocation, lock, log or throw).
#pragma once

#include "hapticd/env/constraints.hpp"
#include "hapticd/env/environment.hpp"

namespace hapticd::env {

struct VirtualMassParameters {
    double mass_kg = 0.0;            ///< m_e > 0
    double stiffness_n_per_m = 0.0;  ///< k_e >= 0, to the anchor
    double damping_n_s_per_m = 0.0;  ///< b_e >= 0, to ground
    Vec3 anchor_m{0.0};              ///< a
};

class VirtualMass final : public AdmittanceEnvironment {
  public:
    static constexpr int kProjectionRounds = 4;

    /// `axes` in 1..3. The mass starts at rest at the free point nearest the anchor.
    VirtualMass(const VirtualMassParameters& parameters, ConstraintSet constraints, int axes = 3);

    Vec3 step(const Vec3& device_position_m, const Vec3& device_velocity_mps,
              const CouplingGains& gains, double period_s) noexcept override;
    /// At rest at the free point nearest `position_m`.
    void reset(const Vec3& position_m) noexcept override;

    [[nodiscard]] const Vec3& position_m() const noexcept { return position_m_; }
    [[nodiscard]] const Vec3& velocity_mps() const noexcept { return velocity_mps_; }
    /// The stored energy E above, J.
    [[nodiscard]] double energy_j() const noexcept;
    /// Steps where the passivity check stopped the mass (diagnostics).
    [[nodiscard]] long stopped_steps() const noexcept { return stopped_steps_; }
    [[nodiscard]] const VirtualMassParameters& parameters() const noexcept { return parameters_; }
    [[nodiscard]] const ConstraintSet& constraints() const noexcept { return constraints_; }

  private:
    [[nodiscard]] double energy_j(const Vec3& x, const Vec3& v) const noexcept;
    [[nodiscard]] Vec3 mask(const Vec3& v) const noexcept;

    VirtualMassParameters parameters_;
    ConstraintSet constraints_;
    int axes_;
    Vec3 position_m_{0.0};
    Vec3 velocity_mps_{0.0};
    long stopped_steps_ = 0;
};

}  // namespace hapticd::env
