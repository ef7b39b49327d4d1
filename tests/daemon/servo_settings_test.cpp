// From the daemon's config and the device's self-description to the servo loop's settings.
#include "hapticd/daemon/servo_settings.hpp"

#include <gtest/gtest.h>

#include <iostream>
#include <numbers>
#include <string>

namespace hapticd::daemon {
namespace {

device::DeviceInfo pen_display(bool lockstep) {
    device::DeviceInfo info;
    info.axes = 1;
    info.counts_per_meter = 1e5;
    info.force_limit_n = 8.0;
    info.paces_loop = lockstep;
    info.lockstep = lockstep;
    info.name = "sim";
    return info;
}

Config lab_config() {
    return parse_config(R"(
[servo]
rate_hz = 2000
realtime = "enforce"
priority = 70
cpu = 1
[coupling]
stiffness = 3000
damping = 0.25
[safety]
max_force = 12
max_speed = 0.5
soft_start_ramp = 0.2
passivity = "control"
)",
                        "lab.toml", "");
}

TEST(DaemonServoSettings, GainsRateAndEncoderFromConfigAndDevice) {
    const servo::ServoConfig s = make_servo_config(lab_config(), pen_display(false), false);
    EXPECT_EQ(s.rate_hz, 2000.0);
    EXPECT_EQ(s.axes, 1);
    EXPECT_EQ(s.counts_per_meter, 1e5);
    EXPECT_TRUE(s.coupling_enabled);
    EXPECT_EQ(s.coupling.stiffness_n_per_m, 3000.0);
    EXPECT_EQ(s.coupling.damping_n_s_per_m, 0.25);
    EXPECT_EQ(s.safety.soft_start.ramp_time_s, 0.2);
    EXPECT_EQ(s.safety.passivity.mode, servo::PassivityMode::control);
    EXPECT_NO_THROW(s.validate());
}

TEST(DaemonServoSettings, MaxForceIsTheSmallerOfConfigAndDevice) {
    // [safety] max_force = 12 N, but the device accepts at most 8 N.
    EXPECT_EQ(make_servo_config(lab_config(), pen_display(false), false).safety.max_force_n, 8.0);
    device::DeviceInfo strong = pen_display(false);
    strong.force_limit_n = 40.0;
    EXPECT_EQ(make_servo_config(lab_config(), strong, false).safety.max_force_n, 12.0);
}

TEST(DaemonServoSettings, EncoderJumpIsTenTimesMaxSpeedPerPeriod) {
    // 0.5 m/s at 2 kHz is 0.25 mm per period; a jump is ten times that.
    EXPECT_DOUBLE_EQ(
        make_servo_config(lab_config(), pen_display(false), false).safety.encoder_jump_m,
        10.0 * 0.5 / 2000.0);
}

TEST(DaemonServoSettings, RealtimeRequestOnTheWallClock) {
    const servo::ServoConfig s = make_servo_config(lab_config(), pen_display(false), true);
    EXPECT_EQ(s.realtime.mode, servo::RealtimeMode::enforce);
    EXPECT_EQ(s.realtime.priority, 70);
    EXPECT_EQ(s.realtime.cpu, 1);
    EXPECT_FALSE(s.device_paces_loop);
    EXPECT_FALSE(s.telemetry_backpressure);  // a wall-clock loop never waits for its logger
}

TEST(DaemonServoSettings, LockstepIsPacedByTheDeviceWithoutRealtimeAndLogsLosslessly) {
    const servo::ServoConfig logged = make_servo_config(lab_config(), pen_display(true), true);
    EXPECT_EQ(logged.realtime.mode, servo::RealtimeMode::off);
    EXPECT_TRUE(logged.device_paces_loop);
    EXPECT_TRUE(logged.telemetry_backpressure);
    EXPECT_NO_THROW(logged.validate());
    EXPECT_FALSE(make_servo_config(lab_config(), pen_display(true), false).telemetry_backpressure);
}

TEST(DaemonServoSettings, NoCouplingIsPassedThrough) {
    const Config c = parse_config("[coupling]\nenabled = false\ncheck = \"off\"\n", "x.toml", "");
    const servo::ServoConfig s = make_servo_config(c, pen_display(true), false);
    EXPECT_FALSE(s.coupling_enabled);
    EXPECT_NO_THROW(s.validate());
}

TEST(DaemonServoSettings, LinkFaultsRecoverByDefaultEveryOtherFaultStopsTheRun) {
    const servo::ServoConfig s = make_servo_config(lab_config(), pen_display(false), false);
    EXPECT_TRUE(s.stop_on_fault);
    EXPECT_TRUE(s.link_recovery.enabled);
    EXPECT_EQ(s.link_recovery.settle_s, 0.5);
    EXPECT_EQ(s.link_recovery.timeout_s, 5.0);

    const Config patient = parse_config(
        "[coupling]\nstiffness = 3000\n[safety]\nreconnect_settle = 2\nreconnect_timeout = 0\n",
        "lab.toml", "");
    const servo::ServoConfig p = make_servo_config(patient, pen_display(true), false);
    EXPECT_TRUE(p.link_recovery.enabled);
    EXPECT_EQ(p.link_recovery.settle_s, 2.0);
    EXPECT_EQ(p.link_recovery.timeout_s, 0.0);
    EXPECT_NO_THROW(p.validate());

    const Config strict =
        parse_config("[coupling]\nstiffness = 3000\n[safety]\nreconnect = false\n", "lab.toml", "");
    const servo::ServoConfig off = make_servo_config(strict, pen_display(false), false);
    EXPECT_FALSE(off.link_recovery.enabled);
    EXPECT_TRUE(off.stop_on_fault);
}

TEST(DaemonServoSettings, AxesMustMatchTheDevice) {
    device::DeviceInfo three = pen_display(false);
    three.axes = 3;
    try {
        make_servo_config(lab_config(), three, false);
        FAIL() << "expected a ConfigError";
    } catch (const ConfigError& e) {
        EXPECT_NE(
            std::string(e.what()).find("lab.toml: [device] axes = 1 but the sim device has 3"),
            std::string::npos)
            << e.what();
    }
}

// --- hapticd --identify --------------------------------------------------------------

TEST(DaemonServoSettings, IdentifyRunsOpenLoopWithTheSafetyLimitsButNoSoftStartOrRecovery) {
    const servo::ServoConfig s = make_identify_servo_config(lab_config(), pen_display(true), true);
    EXPECT_FALSE(s.coupling_enabled);
    EXPECT_EQ(s.safety.soft_start.still_time_s, 0.0);  // the excitation waits and fades itself
    EXPECT_EQ(s.safety.soft_start.ramp_time_s, 0.0);
    EXPECT_EQ(s.safety.passivity.mode, servo::PassivityMode::observe);  // was "control"
    EXPECT_FALSE(s.link_recovery.enabled);
    EXPECT_TRUE(s.stop_on_fault);
    EXPECT_EQ(s.safety.max_force_n, 8.0);  // still the smaller of config and device
    EXPECT_EQ(s.safety.max_speed_mps, 0.5);
    EXPECT_TRUE(s.telemetry_backpressure);
    EXPECT_NO_THROW(s.validate());
}

Config pen_config(const std::string& identify = "", const std::string& model = "") {
    return parse_config(R"(
[device.model]
mass = 0.1
damping = 2.0
)" + model + R"(
[safety]
max_force = 20
[identify]
)" + identify,
                        "pen.toml", "");
}

