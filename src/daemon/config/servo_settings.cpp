#include "hapticd/daemon/servo_settings.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include "config/excitation_prediction.hpp"

namespace hapticd::daemon {
namespace {

/// make_servo_config() before its check.
servo::ServoConfig servo_config_of(const Config& config, const device::DeviceInfo& info,
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
                      .damping_n_s_per_m = config.coupling.damping_n_s_per_m,
                      .velocity_filter_hz = config.coupling.velocity_filter_hz};
    servo.safety.max_force_n = info.force_limit_n > 0.0
                                   ? std::min(config.safety.max_force_n, info.force_limit_n)
                                   : config.safety.max_force_n;
    servo.safety.max_speed_mps = config.safety.max_speed_mps;
    servo.safety.encoder_jump_m = 10.0 * config.safety.max_speed_mps / config.servo.rate_hz;
    servo.safety.soft_start = config.safety.soft_start;
    servo.safety.passivity.mode = config.safety.passivity;
    servo.realtime.mode = info.lockstep ? servo::RealtimeMode::off : config.servo.realtime;
    servo.realtime.priority = config.servo.priority;
    servo.realtime.cpu = config.servo.cpu.value_or(-1);
    servo.device_paces_loop = info.paces_loop;
    servo.telemetry_backpressure = lossless_log && info.lockstep && info.paces_loop;
    servo.stop_on_fault = true;
    servo.overrun = config.safety.overrun;
    servo.link_recovery = config.safety.reconnect;
    servo.arm_at_start = config.safety.arm_at_start;
    return servo;
}

/// The whole servo configuration, checked once, before the servo thread exists.
servo::ServoConfig checked(servo::ServoConfig servo, const Config& config) {
    if (std::string error; !servo.is_valid(&error)) {
        throw ConfigError(config.source + ": " + error);
    }
    return servo;
}

}  // namespace

servo::ServoConfig make_servo_config(const Config& config, const device::DeviceInfo& info,
                                     bool lossless_log) {
    return checked(servo_config_of(config, info, lossless_log), config);
}

servo::ServoConfig make_identify_servo_config(const Config& config, const device::DeviceInfo& info,
                                              bool lossless_log) {
    servo::ServoConfig servo = servo_config_of(config, info, lossless_log);
    servo.coupling_enabled = false;
    servo.coupling = {};
    servo.safety.soft_start.still_time_s = 0.0;
    servo.safety.soft_start.ramp_time_s = 0.0;
    servo.safety.passivity.mode = servo::PassivityMode::observe;
    servo.link_recovery.enabled = false;
    servo.arm_at_start = true;  // the excitation is what was asked for: it plays at once
    return checked(servo, config);
}

namespace {

std::string format(double value) {
    std::ostringstream out;
    out << std::setprecision(3) << value;
    return out.str();
}

// Seconds of full periods a default run covers (docs/daemon.md, "Identification run").
constexpr double kDefaultExcitedTime_s = 10.0;
// Zero force logged after the excitation: the handle coming to rest.
constexpr double kTail_s = 0.5;

}  // namespace

