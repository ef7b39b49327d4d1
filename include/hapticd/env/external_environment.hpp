// An external world (docs/external-worlds.md): another process renders the virtual world at its
// own rate through the shared memory of external_world.h, as an admittance environment (22):
// it reads the handle and the coupling's force, and writes where its tool is. Each tick:
//
//   1. In lockstep (lockstep_every = N > 0), every N-th step publishes the handle and waits for
//      the world's answer to it (at most lockstep_timeout_s; after a timeout the tick stops
//      waiting, and asks without waiting, until the world answers again).
//   2. The world's newest update, when a consistent copy of its block can be had at once (the
//      tick never waits for it), with every value finite.
//   3. The tool the world wants at this tick: the update held, or extrapolated along the
//      world's tool velocity (given, or the last two updates') since it came; before the first
//      update, the handle (no force). After stale_after_s without an update the world is stale:
//      the tool holds where it was and is led onto the handle over ramp_s, so that the
//      coupling's force ramps to zero; a new update makes the world live again.
//   4. The passivity controller on the port (port_passivity.hpp): the tool the coupling
//      renders is the nearest to the wanted one that keeps the port passive, so that whatever
//      the world does between and at its updates (a hold, a delay, negative damping, a jump)
//      it delivers no net energy, and the certified gains hold for it.
//   5. The step published: the handle, the tool rendered, the coupling's force on it, the
//      energy the controller has removed, and the world's state.
//
// Staleness is counted in the servo's ticks (their intervals summed), not the host's clock: a
// virtual-time run judges it the same on any host. Real time: step() allocates, locks and
// logs nothing; it waits only in lockstep, by design, polling the channel.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "hapticd/env/environment.hpp"
#include "hapticd/env/external_channel.hpp"
#include "hapticd/env/port_passivity.hpp"

namespace hapticd::env {

/// What the coupling sees between the world's updates.
enum class BetweenUpdates {
    hold,         ///< the update's position, held (a zero-order hold at the world's rate)
    extrapolate,  ///< the update's position moved on at its velocity (first order)
};
const char* to_string(BetweenUpdates between) noexcept;

/// A scene's [external] table (docs/scenes.md, "A world at its own rate").
struct ExternalSpec {
    BetweenUpdates between_updates = BetweenUpdates::extrapolate;
    double stale_after_s = 0.1;  ///< no update for this long: stale
    double ramp_s = 0.2;         ///< stale: the force ramps to zero over this long
    std::uint32_t lockstep_every = 0;
    double lockstep_timeout_s = 10.0;
    PassivityMode passivity = PassivityMode::control;
};

/// Where the world stands, for the status and the summary.
enum class WorldState : std::uint32_t {
    waiting = HAPTICD_WORLD_WAITING,
    live = HAPTICD_WORLD_LIVE,
    stale = HAPTICD_WORLD_STALE,
};
const char* to_string(WorldState state) noexcept;

class ExternalEnvironment final : public AdmittanceEnvironment {
  public:
    /// `stop`: a lockstep wait ends when it is set (the daemon's stop flag; may be null).
    ExternalEnvironment(const ExternalSpec& spec, std::unique_ptr<ExternalChannel> channel,
                        int axes, const std::atomic<bool>* stop);

    Vec3 step(const Vec3& device_position_m, const Vec3& device_velocity_mps,
              const CouplingGains& gains, double period_s) noexcept override;
    void reset(const Vec3& position_m) noexcept override;
    servo::EnvironmentPortReport port_report() const noexcept override;

    const ExternalSpec& spec() const noexcept { return spec_; }
    const ExternalChannel& channel() const noexcept { return *channel_; }
    ExternalChannel& channel() noexcept { return *channel_; }
    WorldState state() const noexcept { return state_; }
    const PortPassivity& passivity() const noexcept { return passivity_; }

  private:
    void wait_for_answer() noexcept;
    void take_update() noexcept;
    Vec3 wanted_tool(const Vec3& device_position_m) noexcept;
    void publish(const Vec3& device_position_m, const Vec3& device_velocity_mps,
                 const CouplingGains& gains, double period_s) noexcept;

    ExternalSpec spec_;
    std::unique_ptr<ExternalChannel> channel_;
    int axes_;
    const std::atomic<bool>* stop_;
    PortPassivity passivity_;

    std::uint64_t step_ = 0;
    double time_s_ = 0.0;
    std::uint64_t unanswered_ = 0;  ///< lockstep: the step that asked and has no answer yet
    bool lockstep_waits_ = true;    ///< false after a timeout, until the world answers again
    WorldState state_ = WorldState::waiting;

    // The world's newest update, and the one before (for a velocity it did not give).
    std::uint64_t update_ = 0;
    Vec3 world_position_m_{0.0};
    Vec3 world_velocity_mps_{0.0};
    double world_time_s_ = 0.0;  ///< its own clock, or NaN
    double arrived_s_ = 0.0;     ///< time_s_ when it came
    std::uint64_t stale_episodes_ = 0;
    std::uint64_t rejected_updates_ = 0;
    Vec3 stale_from_m_{0.0};  ///< where the tool was when the world went stale
    double stale_since_s_ = 0.0;

    Vec3 tool_m_{0.0};   ///< the tool rendered last step
    Vec3 force_n_{0.0};  ///< the coupling's force on it
};

}  // namespace hapticd::env
