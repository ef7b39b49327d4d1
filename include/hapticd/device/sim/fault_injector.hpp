// Deterministic fault injection for the simulated device (FaultConfig in sim_config.hpp).
//
// Every decision is a pure function of the configuration, the seed and the sample (its
// device time, the previous sample's device time and its sequence number), so a lockstep run
// is repeatable bit for bit, and reading the same lockstep sample twice gives the same
// verdict. Random faults draw from a counter-based generator (splitmix64 of seed and sequence),
// not from a stream, for the same reason.
#pragma once

#include <cstdint>

#include "hapticd/device/sim/sim_config.hpp"

namespace hapticd::device::sim {

/// What happens to one sample.
struct FaultVerdict {
    std::uint32_t status = 0;   ///< servo::StatusBit flags
    bool disconnected = false;  ///< read/write return IoResult::disconnected
    bool dropped = false;       ///< read returns IoResult::timeout
    bool late = false;          ///< the reply is late (realtime: really late by late_by_s)
    bool stale = false;         ///< the counts are frozen at the last fresh sample
    std::int64_t jump_offset_counts = 0;  ///< added to jump_axis's counts
};

class FaultInjector {
  public:
    /// Outside the tick; copies and sorts the schedules.
    void configure(const FaultConfig& faults, double period_s);

    /// The sample at device time time_s (the previous one was at previous_time_s, or -inf
    /// for the first). An event at time t hits the sample with previous < t <= time.
    FaultVerdict evaluate(double previous_time_s, double time_s,
                          std::uint64_t sequence) const noexcept;

    /// True from disconnect_at_s on.
    bool disconnected(double time_s) const noexcept;

    int jump_axis() const noexcept { return faults_.jump_axis; }
    double late_by_s() const noexcept { return late_by_s_; }

  private:
    bool reached(double at_s, double time_s) const noexcept;
    bool hit(double at_s, double previous_time_s, double time_s) const noexcept;
    bool any_hit(const std::vector<double>& sorted_s, double previous_time_s,
                 double time_s) const noexcept;
    double uniform(std::uint64_t sequence, std::uint64_t stream) const noexcept;

    FaultConfig faults_;
    double tolerance_s_ = 0.0;  ///< absorbs rounding of n T against a configured time
    double late_by_s_ = 0.0;
};

}  // namespace hapticd::device::sim
