// Virtual environments: abstract bases for the two causalities whose shapes the servo tick
// expects (servo/environment_port.hpp explains the physics, the sign convention and the
// real-time contract). Scenes (env/scene.hpp) build concrete ones.
#pragma once

#include <string_view>

#include "hapticd/servo/environment_port.hpp"

namespace hapticd::env {

using servo::CouplingGains;
using servo::Mat3;
using servo::PenaltyForce;
using servo::Vec3;

class ImpedanceEnvironment {
  public:
    virtual ~ImpedanceEnvironment() = default;
    /// f_env at a trial tool state; the solver may call it several times per tick.
    virtual PenaltyForce evaluate(const Vec3& tool_position_m,
                                  const Vec3& tool_velocity_mps) const noexcept = 0;
    /// Accept the solved tool state of this tick (friction anchors, detent state...).
    virtual void commit(const Vec3& tool_position_m, const Vec3& tool_velocity_mps) noexcept = 0;
    /// Forget all state; the tool starts at `tool_position_m`.
    virtual void reset(const Vec3& tool_position_m) noexcept = 0;
    /// The environment failed in this tick or before (a plugin's world: plugin_environment.hpp);
    /// the servo raises the fault `environment`. A reset clears it.
    virtual bool failed() const noexcept { return false; }
    /// Why it failed, for the journal, the status and the summary ("" when not).
    virtual std::string_view failure() const noexcept { return {}; }
    /// The port's report (an external world's); none for hapticd's own objects.
    virtual servo::EnvironmentPortReport port_report() const noexcept { return {}; }
};
static_assert(servo::ImpedancePort<ImpedanceEnvironment>);

class AdmittanceEnvironment {
  public:
    virtual ~AdmittanceEnvironment() = default;
    /// One tick: the tool position x_e for the device at x_d moving at v_d (backward
    /// difference), with the coupling gains and the period T.
    virtual Vec3 step(const Vec3& device_position_m, const Vec3& device_velocity_mps,
                      const CouplingGains& gains, double period_s) noexcept = 0;
    /// Forget all state; the tool starts at the constrained point nearest `position_m`.
    virtual void reset(const Vec3& position_m) noexcept = 0;
    /// As ImpedanceEnvironment::failed().
    virtual bool failed() const noexcept { return false; }
    virtual std::string_view failure() const noexcept { return {}; }
    /// As ImpedanceEnvironment::port_report().
    virtual servo::EnvironmentPortReport port_report() const noexcept { return {}; }
};
static_assert(servo::AdmittancePort<AdmittanceEnvironment>);

}  // namespace hapticd::env
