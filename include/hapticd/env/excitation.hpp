// The excitation of `hapticd --identify` as an impedance environment: a force source that
// plays the multisine of excitation_signal.hpp on the handle, open loop (the daemon runs it
// with the coupling off: VirtualCoupling::step_rigid hands evaluate()'s force straight to the
// handle). docs/identification.md, "Excitation", says why this signal.
//
// One run, in excitation samples j (one per committed tick; j = 0 is the first tick of
// the excitation):
//
//   waiting   zero force until the handle has been still (|v| < still_speed on every axis)
//             for still_time; the workspace box is then centred where the handle is;
//   fade-in   j in [0, F):          f = w(j) u(j - F),  w = (1 - cos(π j / F)) / 2
//   periods   j in [F, F + K L):    f = u(j - F)        K whole periods of L samples
//   fade-out  j in [F + K L, 2F + K L): f = w'(j) u(j - F), w' = (1 + cos(π (j-F-KL) / F)) / 2
//   finished  zero force.
//
// with u the multisine (so the full periods start at phase 0) and the force vector clamped
// to |f| <= force_limit (it only acts if the signal's own peak vector exceeds it).
//
// The workspace rule: a handle more than workspace_half_width from the centre on any axis
// gets zero force from evaluate() in that very tick, and commit() latches `left_workspace`:
// zero force for the rest of the run (no re-entry: an excitation that drove the handle out
// once will again, and a person may be holding it now). reset() after the start (link
// recovery, re-arming) ends the excitation the same way (`interrupted`); reset() before it
// restarts the wait for a still handle. So the force is either the signal or zero.
//
// Time: the impedance port passes no clock, so the environment counts its commits; one
// commit per tick with a sample (step_rigid commits once). In a run without overruns or
// dropped samples tick n is at t = n T; the log's f{i}_n column is the force actually sent
// either way, which is what the identification replays.
//
// The Jacobians are zero (a pure source): with the coupling on, the series solve (17) would
// still converge in one step, but the daemon does not do that.
//
// evaluate(), commit() and reset() are real-time safe: the tables are built by the
// constructor; nothing in the tick allocates, locks, logs or throws.
#pragma once

#include <cstdint>

#include "hapticd/env/environment.hpp"
#include "hapticd/env/excitation_signal.hpp"

namespace hapticd::env {

struct ExcitationSettings {
    MultisineSettings signal;              ///< peak_force_n: each axis's peak, N
    int periods = 4;                       ///< K >= 1 full periods at full amplitude
    double fade_s = 1.0;                   ///< F / rate, >= 0 (0: the signal starts as a step)
    double workspace_half_width_m = 0.03;  ///< > 0, per axis, about the still position
    double force_limit_n = 10.0;           ///< > 0: |f| (vector norm) never exceeds it
    double still_speed_mps = 0.02;         ///< >= 0; the servo soft start's default
    double still_time_s = 0.2;             ///< >= 0; the servo soft start's default
};

class ExcitationEnvironment final : public ImpedanceEnvironment {
  public:
    enum class Phase {
        waiting_for_still,
        running,         ///< fade-in, periods or fade-out
        finished,        ///< the whole excitation was played
        left_workspace,  ///< stopped by the workspace rule
        interrupted,     ///< stopped by a reset() after the start
    };

    /// Builds the tables. Throws std::invalid_argument naming the setting and its value.
    explicit ExcitationEnvironment(const ExcitationSettings& settings);

    PenaltyForce evaluate(const Vec3& tool_position_m,
                          const Vec3& tool_velocity_mps) const noexcept override;
    void commit(const Vec3& tool_position_m, const Vec3& tool_velocity_mps) noexcept override;
    void reset(const Vec3& tool_position_m) noexcept override;

    /// The force of excitation sample j (any integer; zero outside [0, samples())), after
    /// the clamp, before the workspace rule. Real-time safe.
    [[nodiscard]] Vec3 scheduled_force_n(std::int64_t j) const noexcept;
    /// The envelope w(j) in [0, 1] (zero outside the excitation).
    [[nodiscard]] double envelope(std::int64_t j) const noexcept;

    [[nodiscard]] const ExcitationSettings& settings() const noexcept { return settings_; }
    [[nodiscard]] const Multisine& signal() const noexcept { return signal_; }
    [[nodiscard]] int axes() const noexcept { return signal_.axes(); }
    /// F, fade samples.
    [[nodiscard]] std::int64_t fade_samples() const noexcept { return fade_samples_; }
    /// 2F + K L: the whole excitation.
    [[nodiscard]] std::int64_t samples() const noexcept { return samples_; }
    /// The still wait, in ticks.
    [[nodiscard]] std::int64_t still_ticks() const noexcept { return still_ticks_needed_; }

    // --- state (the servo thread, or any thread after the run) ------------------------
    [[nodiscard]] Phase phase() const noexcept { return phase_; }
    /// Commits since construction (ticks that ran the environment).
    [[nodiscard]] std::int64_t ticks() const noexcept { return ticks_; }
    /// The tick (counted as ticks()) that played sample j = 0; -1 before the start.
    [[nodiscard]] std::int64_t start_tick() const noexcept { return start_tick_; }
    /// Samples played so far (j of the next tick while running).
    [[nodiscard]] std::int64_t samples_played() const noexcept { return played_; }
    /// Where the workspace box is centred (the still handle at the start).
    [[nodiscard]] const Vec3& center_m() const noexcept { return center_m_; }
    /// The handle position that broke the workspace rule (when phase() is left_workspace).
    [[nodiscard]] const Vec3& exit_position_m() const noexcept { return exit_position_m_; }

    /// True when `position_m` is inside the workspace box about center_m() (the box's own
    /// faces count as inside).
    [[nodiscard]] bool inside_workspace(const Vec3& position_m) const noexcept;

  private:
    ExcitationSettings settings_;
    Multisine signal_;
    std::int64_t fade_samples_ = 0;
    std::int64_t samples_ = 0;
    std::int64_t still_ticks_needed_ = 0;

    Phase phase_ = Phase::waiting_for_still;
    std::int64_t ticks_ = 0;
    std::int64_t still_for_ = 0;
    std::int64_t start_tick_ = -1;
    std::int64_t played_ = 0;
    Vec3 center_m_{0.0};
    Vec3 exit_position_m_{0.0};
};

[[nodiscard]] const char* to_string(ExcitationEnvironment::Phase phase) noexcept;

}  // namespace hapticd::env
