#include "hapticd/daemon/servo_settings.hpp"

#include <algorithm>
#include <string>

namespace hapticd::daemon {

servo::ServoConfig make_servo_config(const Config& config, const device::DeviceInfo& info,
                                     bool lossless_log) {
    if (info.axes != config.device.axes) {
        throw ConfigError(config.source +
                          ": [device] axes = " + std::to_string(config.device.axes) + " but the " +
                          info.name + " device has " + std::to_string(info.axes));
    }
    servo::ServoConfig servo;
    servo.rate_hz = config.servo.rate_hz;
    servo.axes = config.device.axes;
    servo.counts_per_meter = info.counts_per_meter;
    servo.coupling_enabled = config.coupling.enabled;
    servo.coupling = {.stiffness_n_per_m = config.coupling.stiffness_n_per_m,
                      .damping_n_s_per_m = config.coupling.damping_n_s_per_m};
    servo.safety.max_force_n = info.force_limit_n > 0.0
                                   ? std::min(config.safety.max_force_n, info.force_limit_n)
                                   : config.safety.max_force_n;
    servo.safety.max_speed_mps = config.safety.max_speed_mps;
    servo.safety.encoder_jump_m = 10.0 * config.safety.max_speed_mps / config.servo.rate_hz;
    servo.safety.soft_start.ramp_time_s = config.safety.soft_start_ramp_s;
    servo.safety.passivity.mode = config.safety.passivity == "control"
                                      ? servo::PassivityMode::control
                                      : servo::PassivityMode::observe;
    servo.realtime.mode = info.lockstep ? servo::RealtimeMode::off
                                        : servo::parse_realtime_mode(config.servo.realtime);
    servo.realtime.priority = config.servo.priority;
    servo.realtime.cpu = config.servo.cpu.value_or(-1);
    servo.device_paces_loop = info.paces_loop;
    servo.telemetry_backpressure = lossless_log && info.lockstep && info.paces_loop;
    servo.stop_on_fault = true;
    servo.link_recovery = {.enabled = config.safety.reconnect,
                           .settle_s = config.safety.reconnect_settle_s,
                           .timeout_s = config.safety.reconnect_timeout_s};
    servo.start_armed = true;
    return servo;
}

}  // namespace hapticd::daemon