device::DeviceInfo strong_pen(int axes = 1) {
    device::DeviceInfo info = pen_display(true);
    info.force_limit_n = 20.0;
    info.axes = axes;
    return info;
}

TEST(DaemonServoSettings, IdentifyChoosesTheBandAndAmplitudeFromTheDeviceModel) {
    const IdentifyPlan plan = make_identify_plan(pen_config(), strong_pen());
    const env::ExcitationSettings& s = plan.excitation;
    const double corner_hz = 2.0 / (2.0 * std::numbers::pi * 0.1);  // 3.18 Hz
    EXPECT_DOUBLE_EQ(s.signal.band_low_hz, corner_hz / 2.0);
    EXPECT_DOUBLE_EQ(s.signal.band_high_hz, 10.0 * corner_hz);
    EXPECT_DOUBLE_EQ(s.signal.period_s, 4.0 / s.signal.band_low_hz);
    EXPECT_EQ(s.signal.sample_rate_hz, 1000.0);
    EXPECT_EQ(s.signal.lines_per_decade, 10.0);
    EXPECT_EQ(s.periods, 4);  // 4 x 2.513 s: about 10 s of whole periods
    EXPECT_NEAR(s.fade_s, 0.5 * 2.513, 1e-12);
    EXPECT_EQ(s.workspace_half_width_m, 0.03);
    EXPECT_EQ(s.force_limit_n, 20.0);
    EXPECT_EQ(s.still_time_s, 0.2);
    // The amplitude is the one for which the model's periodic steady state swings half the
    // workspace. Driven from rest, the prediction is what the sim does from rest (+-14.4 mm,
    // HilIdentify.PenDisplayLogsTheSignalItCommandedAndStaysInTheWorkspace).
    const env::Multisine signal(s.signal);
    EXPECT_NEAR(signal.steady_state_excursion_m(0.1, 2.0), 0.015, 1e-12);
    ASSERT_TRUE(plan.predicted_excursion_m.has_value());
    EXPECT_NEAR(*plan.predicted_excursion_m, 0.0144, 0.00005);
    EXPECT_FALSE(plan.predicted_stuck_fraction.has_value());  // no [device.model] coulomb
    std::cout << "[identify] pen display: force_amplitude " << s.signal.peak_force_n
              << " N, duration " << plan.duration_s << " s\n";
    EXPECT_GT(s.signal.peak_force_n, 0.5);
    EXPECT_LT(s.signal.peak_force_n, 1.0);
    // Still wait + 2 fades (1256.5 ticks, rounded up) + 4 periods + 0.5 s.
    EXPECT_NEAR(plan.duration_s, 0.2 + 2 * 1.257 + 4 * 2.513 + 0.5, 1e-9);
    EXPECT_EQ(plan.chosen.size(), 6u);
    EXPECT_NE(plan.chosen.front().find("band_low = 1.59 Hz (half the corner"), std::string::npos)
        << plan.chosen.front();
}

