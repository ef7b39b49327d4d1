#include "hapticd/env/external_environment.hpp"

#include <time.h>

#include <algorithm>
#include <cmath>

#include "c_vectors.hpp"
#include "hapticd/servo/monotonic_clock.hpp"

namespace hapticd::env {
namespace {

using detail::to_array;

// How often a lockstep wait looks at the channel.
constexpr long kLockstepPollNs = 20'000;

// The world's vector, its components past the scene's axes 0; false if one within is not finite.
bool from_array(const double (&in)[3], int axes, Vec3& out) noexcept {
    out = Vec3(0.0);
    for (int i = 0; i < axes; ++i) {
        if (!std::isfinite(in[i])) return false;
        out[i] = in[i];
    }
    return true;
}

}  // namespace

const char* to_string(BetweenUpdates between) noexcept {
    return between == BetweenUpdates::hold ? "hold" : "extrapolate";
}

const char* to_string(WorldState state) noexcept {
    switch (state) {
        case WorldState::waiting:
            return "waiting";
        case WorldState::live:
            return "live";
        case WorldState::stale:
            return "stale";
    }
    return "?";
}

ExternalEnvironment::ExternalEnvironment(const ExternalSpec& spec,
                                         std::unique_ptr<ExternalChannel> channel, int axes,
                                         const std::atomic<bool>* stop)
    : spec_(spec),
      channel_(std::move(channel)),
      axes_(axes),
      stop_(stop),
      passivity_(spec.passivity) {}

Vec3 ExternalEnvironment::step(const Vec3& device_position_m, const Vec3& device_velocity_mps,
                               const CouplingGains& gains, double period_s) noexcept {
    ++step_;
    time_s_ += period_s;
    if (spec_.lockstep_every > 0 && step_ % spec_.lockstep_every == 0) {
        // The request stays in every block until it is answered (or the next replaces it), so
        // that a world the tick stopped waiting for can answer and bring the waits back.
        unanswered_ = step_;
        publish(device_position_m, device_velocity_mps, gains, period_s);
        if (lockstep_waits_) wait_for_answer();
    }
    take_update();
    const Vec3 wanted = wanted_tool(device_position_m);
    const Vec3 tool =
        passivity_.limit(wanted, tool_m_, device_position_m, device_velocity_mps, gains, period_s);
    // The coupling's force on the tool (16) at the tool rendered, as VirtualCoupling computes it.
    force_n_ = gains.stiffness_n_per_m * (device_position_m - tool) +
               gains.damping_n_s_per_m * (device_velocity_mps - (tool - tool_m_) / period_s);
    tool_m_ = tool;
    publish(device_position_m, device_velocity_mps, gains, period_s);
    return tool;
}

void ExternalEnvironment::reset(const Vec3& position_m) noexcept {
    tool_m_ = position_m;
    force_n_ = Vec3(0.0);
    passivity_.reset(position_m);
    // A stale world's ramp is over: the tool restarts on the handle, at zero force.
    stale_from_m_ = position_m;
    stale_since_s_ = time_s_ - spec_.ramp_s;
}

servo::EnvironmentPortReport ExternalEnvironment::port_report() const noexcept {
    return {.external = true,
            .world_state = static_cast<std::uint32_t>(state_),
            .update = update_,
            .stale_episodes = stale_episodes_,
            .rejected_updates = rejected_updates_,
            .since_update_s = update_ == 0 ? 0.0 : time_s_ - arrived_s_,
            .energy_j = passivity_.energy_j(),
            .energy_removed_j = passivity_.removed_j()};
}

// Lockstep: the request is published; poll for the answer to it. A world that does not answer
// within lockstep_timeout_s is waited for no more until it answers again (take_update).
void ExternalEnvironment::wait_for_answer() noexcept {
    const std::int64_t deadline_ns =
        servo::monotonic_now_ns() + static_cast<std::int64_t>(spec_.lockstep_timeout_s * 1e9);
    const timespec pause{.tv_sec = 0, .tv_nsec = kLockstepPollNs};
    hapticd_world_update update{};
    for (;;) {
        if (channel_->try_take(update) && update.answers >= step_) return;
        if (stop_ != nullptr && stop_->load(std::memory_order_relaxed)) return;
        if (servo::monotonic_now_ns() > deadline_ns) {
            lockstep_waits_ = false;
            return;
        }
        ::clock_nanosleep(CLOCK_MONOTONIC, 0, &pause, nullptr);
    }
}

void ExternalEnvironment::take_update() noexcept {
    hapticd_world_update update{};
    if (!channel_->try_take(update) || update.update == update_) return;
    Vec3 position{0.0};
    Vec3 velocity{0.0};
    const bool position_finite = from_array(update.tool_position_m, axes_, position);
    const bool velocity_given = !std::isnan(update.tool_velocity_mps[0]);  // NaN: not given
    const bool velocity_finite = from_array(update.tool_velocity_mps, axes_, velocity);
    if (!position_finite || (velocity_given && !velocity_finite)) {
        ++rejected_updates_;  // not rendered; the world's next update may be
        update_ = update.update;
        return;
    }
    if (!velocity_given) {  // the last two updates' difference, over the world's clock or ours
        const double world_dt_s = update.world_time_s - world_time_s_;
        const double dt_s =
            std::isfinite(world_dt_s) && world_dt_s > 0.0 ? world_dt_s : time_s_ - arrived_s_;
        velocity = update_ != 0 && dt_s > 0.0 ? (position - world_position_m_) / dt_s : Vec3(0.0);
    }
    update_ = update.update;
    world_position_m_ = position;
    world_velocity_mps_ = velocity;
    world_time_s_ = update.world_time_s;
    arrived_s_ = time_s_;
    if (unanswered_ != 0 && update.answers >= unanswered_) {
        unanswered_ = 0;
        lockstep_waits_ = true;
    }
    state_ = WorldState::live;
}

Vec3 ExternalEnvironment::wanted_tool(const Vec3& device_position_m) noexcept {
    if (state_ == WorldState::waiting) return device_position_m;  // no world yet: no force
    const double since_s = time_s_ - arrived_s_;
    if (state_ == WorldState::live && since_s > spec_.stale_after_s) {
        state_ = WorldState::stale;
        ++stale_episodes_;
        stale_from_m_ = tool_m_;
        stale_since_s_ = time_s_;
    }
    if (state_ == WorldState::stale) {
        const double left =
            spec_.ramp_s > 0.0
                ? std::clamp(1.0 - (time_s_ - stale_since_s_) / spec_.ramp_s, 0.0, 1.0)
                : 0.0;
        // Written from the handle, so that the ramp's end is the handle exactly (no force).
        return device_position_m + left * (stale_from_m_ - device_position_m);
    }
    if (spec_.between_updates == BetweenUpdates::hold) return world_position_m_;
    return world_position_m_ + world_velocity_mps_ * since_s;
}

void ExternalEnvironment::publish(const Vec3& device_position_m, const Vec3& device_velocity_mps,
                                  const CouplingGains& gains, double period_s) noexcept {
    hapticd_world_tick tick{};
    tick.step = step_;
    tick.answer_for = unanswered_;
    tick.time_s = time_s_;
    tick.period_s = period_s;
    tick.stiffness_n_per_m = gains.stiffness_n_per_m;
    tick.damping_n_s_per_m = gains.damping_n_s_per_m;
    to_array(device_position_m, tick.handle_position_m);
    to_array(device_velocity_mps, tick.handle_velocity_mps);
    to_array(tool_m_, tick.tool_position_m);
    to_array(force_n_, tick.coupling_force_n);
    tick.energy_removed_j = passivity_.removed_j();
    tick.state = static_cast<std::uint32_t>(state_);
    tick.update_in_force = update_;
    channel_->publish(tick);
}

}  // namespace hapticd::env
