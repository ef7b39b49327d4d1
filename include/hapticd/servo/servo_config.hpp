// Configuration of the servo loop, read once before it starts. is_valid() checks all of it,
// the safety limits and the real-time request included, Ceres-style: errors are found
// before the servo thread exists (the daemon calls it in make_servo_config), not on it.
#pragma once

#include <cstdint>
#include <string>

#include "hapticd/input/range.hpp"
#include "hapticd/servo/coupling.hpp"
#include "hapticd/servo/environment_port.hpp"
#include "hapticd/servo/io.hpp"
#include "hapticd/servo/link_recovery.hpp"
#include "hapticd/servo/rate.hpp"
#include "hapticd/servo/realtime.hpp"
#include "hapticd/servo/safety.hpp"

namespace hapticd::servo {

/// The largest overrun budget, either count ([safety] max_missed_periods, ...).
inline constexpr std::int64_t kMaxOverrunBudget = 1'000'000;

/// How much overrunning the loop tolerates before it latches kFaultOverrunBudget.
struct OverrunBudget {
    int max_consecutive_overruns = 5;      ///< more overrunning ticks in a row: fault
    std::int64_t max_missed_periods = 20;  ///< more periods missed by one overrun: fault
};

struct ServoConfig {
    double rate_hz = kDefaultRateHz;  ///< [servo] rate_hz; T = 1/rate_hz
    int axes = 1;                     ///< [device] axes, 1..kMaxAxes
    double counts_per_meter = 0.0;    ///< from DeviceInfo, > 0
    /// [coupling] stiffness, damping, velocity_filter: k_c, b_c of (16), f_c (< rate_hz/2)
    CouplingGains coupling{};
    /// false: no virtual coupling; an impedance environment acts on the device directly
    /// (VirtualCoupling::step_rigid). The gains are then unused. Not for admittance scenes.
    bool coupling_enabled = true;
    SeriesSolverOptions solver{};  ///< Newton solve of (17)
    SafetyLimits safety{};         ///< [safety]; max_force_n also capped at the device's limit
    RealtimeRequest realtime{};    ///< [servo] realtime, priority, cpu
    /// The device's read() blocks until its next period (DeviceInfo::paces_loop): the loop
    /// does not sleep to a deadline of its own.
    bool device_paces_loop = false;
    OverrunBudget overrun{};
    /// run() returns after the tick that latches a fault. Otherwise it keeps ticking at zero
    /// force until request_fault_reset() (a lost device always ends the run). With
    /// link_recovery enabled, a latch of link faults only (kLinkFaults) never stops the run:
    /// it keeps ticking at zero force until the device is back and the latch clears, or
    /// until link_recovery.timeout_s.
    bool stop_on_fault = true;
    /// Clears a latch of link faults only by itself once the device is back (LinkRecovery).
    LinkRecoverySettings link_recovery{};
    bool arm_at_start = true;  ///< false: zero force until arm()
    /// Virtual time only (a lockstep device that paces the loop): before each tick run()
    /// waits, outside the tick, until the telemetry ring has room, so that a log of a
    /// lockstep run is complete however fast the loop goes. Rejected without
    /// device_paces_loop: a wall-clock loop must never wait for its logger.
    bool telemetry_backpressure = false;

    double period_s() const noexcept { return 1.0 / rate_hz; }
    std::int64_t period_ns() const noexcept;

    /// Ceres-style: false, with the offending field, its value and the allowed range in
    /// `error` (may be null).
    bool is_valid(std::string* error) const;
    /// Throws std::invalid_argument with is_valid()'s message.
    void validate() const;
};

}  // namespace hapticd::servo