TEST(DaemonServoSettings, IdentifyTakesWhatTheConfigSays) {
    const IdentifyPlan plan = make_identify_plan(
        pen_config("force_amplitude = 1.5\nworkspace = 0.05\nband_low = 2\nband_high = 40\n"
                   "lines_per_decade = 6\nperiod = 3\nperiods = 2\nfade = 0.25\n"),
        strong_pen());
    const env::ExcitationSettings& s = plan.excitation;
    EXPECT_EQ(s.signal.peak_force_n, 1.5);
    EXPECT_EQ(s.workspace_half_width_m, 0.05);
    EXPECT_EQ(s.signal.band_low_hz, 2.0);
    EXPECT_EQ(s.signal.band_high_hz, 40.0);
    EXPECT_EQ(s.signal.lines_per_decade, 6.0);
    EXPECT_EQ(s.signal.period_s, 3.0);
    EXPECT_EQ(s.periods, 2);
    EXPECT_EQ(s.fade_s, 0.25);
    EXPECT_TRUE(plan.chosen.empty());
    EXPECT_NEAR(plan.duration_s, 0.2 + 0.5 + 6.0 + 0.5, 1e-9);
}

std::string plan_error(const Config& config, const device::DeviceInfo& info) {
    try {
        (void)make_identify_plan(config, info);
    } catch (const ConfigError& e) {
        return e.what();
    }
    return "no error";
}

