// The excitation of excitation.hpp as a servo::OpenLoopSource: what the control socket's
// `identify` plays through ServoLoop::play_open_loop (daemon/excitation_session.hpp), with its
// progress published for the threads that watch it. Everything the servo thread calls is
// real-time safe: the excitation's own calls, then two atomic stores.
#pragma once

#include <atomic>
#include <cstdint>

#include "hapticd/env/excitation.hpp"
#include "hapticd/servo/open_loop_source.hpp"

namespace hapticd::env {

class ExcitationSource final : public servo::OpenLoopSource {
  public:
    using Phase = ExcitationEnvironment::Phase;

    /// Builds the excitation's tables; throws std::invalid_argument as it does.
    explicit ExcitationSource(const ExcitationSettings& settings) : excitation_(settings) {}

    [[nodiscard]] PenaltyForce evaluate(const Vec3& handle_position_m,
                                        const Vec3& handle_velocity_mps) const noexcept override {
        return excitation_.evaluate(handle_position_m, handle_velocity_mps);
    }
    void commit(const Vec3& handle_position_m, const Vec3& handle_velocity_mps) noexcept override {
        excitation_.commit(handle_position_m, handle_velocity_mps);
        publish();
    }
    void reset(const Vec3& handle_position_m) noexcept override {
        excitation_.reset(handle_position_m);
        publish();
    }
    /// Played to its end, stopped by the workspace rule, or interrupted by a reset after
    /// its start: only zero force is left to play.
    [[nodiscard]] bool done() const noexcept override {
        const Phase phase = excitation_.phase();
        return phase != Phase::waiting_for_still && phase != Phase::running;
    }

    /// Any thread: the phase and the samples played, as of the servo's last tick.
    [[nodiscard]] Phase phase() const noexcept { return phase_.load(std::memory_order_acquire); }
    [[nodiscard]] std::int64_t samples_played() const noexcept {
        return played_.load(std::memory_order_acquire);
    }
    /// The excitation itself: on the servo thread, or on any thread once the loop has let go
    /// of the source (ServoLoop::open_loop_idle()).
    [[nodiscard]] const ExcitationEnvironment& excitation() const noexcept { return excitation_; }

  private:
    void publish() noexcept {
        played_.store(excitation_.samples_played(), std::memory_order_release);
        phase_.store(excitation_.phase(), std::memory_order_release);
    }

    ExcitationEnvironment excitation_;
    std::atomic<Phase> phase_{Phase::waiting_for_still};
    std::atomic<std::int64_t> played_{0};
};

}  // namespace hapticd::env
