// The simulated device's loop delay ([device.sim] delay, docs/sim-device.md "Loop delay"):
// the commands in flight between the encoder sample they were computed from and the moment
// they act on the handle.
//
// A force written in tick n (sample at t = nT) acts over [nT + D, (n+1)T + D); before
// nT + D the previous command still acts. With D = (q + φ) T, q a whole number of periods
// and 0 <= φ < 1, period n therefore sees F[n-q-1] for its first φT and F[n-q] for the
// rest: the zero-order hold of the paper's (13), shifted by D.
//
// LoopDelay is D split that way; CommandPipeline is the first-in first-out queue of the
// commands that have been written but do not act yet, each with the time it lands. The
// queue is a ring allocated by configure() (outside the tick); push(), due(), pop() and
// clear() never allocate, lock, log or throw.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "hapticd/device/device.hpp"

namespace hapticd::device::sim {

/// The largest loop delay [device.sim] delay accepts, in periods (exclusive).
inline constexpr double kMaxDelayPeriods = 10.0;

/// D = (whole_periods + fraction) T.
struct LoopDelay {
    std::uint64_t whole_periods = 0;  ///< q
    double fraction = 0.0;            ///< φ, in [0, 1)
    /// D in units of T 2^-kFractionBits (axis_plant.hpp), nearest: the realtime clock's
    /// resolution. The lockstep clock uses whole_periods and fraction, exactly.
    std::uint64_t units = 0;

    bool is_zero() const noexcept { return whole_periods == 0 && fraction == 0.0; }
};

/// Splits `delay_s` at `rate_hz`. A delay within 1e-9 periods of a whole number of periods
/// is that whole number (so that 1e-3 s at 1 kHz is exactly one period, whatever the
/// rounding of 1e-3 * 1000). Outside the tick; throws std::invalid_argument for a delay that
/// is not finite, negative, or not below kMaxDelayPeriods periods (parse_sim_config()
/// reports those to the user first, naming the file and the key).
LoopDelay split_delay(double delay_s, double rate_hz);

/// A command on its way to the handle.
struct PendingCommand {
    /// When it lands: lockstep, the period index in which it starts to act (at φT into
    /// it); realtime, the device time in units of T 2^-kFractionBits since open().
    std::uint64_t due = 0;
    std::array<double, kMaxAxes> force_n{};  ///< after clamping; zero for a disabled command
    std::uint64_t tag = 0;  ///< the writer's name for it (SimDevice: the write() call)
};

class CommandPipeline {
  public:
    /// Outside the tick: room for `capacity` (>= 1) commands in flight; empties the queue.
    void configure(std::size_t capacity);

    /// Forgets every command in flight: none of them will ever act.
    void clear() noexcept { size_ = 0; }
    std::size_t size() const noexcept { return size_; }
    std::size_t capacity() const noexcept { return ring_.size(); }

    /// Appends a command; `due` must not be before that of the newest one in flight. When
    /// the ring is full (a host that writes more than capacity() commands within one loop
    /// delay), the newest command in flight is replaced by this one, which lands at its own
    /// time: like a device's command mailbox that keeps the latest value.
    void push(std::uint64_t due, const std::array<double, kMaxAxes>& force_n,
              std::uint64_t tag = 0) noexcept;

    /// The oldest command in flight if it lands at or before `now`, else nullptr.
    const PendingCommand* due(std::uint64_t now) const noexcept;
    /// Removes the oldest command in flight (call after due() returned it).
    void pop() noexcept;

  private:
    std::vector<PendingCommand> ring_;
    std::size_t head_ = 0;  ///< index of the oldest command in flight
    std::size_t size_ = 0;
};

}  // namespace hapticd::device::sim