TEST(DaemonServoSettings, IdentifyRefusesWhatMakesNoSafeSignal) {
    // No model: nothing to size the force from.
    const Config no_model = parse_config("[identify]\nworkspace = 0.02\n", "lab.toml", "");
    EXPECT_NE(plan_error(no_model, strong_pen())
                  .find("lab.toml: [identify] force_amplitude is "
                        "required without [device.model]"),
              std::string::npos)
        << plan_error(no_model, strong_pen());
    // With the force given it uses generic bands: 1 Hz to 30 Hz.
    const Config given = parse_config("[identify]\nforce_amplitude = 0.5\n", "lab.toml", "");
    const IdentifyPlan generic = make_identify_plan(given, strong_pen());
    EXPECT_EQ(generic.excitation.signal.band_low_hz, 1.0);
    EXPECT_EQ(generic.excitation.signal.band_high_hz, 30.0);
    EXPECT_FALSE(generic.predicted_excursion_m.has_value());
    // A band that gives an axis too few lines.
    EXPECT_NE(plan_error(pen_config("band_low = 10\nband_high = 11\n"), strong_pen())
                  .find("pen.toml: [identify] band_low = 10 Hz, band_high = 11 Hz"),
              std::string::npos)
        << plan_error(pen_config("band_low = 10\nband_high = 11\n"), strong_pen());
    // A default band_low above the given band_high.
    EXPECT_NE(plan_error(pen_config("band_high = 1\n"), strong_pen())
                  .find("[identify] band_high = 1 Hz is not above band_low = 1.59 Hz"),
              std::string::npos)
        << plan_error(pen_config("band_high = 1\n"), strong_pen());
    // Three axes at 8 N each would ask more than 20 N of the vector.
    const Config three = parse_config(R"(
[device]
axes = 3
[device.model]
mass = 0.1
damping = 2.0
[safety]
max_force = 20
[identify]
force_amplitude = 15
)",
                                      "lab.toml", "");
    const std::string too_strong = plan_error(three, strong_pen(3));
    EXPECT_NE(too_strong.find("lab.toml: [identify] force_amplitude = 15 N makes a peak force of"),
              std::string::npos)
        << too_strong;
    EXPECT_NE(too_strong.find("above the force limit 20 N"), std::string::npos) << too_strong;
    // The device's own limit counts as well: 8 N < 10 N asked.
    const std::string weak = plan_error(pen_config("force_amplitude = 10\n"), pen_display(true));
    EXPECT_NE(weak.find("above the force limit 8 N"), std::string::npos) << weak;
}

/// The number after `prefix` in `message`.
double number_after(const std::string& message, const std::string& prefix) {
    const std::size_t at = message.find(prefix);
    if (at == std::string::npos) return std::nan("");
    return std::stod(message.substr(at + prefix.size()));
}

TEST(DaemonServoSettings, IdentifyRefusesARunTheModelSaysWouldLeaveTheWorkspace) {
    // 2 N on the pen display: +-38 mm about the start, in a +-10 mm box.
    const std::string error =
        plan_error(pen_config("force_amplitude = 2.0\nworkspace = 0.01\n"), strong_pen());
    EXPECT_NE(error.find("pen.toml: [identify] force_amplitude = 2 N: [device.model] (m = 0.1 "
                         "kg, b = 2 N s/m) predicts the handle swings +-"),
              std::string::npos)
        << error;
    EXPECT_NE(error.find("beyond [identify] workspace = 0.01 m"), std::string::npos) << error;
    EXPECT_NE(error.find("raise [identify] band_low (now 1.59 Hz) or workspace"), std::string::npos)
        << error;
    // The amplitude it names is the largest that stays inside, to the message's digits.
    const double allowed = number_after(error, "Lower force_amplitude to <= ");
    ASSERT_TRUE(std::isfinite(allowed)) << error;
    const auto excursion = [](double amplitude) {
        std::ostringstream identify;
        identify << "force_amplitude = " << amplitude << "\nworkspace = 0.01\n";
        return *make_identify_plan(pen_config(identify.str()), strong_pen()).predicted_excursion_m;
    };
    EXPECT_LE(excursion(allowed), 0.01);
    EXPECT_GT(excursion(allowed), 0.0098);
    EXPECT_NE(plan_error(pen_config("force_amplitude = " + std::to_string(1.02 * allowed) +
                                    "\nworkspace = 0.01\n"),
                         strong_pen()),
              "no error");
}

