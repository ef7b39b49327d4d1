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
// Commands: force_n clamped to +-force_limit; enable = false or a non-finite force holds zero
// (a non-finite force also makes write() return IoResult::error). After disconnect, and after
// close(), the force is zero: the device's own watchdog.
//
// Real-time: read() and write() do not allocate, lock, log or throw. The realtime clock's late
// replies sleep (clock_nanosleep) in read(), as a late device would keep the caller waiting.
#pragma once

#include <array>
#include <cstdint>

#include "hapticd/device/device.hpp"
#include "hapticd/device/sim/axis_plant.hpp"
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

    // Inspection, for tests and benchmarks (not part of Device).
    const SimConfig& config() const noexcept { return config_; }
    const AxisPlant& plant(int axis) const noexcept { return plants_[axis]; }
    /// Device time of the physics state, s.
    double time_s() const noexcept;
    /// The force being held on each axis, N (after clamping, zero when disabled).
    const std::array<double, kMaxAxes>& held_force_n() const noexcept { return held_force_n_; }
    bool is_open() const noexcept { return open_; }

  private:
    /// Advances every axis to `units` (T 2^-20 since open) under the held force.
    void advance_to(std::uint64_t units) noexcept;
    /// Realtime: the current CLOCK_MONOTONIC time in units since open.
    std::uint64_t now_units() const noexcept;
    double units_to_s(std::uint64_t units) const noexcept;
    std::int64_t encoder_counts(int axis) const noexcept;

    SimConfig config_;
    std::array<AxisPlant, kMaxAxes> plants_{};
    FaultInjector faults_;
    std::array<double, kMaxAxes> held_force_n_{};
    std::array<std::int64_t, kMaxAxes> last_fresh_counts_{};
    std::uint64_t units_ = 0;              ///< physics time since open, T 2^-20
    std::int64_t open_time_ns_ = 0;        ///< realtime: CLOCK_MONOTONIC at open()
    std::uint64_t samples_produced_ = 0;   ///< realtime: sequence of the next sample
    double previous_sample_time_s_ = 0.0;  ///< realtime: device time of the last sample
    bool open_ = false;
};

}  // namespace hapticd::device::sim
