// One schema: the config's keys and the servo layer's settings cannot disagree. Each test
// reproduces a disagreement that existed before the config had one reader (docs/architecture.md
// §2.3): the rate's three ranges, max_force's defaults (10 N here, 5 N in SafetyLimits) and
// reconnect's (on here, off in LinkRecoverySettings).
#include <gtest/gtest.h>

#include <string>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/servo_settings.hpp"
#include "hapticd/device/plugin_loader.hpp"

namespace hapticd::daemon {
namespace {

bool config_accepts(const std::string& text) {
    try {
        (void)parse_config(text, "lab.toml", "");
        return true;
    } catch (const ConfigError&) {
        return false;
    }
}

device::DeviceInfo sim_info() {
    device::DeviceInfo info;
    info.counts_per_meter = 1e5;
    info.lockstep = true;
    info.paces_loop = true;
    info.name = "sim";
    return info;
}

const std::string kCoupled = "[coupling]\nstiffness = 1000\n";

// One key, one range: what the config takes, the servo loop takes, at either end.
TEST(DaemonConfigSchema, TheRateHasOneRange) {
    for (const double rate : {99.0, 100.0, 20000.0, 20001.0, 50.0, 1.0, 100000.0}) {
        SCOPED_TRACE(rate);
        const std::string text = "[servo]\nrate_hz = " + std::to_string(rate) + "\n" + kCoupled;
        servo::ServoConfig servo;
        servo.rate_hz = rate;
        servo.counts_per_meter = 1e5;
        servo.coupling.stiffness_n_per_m = 1000.0;
        servo.realtime.mode = servo::RealtimeMode::off;
        std::string why;
        EXPECT_EQ(config_accepts(text), servo.is_valid(&why)) << why;
        EXPECT_EQ(config_accepts(text), rate >= 100.0 && rate <= 20000.0);
    }
}

TEST(DaemonConfigSchema, EachDefaultIsTheServosOwn) {
    const Config defaults = parse_config(kCoupled, "lab.toml", "");
    const servo::ServoConfig servo;
    EXPECT_EQ(defaults.safety.max_force_n, 10.0);
    EXPECT_EQ(defaults.safety.max_force_n, servo.safety.max_force_n);
    EXPECT_TRUE(defaults.safety.reconnect.enabled);
    EXPECT_EQ(defaults.safety.reconnect.enabled, servo.link_recovery.enabled);
    EXPECT_EQ(defaults.safety.reconnect.settle_s, servo.link_recovery.settle_s);
    EXPECT_EQ(defaults.safety.reconnect.timeout_s, servo.link_recovery.timeout_s);
    EXPECT_EQ(defaults.safety.max_speed_mps, servo.safety.max_speed_mps);
    EXPECT_EQ(defaults.safety.soft_start.ramp_time_s, servo.safety.soft_start.ramp_time_s);
    EXPECT_EQ(defaults.safety.passivity, servo.safety.passivity.mode);
    EXPECT_EQ(defaults.safety.overrun.max_missed_periods, servo.overrun.max_missed_periods);
    EXPECT_EQ(defaults.safety.overrun.max_consecutive_overruns,
              servo.overrun.max_consecutive_overruns);
    EXPECT_EQ(defaults.servo.rate_hz, servo.rate_hz);
    EXPECT_EQ(defaults.servo.realtime, servo.realtime.mode);
    EXPECT_EQ(defaults.servo.priority, servo.realtime.priority);
    EXPECT_EQ(defaults.coupling.enabled, servo.coupling_enabled);
    // A Config that was never parsed holds the same defaults.
    const Config unparsed;
    EXPECT_EQ(unparsed.safety.max_force_n, defaults.safety.max_force_n);
    EXPECT_EQ(unparsed.safety.reconnect.enabled, defaults.safety.reconnect.enabled);
    EXPECT_EQ(unparsed.servo.rate_hz, defaults.servo.rate_hz);
    EXPECT_EQ(unparsed.coupling.check, defaults.coupling.check);
    // And the servo loop gets them: the force limit of a device without one of its own.
    const servo::ServoConfig made = make_servo_config(defaults, sim_info(), false);
    EXPECT_EQ(made.safety.max_force_n, 10.0);
    EXPECT_TRUE(made.link_recovery.enabled);
}

// The servo configuration is valid as a whole before the servo thread exists: a limit or a
// real-time request the servo layer would refuse is a config error naming the file.
TEST(DaemonConfigSchema, TheServoConfigurationIsCheckedBeforeTheLoop) {
    device::DeviceInfo info = sim_info();
    info.lockstep = false;
    info.paces_loop = false;
    const Config config =
        parse_config("[servo]\nrealtime = \"warn\"\ncpu = 1023\n" + kCoupled, "lab.toml", "");
    try {
        (void)make_servo_config(config, info, false);
        FAIL() << "a CPU this machine does not have was accepted";
    } catch (const ConfigError& e) {
        const std::string message = e.what();
        EXPECT_EQ(message.rfind("lab.toml: servo config: realtime.cpu = 1023 is out of range: "
                                "allowed -1 (none) or 0..",
                                0),
                  0u)
            << message;
        EXPECT_NE(message.find("(this machine's CPUs)"), std::string::npos) << message;
    }
    // check = "off" with no gains runs no check, but the servo loop still needs a coupling.
    const Config unchecked = parse_config("[coupling]\ncheck = \"off\"\n", "lab.toml", "");
    try {
        (void)make_servo_config(unchecked, sim_info(), false);
        FAIL() << "a coupling of zero was accepted";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("coupling.stiffness_n_per_m = 0 is out of range"),
                  std::string::npos)
            << e.what();
    }
}

// A plugin's table reaches the plugin where it is in the file: its errors carry the line,
// as the daemon's and a scene's do.
TEST(DaemonConfigSchema, APluginsErrorsCarryTheLineInTheConfig) {
    const Config config = parse_config(
        "[servo]\nrate_hz = 1000\n\n[device]\nplugin = \"sim\"\n\n[device.sim]\nmass = 0.1\n"
        "damping = -2\n[device.sim.human]\nmodel = \"heavy-hand\"\nhand_mas = 1\n" +
            kCoupled,
        "lab.toml", "");
    EXPECT_EQ(config.device.plugin_table_path, "device.sim");
    device::DeviceHandle sim = device::load_device(config.device.plugin);
    device::DeviceConfig device_config;
    device_config.plugin_table_toml = config.device.plugin_table_toml;
    device_config.plugin_table_path = config.device.plugin_table_path;
    device_config.source = config.source;
    try {
        sim->open(device_config);
        FAIL() << "damping = -2 accepted";
    } catch (const std::exception& e) {
        EXPECT_EQ(std::string(e.what()),
                  "lab.toml:9: [device.sim] damping = -2 is out of range: allowed >= 0 and <= "
                  "1e+06 (N s/m)");
    }
    sim->close();
    device_config.plugin_table_toml.replace(device_config.plugin_table_toml.find("-2"), 2, "2");
    try {
        sim->open(device_config);
        FAIL() << "hand_mas accepted";
    } catch (const std::exception& e) {
        EXPECT_EQ(std::string(e.what()).rfind(
                      "lab.toml:12: [device.sim.human] hand_mas = 1 is not a known key: allowed "
                      "model, hand_mass",
                      0),
                  0u)
            << e.what();
    }
    sim->close();
}

TEST(DaemonConfigSchema, ModeStringsAreEnumsOnceRead) {
    const Config c = parse_config(
        "[servo]\nrealtime = \"off\"\n[coupling]\ncheck = \"encoder\"\nstiffness = 1\n"
        "[safety]\npassivity = \"control\"\n",
        "lab.toml", "");
    EXPECT_EQ(c.servo.realtime, servo::RealtimeMode::off);
    EXPECT_EQ(c.coupling.check, tune::StabilityModel::encoder);
    EXPECT_EQ(c.safety.passivity, servo::PassivityMode::control);
    EXPECT_EQ(to_string(CheckModel{}), "off");
    EXPECT_EQ(to_string(EnvironmentClass::every_passive), "every-passive");
}

}  // namespace
}  // namespace hapticd::daemon