TEST(DaemonServoSettings, IdentifyRefusesARunFrictionWouldHoldStillTooLong) {
    // 0.2 N of friction (the sim pen of the identification tests) under 0.3 N peaks: the
    // handle sticks after most periods. haptic-tune identify refuses a log above 25 %.
    const std::string error =
        plan_error(pen_config("force_amplitude = 0.3\n", "coulomb = 0.2\n"), strong_pen());
    EXPECT_NE(error.find("pen.toml: [identify] force_amplitude = 0.3 N: [device.model] (m = 0.1 "
                         "kg, b = 2 N s/m, coulomb = 0.2 N) predicts Coulomb friction holds the "
                         "handle still after "),
              std::string::npos)
        << error;
    EXPECT_NE(error.find("haptic-tune identify refuses a run stuck above 25 %"), std::string::npos)
        << error;
    const double needed = number_after(error, "Raise force_amplitude to >= ");
    ASSERT_TRUE(std::isfinite(needed)) << error;
    const auto stuck = [](double amplitude) {
        return *make_identify_plan(
                    pen_config("force_amplitude = " + std::to_string(amplitude) + "\n",
                               "coulomb = 0.2\n"),
                    strong_pen())
                    .predicted_stuck_fraction;
    };
    EXPECT_LE(stuck(needed), 0.25);
    EXPECT_NE(plan_error(pen_config("force_amplitude = " + std::to_string(0.98 * needed) + "\n",
                                    "coulomb = 0.2\n"),
                         strong_pen()),
              "no error");
    // The default amplitude (half the workspace) keeps the pen moving: 15 % stuck, as the
    // sim measures it (docs/identification-excitation.md).
    const IdentifyPlan plan = make_identify_plan(pen_config("", "coulomb = 0.2\n"), strong_pen());
    ASSERT_TRUE(plan.predicted_stuck_fraction.has_value());
    std::cout << "[identify] pen display with 0.2 N of friction at the default amplitude: "
              << *plan.predicted_stuck_fraction << " of the periods stuck\n";
    EXPECT_GT(*plan.predicted_stuck_fraction, 0.05);
    EXPECT_LT(*plan.predicted_stuck_fraction, 0.25);
    // Where no amplitude within the workspace keeps it moving, it says so.
    const std::string boxed = plan_error(
        pen_config("force_amplitude = 0.2\nworkspace = 0.002\n", "coulomb = 0.2\n"), strong_pen());
    EXPECT_NE(boxed.find("No force_amplitude up to "), std::string::npos) << boxed;
    EXPECT_NE(boxed.find("widen [identify] workspace"), std::string::npos) << boxed;
}

TEST(DaemonServoSettings, IdentifyDefaultAmplitudeRespectsTheForceLimitOnEveryAxis) {
    // A wide workspace: the workspace rule would allow more than half the force limit.
    const Config three = parse_config(R"(
[device]
axes = 3
[device.model]
mass = 0.1
damping = 2.0
[safety]
max_force = 2
[identify]
workspace = 1.0
)",
                                      "lab.toml", "");
    const IdentifyPlan plan = make_identify_plan(three, strong_pen(3));
    const env::Multisine signal(plan.excitation.signal);
    EXPECT_NEAR(signal.peak_vector_norm_n(), 1.0, 1e-12);  // half of 2 N
    EXPECT_NE(plan.chosen.back().find("half a period"), std::string::npos);
}

}  // namespace
}  // namespace hapticd::daemon
