// One telemetry record per servo tick: what the daemon's writer thread turns into a CSV line
// (telemetry_csv.hpp) after taking it off the lock-free ring (telemetry_ring.hpp).
#pragma once

#include <array>
#include <cstdint>

#include "hapticd/servo/io.hpp"

namespace hapticd::servo {

/// Servo-side flags of one tick (the `tick_flags` column); the device's own StatusBit flags go
/// unchanged into the `status` column.
enum TickFlag : std::uint32_t {
    kFlagOverrun = 1u << 0,             ///< this tick started after its deadline had passed
    kFlagSaturated = 1u << 1,           ///< force saturation acted
    kFlagOverspeed = 1u << 2,           ///< the velocity limit acted
    kFlagSoftStart = 1u << 3,           ///< the soft start scaled the force below 1
    kFlagPassivityControl = 1u << 4,    ///< the passivity controller added damping
    kFlagSolverNotConverged = 1u << 5,  ///< (17) did not meet its tolerance
    kFlagNoSample = 1u << 6,            ///< read() gave no sample (timeout, dropped)
    kFlagDisarmed = 1u << 7,            ///< the loop is disarmed: zero force by request
    kFlagLinkRecovered = 1u << 8,       ///< the link-fault latch clears after this tick
    /// The time since the last sample is unknown (the device's clock stood still or went
    /// backwards): zero force, and the velocity history starts again at this sample.
    kFlagIntervalUnknown = 1u << 9,
    /// An OpenLoopSource played this tick's force, in place of the coupling and the
    /// environment (ServoLoop::play_open_loop: the control socket's identify).
    kFlagOpenLoop = 1u << 10,
};

struct TelemetryRecord {
    std::uint64_t tick = 0;    ///< 0, 1, 2, ... (ticks actually run)
    double t_s = 0.0;          ///< scheduled time since start, or the device's time if it paces
    double unix_time_s = 0.0;  ///< when the tick ran: CLOCK_REALTIME, whole µs, Unix seconds
    std::array<double, kMaxAxes> x_m{};    ///< device position x_d
    std::array<double, kMaxAxes> v_mps{};  ///< device velocity v_d (backward difference)
    std::array<double, kMaxAxes> xe_m{};   ///< environment-side tool position x_e
    std::array<double, kMaxAxes> f_n{};    ///< force commanded on the handle, after safety
    std::uint32_t status = 0;              ///< the sample's StatusBit flags
    std::uint32_t flags = 0;               ///< TickFlag (the `tick_flags` column)
    std::uint32_t faults = 0;              ///< latched Fault mask
    std::uint32_t state = 0;               ///< ServoState: 0 disabled 1 arming 2 running 3 fault
    double wake_latency_us = 0.0;          ///< actual wake - deadline
    double compute_us = 0.0;               ///< wake to command written
    double energy_j = 0.0;                 ///< passivity observer energy
    std::uint32_t mark = 0;                ///< the latest LoopInbox::mark() (0: none yet)
};

}  // namespace hapticd::servo
