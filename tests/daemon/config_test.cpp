// hapticd's config file: every key of docs/daemon.md "Config" (docs/architecture.md §5.3),
// checked for type and range.
#include "hapticd/daemon/config.hpp"

#include <gtest/gtest.h>

#include <string>

namespace hapticd::daemon {
namespace {

std::string error_of(const std::string& text) {
    try {
        parse_config(text, "lab.toml", "/etc/hapticd");
    } catch (const ConfigError& e) {
        return e.what();
    }
    return "no error";
}

TEST(DaemonConfig, ReadsEveryKey) {
    const Config c = parse_config(R"(
[servo]
rate_hz = 2000
realtime = "enforce"
priority = 90
cpu = 1
[device]
plugin = "sim"
axes = 3
[device.model]
mass = 0.2
damping = 3.5
[device.sim]
mass = 0.25
[coupling]
stiffness = 5000
damping = 0.5
velocity_filter = 300
check = "exact"
[scene]
file = "scenes/box.toml"
[safety]
max_force = 12
max_speed = 0.5
soft_start_ramp = 0.25
passivity = "control"
reconnect = true
reconnect_settle = 1.5
reconnect_timeout = 30
)",
                                  "lab.toml", "/etc/hapticd");
    EXPECT_EQ(c.servo.rate_hz, 2000.0);
    EXPECT_EQ(c.servo.realtime, servo::RealtimeMode::enforce);
    EXPECT_EQ(c.servo.priority, 90);
    EXPECT_EQ(c.servo.cpu, 1);
    EXPECT_EQ(c.device.plugin, "sim");
    EXPECT_EQ(c.device.axes, 3);
    EXPECT_EQ(c.device.model.mass_kg, 0.2);
    EXPECT_EQ(c.device.model.damping_n_s_per_m, 3.5);
    EXPECT_NE(c.device.plugin_table_toml.find("mass = 0.25"), std::string::npos);
    EXPECT_EQ(c.coupling.stiffness_n_per_m, 5000.0);
    EXPECT_EQ(c.coupling.damping_n_s_per_m, 0.5);
    EXPECT_EQ(c.coupling.velocity_filter_hz, 300.0);
    EXPECT_EQ(c.coupling.check, tune::StabilityModel::exact);
    EXPECT_EQ(c.scene_file, "/etc/hapticd/scenes/box.toml");
    EXPECT_EQ(c.safety.max_force_n, 12.0);
    EXPECT_EQ(c.safety.max_speed_mps, 0.5);
    EXPECT_EQ(c.safety.soft_start.ramp_time_s, 0.25);
    EXPECT_EQ(c.safety.passivity, servo::PassivityMode::control);
    EXPECT_TRUE(c.safety.reconnect.enabled);
    EXPECT_EQ(c.safety.reconnect.settle_s, 1.5);
    EXPECT_EQ(c.safety.reconnect.timeout_s, 30.0);
    EXPECT_TRUE(c.coupling.enabled);
}

TEST(DaemonConfig, ReconnectIsOnByDefaultAndCanBeTurnedOffOrMadePatient) {
    const Config defaults = parse_config("", "lab.toml", "");
    EXPECT_TRUE(defaults.safety.reconnect.enabled);
    EXPECT_EQ(defaults.safety.reconnect.settle_s, 0.5);
    EXPECT_EQ(defaults.safety.reconnect.timeout_s, 5.0);
    EXPECT_FALSE(
        parse_config("[safety]\nreconnect = false\n", "lab.toml", "").safety.reconnect.enabled);
    EXPECT_EQ(parse_config("[safety]\nreconnect_timeout = 0\n", "lab.toml", "")
                  .safety.reconnect.timeout_s,
              0.0);  // wait for ever
    EXPECT_EQ(
        parse_config("[safety]\nreconnect_settle = 60\nreconnect_timeout = 61\n", "lab.toml", "")
            .safety.reconnect.settle_s,
        60.0);
}

TEST(DaemonConfig, TheOverrunBudgetIsASafetyKeyWithItsDefault) {
    const Config defaults = parse_config("", "lab.toml", "");
    EXPECT_EQ(defaults.safety.overrun.max_missed_periods, 20);
    EXPECT_EQ(defaults.safety.overrun.max_consecutive_overruns, 5);
    const Config patient = parse_config(
        "[safety]\nmax_missed_periods = 100\nmax_consecutive_overruns = 0\n", "lab.toml", "");
    EXPECT_EQ(patient.safety.overrun.max_missed_periods, 100);
    EXPECT_EQ(patient.safety.overrun.max_consecutive_overruns, 0);
}

TEST(DaemonConfig, NoCouplingMustBeDeliberate) {
    const Config c = parse_config("[coupling]\nenabled = false\ncheck = \"off\"\n", "lab.toml", "");
    EXPECT_FALSE(c.coupling.enabled);
    EXPECT_EQ(c.coupling.check, std::nullopt);  // "off"
}

TEST(DaemonConfig, DefaultsFillWhatIsMissing) {
    const Config c = parse_config("", "empty.toml", "");
    EXPECT_EQ(c.servo.rate_hz, 1000.0);
    EXPECT_EQ(c.servo.realtime, servo::RealtimeMode::warn);
    EXPECT_FALSE(c.servo.cpu.has_value());
    EXPECT_EQ(c.device.plugin, "sim");
    EXPECT_EQ(c.coupling.check, tune::StabilityModel::passive);
    EXPECT_EQ(c.coupling.velocity_filter_hz, 0.0);  // no filter: the damper on v_d - v_e
    EXPECT_EQ(c.device.model.delay_s, 0.0);
    EXPECT_TRUE(c.scene_file.empty());
}

struct Bad {
    std::string text;
    std::string must_contain;
};
class DaemonConfigRejects : public ::testing::TestWithParam<Bad> {};
void PrintTo(const Bad& b, std::ostream* os) { *os << b.text; }

TEST_P(DaemonConfigRejects, NamingTheFileTheKeyTheValueAndTheRange) {
    const std::string message = error_of(GetParam().text);
    EXPECT_NE(message.find("lab.toml"), std::string::npos) << message;
    EXPECT_NE(message.find(GetParam().must_contain), std::string::npos) << message;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, DaemonConfigRejects,
    ::testing::Values(
        Bad{"[servo]\nrate_hz = 50\n",
            "[servo] rate_hz = 50 is out of range: allowed >= 100 and <= 20000 (Hz)"},
        Bad{"[servo]\nrate_hz = \"fast\"\n",
            "[servo] rate_hz = \"fast\" is not a number: allowed >= 100 and <= 20000 (Hz)"},
        Bad{"[servo]\nrealtime = \"always\"\n", "[servo] realtime = \"always\" is not allowed"},
        Bad{"[servo]\npriority = 0\n", "[servo] priority = 0 is out of range: allowed 1..99"},
        Bad{"[servo]\nname = \"" + std::string(65, 'x') + "\"\n",
            "[servo] name = \"" + std::string(65, 'x') +
                "\" is too long (65 bytes): allowed free text, at most 64 bytes"},
        Bad{"[servo]\nname = \"left\\narm\"\n",
            "[servo] name = \"left\\x0aarm\" holds a control character at byte 5: allowed free "
            "text, at most 64 bytes without control characters"},
        Bad{"[servo]\nname = 3\n", "[servo] name = 3 is not a string: allowed free text"},
        Bad{"[servo]\nrate = 1000\n",
            "lab.toml:2: [servo] rate = 1000 is not a known key: allowed name, rate_hz, "
            "realtime, priority, cpu"},
        Bad{"[device]\naxes = 4\n", "[device] axes = 4 is out of range: allowed 1..3"},
        Bad{"[device]\nplugin = \"sim\"\n[device.usb]\nvid = 1\n",
            "lab.toml:3: [device.usb] is not a known table: allowed plugin, axes, [device.model], "
            "[device.sim]"},
        Bad{"[device.model]\nmass = -1\n",
            "[device.model] mass = -1 is out of range: allowed >= 0.0001 and <= 1000 (kg)"},
        Bad{"[device.model]\nmass = 1e-20\n", "[device.model] mass = 1e-20 is out of range"},
        Bad{"[device.model]\ndelay = -0.001\n",
            "[device.model] delay = -0.001 is out of range: allowed >= 0 and < 0.01 (s: 10 periods "
            "at "
            "[servo] rate_hz = 1000)"},
        Bad{"[device.model]\ndelay = nan\n", "[device.model] delay = nan is out of range"},
        Bad{"[coupling]\nstiffness = 2e9\n",
            "[coupling] stiffness = 2e+09 is out of range: allowed >= 0 and <= 1e+09 (N/m)"},
        Bad{"[coupling]\ndamping = 1e307\n",
            "[coupling] damping = 1e+307 is out of range: allowed >= 0 and <= 100000 (N s/m)"},
        Bad{"[device.model]\ndelay = 0.01\n",
            "[device.model] delay = 0.01 is out of range: allowed >= 0 and < 0.01 (s: 10 "
            "periods at [servo] rate_hz = 1000)"},
        Bad{"[device.model]\ndamping = nan\n", "[device.model] damping = nan"},
        Bad{"[device.model]\ninertia = 1\n",
            "[device.model] inertia = 1 is not a known key: allowed mass, damping, coulomb, delay"},
        Bad{"[coupling]\nstiffness = -3\n",
            "[coupling] stiffness = -3 is out of range: allowed >= 0 and <= 1e+09 (N/m)"},
        Bad{"[coupling]\ncheck = \"none\"\n", "[coupling] check = \"none\" is not allowed"},
        Bad{"[safety]\nmax_force = 0\n",
            "[safety] max_force = 0 is out of range: allowed > 0 and <= 10000 (N)"},
        Bad{"[safety]\nmax_torque = 1\n", "[safety] max_torque = 1 is not a known key"},
        Bad{"[telemetry]\nfile = \"x\"\n",
            "lab.toml:1: [telemetry] is not a known table: allowed [servo], [device], [coupling], "
            "[operator], [scene], [safety], [identify]"},
        Bad{"rate_hz = 1000\n", "lab.toml:1: rate_hz = 1000 is not a known key: allowed [servo]"},
        Bad{"[servo\n", "lab.toml:1"},
        Bad{"[coupling]\nenabled = false\n", "set check = \"off\" to run it deliberately"},
        Bad{"[coupling]\nenabled = false\ncheck = \"off\"\nstiffness = 100\n",
            "[coupling] stiffness has no effect with enabled = false"},
        Bad{"[coupling]\nenabled = 1\n",
            "[coupling] enabled = 1 is not a boolean: allowed true or false"},
        Bad{"[coupling]\nvelocity_filter = 500\n",
            "[coupling] velocity_filter = 500 is out of range: allowed 0 (no filter) or >= 1 and "
            "< 500 (Hz, below Nyquist: [servo] rate_hz = 1000)"},
        Bad{"[coupling]\nvelocity_filter = 0.5\n",
            "[coupling] velocity_filter = 0.5 is out of range: allowed 0 (no filter) or >= 1"},
        Bad{"[servo]\nrate_hz = 400\n[coupling]\nvelocity_filter = 250\n",
            "[coupling] velocity_filter = 250 is out of range: allowed 0 (no filter) or >= 1 and "
            "< 200 (Hz, below Nyquist: [servo] rate_hz = 400)"},
        Bad{"[coupling]\nvelocity_filter = -5\n",
            "[coupling] velocity_filter = -5 is out of range: allowed 0 (no filter) or >= 1 and "
            "< 500 (Hz, below Nyquist: [servo] rate_hz = 1000)"},
        Bad{"[coupling]\nvelocity_filter = \"fast\"\n",
            "[coupling] velocity_filter = \"fast\" is not a number"},
        Bad{"[coupling]\nenabled = false\ncheck = \"off\"\nvelocity_filter = 100\n",
            "[coupling] velocity_filter has no effect with enabled = false"},
        Bad{"[safety]\nsoft_start_ramp = 20\n",
            "[safety] soft_start_ramp = 20 is out of range: allowed >= 0 and <= 10 (s)"},
        Bad{"[safety]\npassivity = \"on\"\n", "[safety] passivity = \"on\" is not allowed"},
        Bad{"[safety]\nreconnect = \"yes\"\n",
            "[safety] reconnect = \"yes\" is not a boolean: allowed true or false"},
        Bad{"[safety]\narm_at_start = \"no\"\n",
            "[safety] arm_at_start = \"no\" is not a boolean: allowed true or false"},
        Bad{"[safety]\nreconnect_settle = 0\n",
            "[safety] reconnect_settle = 0 is out of range: allowed > 0 and <= 60 (s)"},
        Bad{"[safety]\nreconnect_settle = 61\n",
            "[safety] reconnect_settle = 61 is out of range: allowed > 0 and <= 60 (s)"},
        // toml++ 3.3 recursed once per part of a dotted key: 35,000 overflowed the stack.
        Bad{"[servo]\n" + std::string("a") +
                [] {
                    std::string k;
                    for (int i = 0; i < 35000; ++i) k += ".a";
                    return k;
                }() +
                " = 1\n",
            "lab.toml:2: a key of more than 32 dotted parts (allowed at most 32)"},
        Bad{"[safety]\nmax_speed = 1e308\n",
            "[safety] max_speed = 1e+308 is out of range: allowed > 0 and <= 100 (m/s)"},
        Bad{"[safety]\nmax_force = 1e6\n",
            "[safety] max_force = 1e+06 is out of range: allowed > 0 and <= 10000 (N)"},
        Bad{"[safety]\nmax_missed_periods = -1\n",
            "[safety] max_missed_periods = -1 is out of range: allowed 0..1000000"},
        Bad{"[safety]\nmax_consecutive_overruns = 2.5\n",
            "[safety] max_consecutive_overruns = 2.5 is not an integer: allowed 0..1000000"},
        Bad{"[safety]\nreconnect_timeout = -1\n",
            "[safety] reconnect_timeout = -1 is out of range: allowed >= 0 and <= 3600 (s; 0: "
            "wait for ever)"},
        Bad{"[safety]\nreconnect_timeout = 0.5\n",
            "[safety] reconnect_timeout = 0.5 is out of range: allowed > reconnect_settle = 0.5"},
        Bad{"[safety]\nreconnect_settle = 2\nreconnect_timeout = 1\n",
            "[safety] reconnect_timeout = 1 is out of range: allowed > reconnect_settle = 2"},
        Bad{"[safety]\nreconnect = false\nreconnect_timeout = 10\n",
            "[safety] reconnect_timeout has no effect with reconnect = false"},
        Bad{"[safety]\nreconnect = false\nreconnect_settle = 1\n",
            "[safety] reconnect_settle has no effect with reconnect = false"}));

// [operator]: a declared operator class (tune/operator_class.hpp), and [coupling]
// environments. A class needs every bound, the exact model, and a non-empty range.
const std::string kExact = "[coupling]\ncheck = \"exact\"\n";
const std::string kClass =
    "[operator]\nhand_mass = [0.1, 2]\ngrip_stiffness = [0, 3000]\ngrip_damping = [2, 30]\n"
    "arm_stiffness = [0, 1000]\n";

TEST(DaemonConfig, ReadsAnOperatorClass) {
    const Config c = parse_config(kExact + kClass + "arm_damping = 5\nmax_resonance = 40\n",
                                  "lab.toml", "/etc/hapticd");
    ASSERT_TRUE(c.operators);
    EXPECT_EQ(c.operators->hand_mass_kg.min, 0.1);
    EXPECT_EQ(c.operators->hand_mass_kg.max, 2.0);
    EXPECT_EQ(c.operators->grip_stiffness_n_per_m.max, 3000.0);
    EXPECT_EQ(c.operators->arm_damping_n_s_per_m.min, 5.0);  // one number: [5, 5]
    EXPECT_EQ(c.operators->arm_damping_n_s_per_m.max, 5.0);
    EXPECT_EQ(c.operators->max_resonance_hz, 40.0);
    EXPECT_EQ(c.coupling.environments, EnvironmentClass::every_passive);
    EXPECT_FALSE(parse_config("", "lab.toml", "/etc/hapticd").operators);
    EXPECT_EQ(parse_config("[coupling]\nenvironments = \"scene\"\n", "lab.toml", "/etc/hapticd")
                  .coupling.environments,
              EnvironmentClass::scene);
}

INSTANTIATE_TEST_SUITE_P(
    OperatorClass, DaemonConfigRejects,
    ::testing::Values(
        Bad{kExact + "[operator]\n", "[operator] is empty: declare hand_mass, grip_stiffness"},
        Bad{kExact + kClass, "[operator] arm_damping is missing"},
        Bad{"[operator]\nhand_mass = [0.1, 2]\n",
            "[operator] declares an operator class, which only [coupling] check = \"exact\" "
            "can use, but check = \"passive\" (the passive model holds for every passive "
            "operator)"},
        Bad{kExact + kClass + "arm_damping = [20, 0]\n",
            "[operator] arm_damping = [20, 0] is an empty range"},
        Bad{kExact + kClass + "arm_damping = nan\n", "[operator] arm_damping = nan N s/m is out"},
        Bad{kExact + kClass + "arm_damping = [0, 1, 2]\n",
            "[operator] arm_damping = [0, 1, 2] is not a number or an array [min, max] of two "
            "numbers: allowed a number or [min, max] (N s/m)"},
        Bad{kExact + kClass + "arm_damping = \"low\"\n",
            "[operator] arm_damping = \"low\" is not a number or an array"},
        Bad{kExact + kClass + "arm_damping = 0\nhand_size = 1\n",
            "[operator] hand_size = 1 is not a known key"},
        Bad{kExact + "[operator]\nhand_mass = [0.1, 2]\ngrip_stiffness = [500, 3000]\n"
                     "grip_damping = 2\narm_stiffness = 0\narm_damping = 0\nmax_resonance = 1\n",
            "max_resonance = 1 Hz contradicts the ranges"},
        Bad{kExact + kClass + "arm_damping = 0\nmax_resonance = 0\n",
            "[operator] max_resonance = 0 is out of range: allowed > 0"},
        Bad{"[coupling]\nenvironments = \"walls\"\n",
            "[coupling] environments = \"walls\" is not allowed"},
        Bad{"[coupling]\ncheck = \"encoder\"\nenvironments = \"scene\"\n",
            "[coupling] environments = \"scene\" needs check = \"passive\" or \"exact\""}));

// [identify]: the excitation of hapticd --identify; every key is checked like the others.
TEST(DaemonConfig, ReadsTheIdentifyTable) {
    const Config c = parse_config(R"(
[servo]
rate_hz = 2000
[safety]
max_force = 8
[identify]
force_amplitude = 1.5
workspace = 0.04
band_low = 2
band_high = 40
lines_per_decade = 12
period = 3
periods = 5
fade = 0.75
)",
                                  "lab.toml", "");
    EXPECT_EQ(c.identify.force_amplitude_n, 1.5);
    EXPECT_EQ(c.identify.workspace_m, 0.04);
    EXPECT_EQ(c.identify.band_low_hz, 2.0);
    EXPECT_EQ(c.identify.band_high_hz, 40.0);
    EXPECT_EQ(c.identify.lines_per_decade, 12.0);
    EXPECT_EQ(c.identify.period_s, 3.0);
    EXPECT_EQ(c.identify.periods, 5);
    EXPECT_EQ(c.identify.fade_s, 0.75);
}

