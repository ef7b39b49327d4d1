// From the daemon's config and the device's self-description to the servo loop's settings.
#include "hapticd/daemon/servo_settings.hpp"

#include <gtest/gtest.h>

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

    const Config strict = parse_config("[safety]\nreconnect = false\n", "lab.toml", "");
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

}  // namespace
}  // namespace hapticd::daemon
