// From the daemon's config and what the opened device says about itself to the servo
// loop's settings. Glue, kept apart so that the mapping is tested on its own.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "hapticd/daemon/config.hpp"
#include "hapticd/device/device.hpp"
#include "hapticd/env/excitation.hpp"
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
/// Then ServoConfig::is_valid(), once, before the servo thread exists: the safety limits and
/// the real-time request included (a [servo] cpu this machine does not have).
/// Throws ConfigError if the device's axes differ from [device] axes, or naming the file and
/// the servo setting that is not valid.
servo::ServoConfig make_servo_config(const Config& config, const device::DeviceInfo& info,
                                     bool lossless_log);

/// `hapticd --identify`: make_servo_config(), then open loop and nothing that would change
/// the excitation on its way to the handle:
/// - no coupling (the excitation is an impedance environment evaluated at the handle:
///   VirtualCoupling::step_rigid), so the gains and the start-up check do not apply;
/// - no soft start in the safety stage: the excitation waits for a still handle itself and
///   fades in from zero (ExcitationEnvironment), so the logged force is the signal exactly;
/// - the passivity observer observes only: an excitation is an active source by design,
///   and the controller would add damping to it;
/// - no link recovery: any fault ends the run (a log with a gap is not a clean record);
/// - max_force, max_speed and the fault latch apply as in any run.
servo::ServoConfig make_identify_servo_config(const Config& config, const device::DeviceInfo& info,
                                              bool lossless_log);

/// The excitation of `hapticd --identify`, with every value [identify] leaves unset chosen:
///   band_low  = f_c / 2, band_high = min(10 f_c, rate_hz / 20), f_c = b / (2π m) the
///               corner of [device.model] (without it: 1 Hz and min(30 Hz, rate_hz / 20));
///   period    = 4 / band_low (at most 60 s), so the lowest line is the 4th harmonic;
///   periods   = enough whole periods for 10 s, at least 2;
///   fade      = period / 2;
///   force_amplitude = the largest peak for which [device.model] predicts a swing of half
///               the workspace (Multisine::steady_state_excursion_m), and at most half the
///               force limit over the axes' combined peak; without [device.model] it is
///               required.
/// The force limit is make_servo_config()'s max force (the smaller of [safety] max_force
/// and the device's). Throws ConfigError naming the file and the keys when the values do
/// not make a signal (fewer than two lines per axis, a band that ends below its start) or
/// when the signal's peak force vector exceeds the force limit.
struct IdentifyPlan {
    env::ExcitationSettings excitation;
    /// Still wait + the excitation + 0.5 s of zero force after it: the default --duration.
    double duration_s = 0.0;
    /// What [device.model] predicts for the swing about the start, m (none without it):
    /// the identification's model driven from rest by the planned run
    /// (excitation_prediction.hpp).
    std::optional<double> predicted_excursion_m;
    /// The fraction of the periods after which [device.model] coulomb would hold the handle
    /// still (none without it).
    std::optional<double> predicted_stuck_fraction;
    /// The values that were chosen here rather than read from [identify], one per line,
    /// e.g. "band_low = 1.59 Hz (half the corner b/(2 pi m) = 3.18 Hz of [device.model])".
    std::vector<std::string> chosen;
};
IdentifyPlan make_identify_plan(const Config& config, const device::DeviceInfo& info);

}  // namespace hapticd::daemon
