// A force source that the servo loop plays on the handle open loop, in place of the virtual
// coupling and the environment (ServoLoop::play_open_loop; docs/architecture.md §3.6): the
// control socket's `identify`, which plays the excitation of `hapticd --identify`
// (env/excitation.hpp) on a running daemon of either causality.
//
// It has the impedance port of environment_port.hpp, so that VirtualCoupling::step_rigid
// hands evaluate()'s force straight to the handle: evaluate() at the handle's state, commit()
// once per tick that played it, reset() where the handle is when it starts (and after any
// break in the position history). done() says it has nothing left to play; the loop then
// lets go of it. All four run on the servo thread and must be real-time safe.
#pragma once

#include "hapticd/servo/environment_port.hpp"

namespace hapticd::servo {

class OpenLoopSource {
  public:
    virtual ~OpenLoopSource() = default;
    /// The force on the handle at its position and velocity, N.
    [[nodiscard]] virtual PenaltyForce evaluate(const Vec3& handle_position_m,
                                                const Vec3& handle_velocity_mps) const noexcept = 0;
    /// This tick's handle state, after evaluate().
    virtual void commit(const Vec3& handle_position_m,
                        const Vec3& handle_velocity_mps) noexcept = 0;
    /// The history starts again at `handle_position_m`.
    virtual void reset(const Vec3& handle_position_m) noexcept = 0;
    /// Nothing left to play: from the next tick on the loop lets go.
    [[nodiscard]] virtual bool done() const noexcept = 0;
};
static_assert(ImpedancePort<OpenLoopSource>);

}  // namespace hapticd::servo
