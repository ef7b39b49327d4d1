// From the daemon's config and what the opened device says about itself to the servo
// loop's settings. Glue, kept apart so that the mapping is tested on its own.
#pragma once

#include "hapticd/daemon/config.hpp"
#include "hapticd/device/device.hpp"
#include "hapticd/servo/servo_config.hpp"

namespace hapticd::daemon {

/// Builds the ServoConfig:
/// - gains from [coupling] (or no coupling when enabled = false);
/// - max force: the smaller of [safety] max_force and the device's own force limit;
/// - encoder jump: a step of more than ten times max_speed in one period is not a hand;
/// - real-time from [servo], but off on a lockstep clock (virtual time has no deadlines, and
///   SCHED_FIFO busy-running would starve the telemetry writer);
/// - the loop is paced by the device when it says so; a lockstep run waits for the
///   telemetry writer between ticks (`lossless_log`) so that its log is complete;
/// - any fault ends the run (stop_on_fault), except link faults with [safety] reconnect:
///   those clear by themselves after reconnect_settle, or end the run after
///   reconnect_timeout (ServoConfig::link_recovery).
/// Throws ConfigError if the device's axes differ from [device] axes.
servo::ServoConfig make_servo_config(const Config& config, const device::DeviceInfo& info,
                                     bool lossless_log);

}  // namespace hapticd::daemon
