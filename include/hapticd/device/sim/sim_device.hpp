// The simulated device: the `sim` plugin's Device (docs/sim-device.md).
//
// Per axis an AxisPlant (device (10) + passive operator, exact ZOH), an encoder that reports
// counts = floor(x counts_per_meter), and a FaultInjector. Two clocks:
//   lockstep  virtual time. Sample n is at t = n T. write() holds its force for exactly one
//             period and advances the physics to t = (n+1) T; read() returns the sample at
//             the current time at once (reading twice without a write returns the same sample).
//             info(): paces_loop = lockstep = true. Deterministic: same config, same commands,
//             same samples, bit for bit.
//   realtime  the physics follows CLOCK_MONOTONIC from open(): read() and write() first
//             advance the state to "now" under the force held since the last write (exactly,
//             in whole periods plus a remainder quantised to T 2^-20); read() returns the
//             state at now, write() then holds its force from now. paces_loop = false.
// Sequence numbers: lockstep, n; realtime, one per read() (the sample the device produced).
//
// Loop delay D ([device.sim] delay, command_pipeline.hpp): a command lands D after the
// sample it was computed from. Lockstep: the force written in tick n acts over
// [nT + D, (n+1)T + D), exactly (each period is integrated in its two pieces, F[n-q-1] then
// F[n-q]). Realtime: a command written after the sample at t_s lands at t_s + D, or at once
// if that has already passed. Until it lands the previous command acts.
//
// Commands: force_n clamped to +-force_limit; enable = false holds zero, landing D later like
// any command (what is already in flight still acts first: it is the device's own delay).
// A non-finite force is refused: zero at once, the commands in flight dropped, and write()
// returns IoResult::error. After a disconnect, and after close(), the force is zero at once
// and nothing in flight ever lands: the device's own watchdog.
//
// What took effect when: every sample reports the command in effect (Sample::applied_write,
// the write() call it came from) and the device time it landed (Sample::applied_time_s), so
// that the link diagnosis measures [device.sim] delay as it would a device's. It samples at
// read() (DeviceInfo::samples_at_read).
//
// Real-time: read() and write() do not allocate, lock, log or throw. The realtime clock's late
// replies sleep (clock_nanosleep) in read(), as a late device would keep the caller waiting.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "hapticd/device/device.hpp"
#include "hapticd/device/sim/axis_plant.hpp"
#include "hapticd/device/sim/command_pipeline.hpp"
#include "hapticd/device/sim/fault_injector.hpp"
#include "hapticd/device/sim/sim_config.hpp"

namespace hapticd::device::sim {

class SimDevice final : public Device {
  public:
    /// Parses config.plugin_table_toml (parse_sim_config), then opens.
    void open(const DeviceConfig& config) override;
    /// The non-plugin way in, for unit tests: an already validated configuration.
    void open(const SimConfig& config);
    DeviceInfo info() const override;
    IoResult read(Sample& sample) noexcept override;
    IoResult write(const Command& command) noexcept override;
    void close() noexcept override;
    /// write() under the caller's own name for the command, `tag` != 0 (DeviceEmulator: its
    /// session and sequence), which Sample::applied_write then reports instead of the call's
    /// count. A command landing with the tag of the one in effect (the same command written
    /// again, as a device holds it period after period) keeps the moment the first took effect.
    IoResult write_tagged(const Command& command, std::uint64_t tag) noexcept;

    // Inspection, for tests and benchmarks (not part of Device).
    const SimConfig& config() const noexcept { return config_; }
    const AxisPlant& plant(int axis) const noexcept { return plants_[axis]; }
    /// Device time of the physics state, s.
    double time_s() const noexcept;
    /// The force acting on each axis at time_s(), N (after clamping, zero when disabled):
    /// with a loop delay, the last command that has landed.
    const std::array<double, kMaxAxes>& held_force_n() const noexcept { return held_force_n_; }
    /// Commands written but not landed yet (the loop delay).
    std::size_t commands_in_flight() const noexcept { return pipeline_.size(); }
    const LoopDelay& loop_delay() const noexcept { return delay_; }
    bool is_open() const noexcept { return open_; }

  private:
    /// Realtime: advances every axis to `units` (T 2^-20 since open), landing each command
    /// in flight at its time on the way.
    void advance_to(std::uint64_t units) noexcept;
    /// Advances every axis to `units` under the held force.
    void advance_held_to(std::uint64_t units) noexcept;
    /// Lockstep: one period [nT, (n+1)T): the held force for its first φT, then the
    /// command due in period n (if any) for the rest.
    void step_lockstep_period() noexcept;
    /// Zero force at once, nothing in flight: the watchdog, close(), a refused command.
    void cut_force() noexcept;
    /// The command named `tag` acts from `time_s` on (unless it already did).
    void took_effect(std::uint64_t tag, double time_s) noexcept;
    /// Realtime: the current CLOCK_MONOTONIC time in units since open.
    std::uint64_t now_units() const noexcept;
    double units_to_s(std::uint64_t units) const noexcept;
    std::int64_t encoder_counts(int axis) const noexcept;

    SimConfig config_;
    std::array<AxisPlant, kMaxAxes> plants_{};
    FaultInjector faults_;
    std::array<double, kMaxAxes> held_force_n_{};
    LoopDelay delay_;
    CommandPipeline pipeline_;        ///< the commands in flight
    std::uint64_t sample_units_ = 0;  ///< realtime: when the last sample was taken
    std::array<std::int64_t, kMaxAxes> last_fresh_counts_{};
    std::uint64_t units_ = 0;              ///< physics time since open, T 2^-20
    std::int64_t open_time_ns_ = 0;        ///< realtime: CLOCK_MONOTONIC at open()
    std::uint64_t samples_produced_ = 0;   ///< realtime: sequence of the next sample
    double previous_sample_time_s_ = 0.0;  ///< realtime: device time of the last sample
    std::uint64_t writes_ = 0;             ///< write() calls since open()
    std::uint64_t applied_tag_ = 0;        ///< the command in effect (0: none yet)
    double applied_time_s_ = 0.0;          ///< ... since this device time
    bool open_ = false;
};

}  // namespace hapticd::device::sim