IdentifyPlan make_identify_plan(const Config& config, const device::DeviceInfo& info) {
    const IdentifySection& identify = config.identify;
    const double rate_hz = config.servo.rate_hz;
    const std::optional<double> mass = config.device.model.mass_kg;
    const std::optional<double> damping = config.device.model.damping_n_s_per_m;
    const bool have_model = mass && damping;
    const std::string where = config.source + ": [identify] ";
    IdentifyPlan plan;
    env::ExcitationSettings& settings = plan.excitation;
    settings.signal.sample_rate_hz = rate_hz;
    settings.signal.axes = config.device.axes;
    settings.signal.lines_per_decade = identify.lines_per_decade;
    settings.workspace_half_width_m = identify.workspace_m;
    settings.force_limit_n = servo_config_of(config, info, false).safety.max_force_n;
    const servo::SoftStartSettings soft_start;  // the still wait, as in any run
    settings.still_speed_mps = soft_start.still_speed_mps;
    settings.still_time_s = soft_start.still_time_s;

    // The band, about the corner f_c = b / (2π m) where damping and inertia are equal.
    const double corner_hz = have_model ? *damping / (2.0 * std::numbers::pi * *mass) : 0.0;
    const std::string corner =
        have_model ? "the corner b/(2 pi m) = " + format(corner_hz) + " Hz of [device.model]"
                   : "no [device.model]";
    if (identify.band_low_hz) {
        settings.signal.band_low_hz = *identify.band_low_hz;
    } else {
        settings.signal.band_low_hz = have_model ? corner_hz / 2.0 : 1.0;
        plan.chosen.push_back("band_low = " + format(settings.signal.band_low_hz) + " Hz (" +
                              (have_model ? "half " + corner : "1 Hz: " + corner) + ")");
    }
    if (identify.band_high_hz) {
        settings.signal.band_high_hz = *identify.band_high_hz;
    } else {
        settings.signal.band_high_hz =
            std::min(have_model ? 10.0 * corner_hz : 30.0, rate_hz / 20.0);
        plan.chosen.push_back("band_high = " + format(settings.signal.band_high_hz) + " Hz (" +
                              (have_model ? "ten times " + corner : "30 Hz: " + corner) +
                              ", at most rate_hz/20)");
    }
    if (!(settings.signal.band_high_hz > settings.signal.band_low_hz)) {
        throw ConfigError(where + "band_high = " + format(settings.signal.band_high_hz) +
                          " Hz is not above band_low = " + format(settings.signal.band_low_hz) +
                          " Hz" +
                          (identify.band_low_hz && identify.band_high_hz
                               ? ""
                               : " (one of them chosen from " + corner + "): set both"));
    }
    if (identify.period_s) {
        settings.signal.period_s = *identify.period_s;
    } else {
        settings.signal.period_s = std::min(4.0 / settings.signal.band_low_hz, 60.0);
        plan.chosen.push_back("period = " + format(settings.signal.period_s) +
                              " s (band_low is its 4th harmonic)");
    }

    // The signal at unit peak: its swing per newton and its combined peak over the axes.
    env::MultisineSettings unit = settings.signal;
    unit.peak_force_n = 1.0;
    std::optional<env::Multisine> shape;
    try {
        shape.emplace(unit);
    } catch (const std::invalid_argument& e) {
        throw ConfigError(where + "band_low = " + format(unit.band_low_hz) + " Hz, band_high = " +
                          format(unit.band_high_hz) + " Hz, period = " + format(unit.period_s) +
                          " s, lines_per_decade = " + format(unit.lines_per_decade) + ": " +
                          e.what());
    }
    const double period_s = shape->period_s();
    const double norm_per_n = shape->peak_vector_norm_n();
    const std::optional<double> swing_per_n =
        have_model ? std::optional<double>(shape->steady_state_excursion_m(*mass, *damping))
                   : std::nullopt;
    if (identify.force_amplitude_n) {
        settings.signal.peak_force_n = *identify.force_amplitude_n;
    } else if (swing_per_n) {
        const double for_workspace = 0.5 * identify.workspace_m / *swing_per_n;
        const double for_force = 0.5 * settings.force_limit_n / norm_per_n;
        settings.signal.peak_force_n = std::min(for_workspace, for_force);
        plan.chosen.push_back(
            "force_amplitude = " + format(settings.signal.peak_force_n) + " N (" +
            (for_workspace <= for_force
                 ? "[device.model] predicts a swing of half the workspace = " +
                       format(0.5 * identify.workspace_m) + " m"
                 : "half the force limit " + format(settings.force_limit_n) + " N") +
            ")");
    } else {
        throw ConfigError(where +
                          "force_amplitude is required without [device.model] mass and "
                          "damping: there is no model to size it from (start low, e.g. a "
                          "tenth of [safety] max_force)");
    }
    const double peak_norm_n = settings.signal.peak_force_n * norm_per_n;
    if (peak_norm_n > settings.force_limit_n * (1.0 + 1e-12)) {
        throw ConfigError(where + "force_amplitude = " + format(settings.signal.peak_force_n) +
                          " N makes a peak force of " + format(peak_norm_n) + " N over the " +
                          std::to_string(config.device.axes) + " axes, above the force limit " +
                          format(settings.force_limit_n) +
                          " N ([safety] max_force, or the device's own): allowed <= " +
                          format(settings.force_limit_n / norm_per_n) + " N");
    }

    if (identify.periods) {
        settings.periods = *identify.periods;
    } else {
        settings.periods =
            std::max(2, static_cast<int>(std::ceil(kDefaultExcitedTime_s / period_s - 1e-9)));
        plan.chosen.push_back("periods = " + std::to_string(settings.periods) + " (" +
                              format(settings.periods * period_s) + " s of whole periods)");
    }
    if (identify.fade_s) {
        settings.fade_s = *identify.fade_s;
    } else {
        settings.fade_s = 0.5 * period_s;
        plan.chosen.push_back("fade = " + format(settings.fade_s) + " s (half a period)");
    }
    const double fade_samples = std::round(settings.fade_s * rate_hz);
    const double excitation_samples =
        2.0 * fade_samples + settings.periods * static_cast<double>(shape->period_samples());
    plan.duration_s = settings.still_time_s + excitation_samples / rate_hz + kTail_s;
    predict_excitation(config, plan, kTail_s);
    return plan;
}

}  // namespace hapticd::daemon