TEST(DaemonConfig, IdentifyLeavesUnsetValuesToTheStartUp) {
    const Config c = parse_config("", "empty.toml", "");
    EXPECT_FALSE(c.identify.force_amplitude_n.has_value());
    EXPECT_EQ(c.identify.workspace_m, 0.03);
    EXPECT_FALSE(c.identify.band_low_hz.has_value());
    EXPECT_FALSE(c.identify.band_high_hz.has_value());
    EXPECT_EQ(c.identify.lines_per_decade, 10.0);
    EXPECT_FALSE(c.identify.period_s.has_value());
    EXPECT_FALSE(c.identify.periods.has_value());
    EXPECT_FALSE(c.identify.fade_s.has_value());
}

INSTANTIATE_TEST_SUITE_P(
    Identify, DaemonConfigRejects,
    ::testing::Values(
        Bad{"[identify]\nforce_amplitud = 1\n", "[identify] force_amplitud = 1 is not a known key"},
        Bad{"[identify]\nseed = 3\n", "[identify] seed = 3 is not a known key"},
        Bad{"[identify]\nforce_amplitude = 0\n",
            "[identify] force_amplitude = 0 is out of range: allowed > 0"},
        Bad{"[identify]\nforce_amplitude = \"big\"\n",
            "[identify] force_amplitude = \"big\" is not a number: allowed > 0 and <= 10000 (N)"},
        Bad{"[safety]\nmax_force = 5\n[identify]\nforce_amplitude = 6\n",
            "[identify] force_amplitude = 6 is out of range: allowed <= [safety] max_force = 5"},
        Bad{"[identify]\nworkspace = 0\n",
            "[identify] workspace = 0 is out of range: allowed > 0 and <= 1 (m)"},
        Bad{"[identify]\nworkspace = 2\n", "[identify] workspace = 2 is out of range"},
        Bad{"[identify]\nband_low = -1\n", "[identify] band_low = -1 is out of range"},
        Bad{"[identify]\nband_high = 200\n",
            "[identify] band_high = 200 is out of range: allowed > 0 and <= 100 (Hz, rate_hz/10 "
            "at most)"},
        Bad{"[servo]\nrate_hz = 500\n[identify]\nband_high = 60\n",
            "[identify] band_high = 60 is out of range: allowed > 0 and <= 50"},
        Bad{"[identify]\nband_low = 10\nband_high = 5\n",
            "[identify] band_high = 5 is out of range: allowed > band_low = 10 (Hz)"},
        Bad{"[identify]\nlines_per_decade = 0.5\n",
            "[identify] lines_per_decade = 0.5 is out of range: allowed >= 1 and <= 50"},
        Bad{"[identify]\nperiod = 0\n", "[identify] period = 0 is out of range"},
        Bad{"[identify]\nperiod = 100\n", "[identify] period = 100 is out of range"},
        Bad{"[identify]\nperiods = 2.5\n",
            "[identify] periods = 2.5 is not an integer: allowed 1..1000"},
        Bad{"[identify]\nperiods = 0\n", "[identify] periods = 0 is out of range: allowed 1..1000"},
        Bad{"[identify]\nfade = -1\n", "[identify] fade = -1 is out of range"},
        Bad{"[identify]\nfade = true\n",
            "[identify] fade = true is not a number: allowed >= 0 and <= 60 (s)"},
        Bad{"identify = 1\n",
            "lab.toml:1: identify = 1 is not a table: allowed a table [identify]"}));

TEST(DaemonConfig, EmbeddedDefaultIsTheSimulatedDeviceAndTheDemoWall) {
    const Config c = default_config();
    EXPECT_EQ(c.source, "<embedded default>");
    EXPECT_EQ(c.device.plugin, "sim");
    EXPECT_TRUE(c.scene_file.empty());  // the compiled-in demo scene
    EXPECT_GT(c.coupling.stiffness_n_per_m, 0.0);
    EXPECT_FALSE(default_scene_text().empty());
}

}  // namespace
}  // namespace hapticd::daemon
