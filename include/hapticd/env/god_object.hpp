// The god-object / proxy (Zilles & Salisbury 1995, the paper's [5]; Ruspini et al. 1997,
// [6]): an admittance environment, (22), whose tool position x_e is the point of free
// space nearest the device position x_d, reached by sliding from the previous proxy along
// the constraint surfaces, so that it never tunnels through a thin object.
//
// One step (all in 3-D; a scene with fewer axes keeps the other components at zero):
//   repeat (at most kMaxIterations):
//     contacts  = the constraints the proxy touches (gap <= kContactTolerance_m), each as
//                 its tangent half-space (a plane is its own; a sphere's is exact to first
//                 order);
//     target    = the point nearest x_d in the intersection of the contact half-spaces
//                 (active-set projection: none, one plane, an edge of two, a corner of
//                 three; the KKT point with non-negative multipliers);
//     stop when the target is the proxy;
//     move the proxy toward the target and stop at the first surface the segment enters
//     (that surface becomes a contact); a spherical cavity left by a tangent move is
//     re-entered radially;
//     a move whose end is not in free space is shortened, and if that fails refused.
// The proxy therefore never leaves free space: every accepted position is checked.
// Curved surfaces converge over a few iterations; what is left is finished next tick.
//
// The coupling gains and period are not needed: a massless proxy is where the constraints
// put it. step() is real-time safe (no allocation, lock, log or throw).
#pragma once

#include "hapticd/env/constraints.hpp"
#include "hapticd/env/environment.hpp"

namespace hapticd::env {

class GodObject final : public AdmittanceEnvironment {
  public:
    static constexpr int kMaxIterations = 16;
    /// Contacts beyond this many at one point are ignored for the target (the move is
    /// still checked against every constraint).
    static constexpr int kMaxContacts = 6;

    /// `axes` in 1..3. The proxy starts at the free point nearest the origin.
    explicit GodObject(ConstraintSet constraints, int axes = 3);

    Vec3 step(const Vec3& device_position_m, const Vec3& device_velocity_mps,
              const CouplingGains& gains, double period_s) noexcept override;
    void reset(const Vec3& position_m) noexcept override;

    [[nodiscard]] const Vec3& proxy_m() const noexcept { return proxy_m_; }
    /// Iterations the last step used (diagnostics, benchmarks).
    [[nodiscard]] int last_iterations() const noexcept { return last_iterations_; }
    [[nodiscard]] const ConstraintSet& constraints() const noexcept { return constraints_; }
    [[nodiscard]] int axes() const noexcept { return axes_; }

  private:
    Vec3 mask(const Vec3& v) const noexcept;

    ConstraintSet constraints_;
    int axes_;
    Vec3 proxy_m_{0.0};
    int last_iterations_ = 0;
};

}  // namespace hapticd::env
