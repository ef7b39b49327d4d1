// The [device.sim] table: defaults, every key read, and errors that name the file, the key,
// the value and the allowed range.
#include "hapticd/device/sim/sim_config.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "hapticd/device/sim/sim_device.hpp"

namespace hapticd::device::sim {
namespace {

DeviceConfig config(const std::string& toml, int axes = 1) {
    DeviceConfig c;
    c.axes = axes;
    c.rate_hz = 2000.0;
    c.plugin_table_toml = toml;
    c.source = "lab.toml";
    return c;
}

/// The message of the runtime_error parse_sim_config throws; fails the test if none.
std::string error_of(const std::string& toml, int axes = 1) {
    try {
        parse_sim_config(config(toml, axes));
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    ADD_FAILURE() << "no error for:\n" << toml;
    return {};
}

TEST(SimConfig, EmptyTableGivesTheDefaults) {
    const SimConfig c = parse_sim_config(config(""));
    EXPECT_EQ(c.axes, 1);
    EXPECT_EQ(c.rate_hz, 2000.0);
    EXPECT_EQ(c.mass_kg, 0.1);
    EXPECT_EQ(c.damping_n_s_per_m, 2.0);
    EXPECT_EQ(c.counts_per_meter, 1e5);
    EXPECT_EQ(c.force_limit_n, 20.0);
    EXPECT_EQ(c.coulomb_n, 0.0);
    EXPECT_EQ(c.clock, SimClock::realtime);
    EXPECT_EQ(c.delay_s, 0.0);
    EXPECT_EQ(c.human[0].family, HumanFamily::hands_off);
    EXPECT_FALSE(c.faults.any());
}

TEST(SimConfig, EveryKeyIsRead) {
    const SimConfig c = parse_sim_config(config(R"(
mass = 0.25
damping = 3
counts_per_meter = 40000.0
force_limit = 8.0
coulomb = 0.1
clock = "lockstep"
delay = 0.0013
initial_position = [0.01, -0.02]
[human]
model = "two-mass-grasp"
hand_mass = 0.4
skin_stiffness = 5000.0
skin_damping = 2.0
arm_stiffness = 300.0
arm_damping = 6.0
set_point = 0.005
push = { to = 0.015, start = 0.5, ramp = 0.25, hold = 1.0 }
[faults]
disconnect_at = 9.0
stale_at = 1.0
stale_for = 0.1
jump_at = 2.0
jump_counts = -300
jump_axis = 1
drop_at = [0.5, 0.75]
drop_probability = 0.01
late_at = [0.3]
late_probability = 0.02
late_by = 0.002
seed = 99
)",
                                                2));
    EXPECT_EQ(c.mass_kg, 0.25);
    EXPECT_EQ(c.damping_n_s_per_m, 3.0);
    EXPECT_EQ(c.counts_per_meter, 40000.0);
    EXPECT_EQ(c.force_limit_n, 8.0);
    EXPECT_EQ(c.coulomb_n, 0.1);
    EXPECT_EQ(c.clock, SimClock::lockstep);
    EXPECT_EQ(c.delay_s, 0.0013);
    EXPECT_EQ(c.initial_position_m[0], 0.01);
    EXPECT_EQ(c.initial_position_m[1], -0.02);
    for (int i = 0; i < 2; ++i) {
        const HumanModel& h = c.human[i];
        EXPECT_EQ(h.family, HumanFamily::two_mass_grasp);
        EXPECT_EQ(h.hand_mass_kg, 0.4);
        EXPECT_EQ(h.skin_stiffness_n_per_m, 5000.0);
        EXPECT_EQ(h.skin_damping_n_s_per_m, 2.0);
        EXPECT_EQ(h.arm_stiffness_n_per_m, 300.0);
        EXPECT_EQ(h.arm_damping_n_s_per_m, 6.0);
        EXPECT_EQ(h.push.from_m, 0.005);
        EXPECT_EQ(h.push.to_m, 0.015);
        EXPECT_EQ(h.push.start_s, 0.5);
        EXPECT_EQ(h.push.ramp_s, 0.25);
        EXPECT_EQ(h.push.hold_s, 1.0);
    }
    EXPECT_EQ(c.faults.disconnect_at_s, 9.0);
    EXPECT_EQ(c.faults.stale_at_s, 1.0);
    EXPECT_EQ(c.faults.stale_for_s, 0.1);
    EXPECT_EQ(c.faults.jump_at_s, 2.0);
    EXPECT_EQ(c.faults.jump_counts, -300);
    EXPECT_EQ(c.faults.jump_axis, 1);
    EXPECT_EQ(c.faults.drop_at_s, (std::vector<double>{0.5, 0.75}));
    EXPECT_EQ(c.faults.drop_probability, 0.01);
    EXPECT_EQ(c.faults.late_at_s, (std::vector<double>{0.3}));
    EXPECT_EQ(c.faults.late_probability, 0.02);
    EXPECT_EQ(c.faults.late_by_s, 0.002);
    EXPECT_EQ(c.faults.seed, 99u);
}

TEST(SimConfig, HumanPerAxisAndSetPointDefaultsToTheInitialPosition) {
    const SimConfig c = parse_sim_config(config(R"(
initial_position = 0.03
[[human]]
model = "heavy-hand"
hand_mass = 1.0
hand_damping = 2.0
[[human]]
model = "stiff-grasp"
hand_mass = 0.0
hand_stiffness = 700
[[human]]
)",
                                                3));
    EXPECT_EQ(c.human[0].family, HumanFamily::heavy_hand);
    EXPECT_EQ(c.human[0].hand_mass_kg, 1.0);
    EXPECT_EQ(c.human[0].hand_damping_n_s_per_m, 2.0);
    EXPECT_EQ(c.human[1].family, HumanFamily::stiff_grasp);
    EXPECT_EQ(c.human[1].hand_stiffness_n_per_m, 700.0);
    EXPECT_EQ(c.human[1].hand_mass_kg, 0.0);
    EXPECT_EQ(c.human[1].push.set_point_m(0.0), 0.03);
    EXPECT_TRUE(c.human[1].push.is_fixed());
    EXPECT_EQ(c.human[2].family, HumanFamily::hands_off);
    EXPECT_EQ(c.initial_position_m[2], 0.03);
}

TEST(SimConfig, AMultiModeGraspHasOneToEightAbsorbers) {
    const SimConfig c = parse_sim_config(config(R"(
[human]
model = "multi-mode-grasp"
hand_stiffness = 500
modes = [{ mass = 0.01, stiffness = 1e5 }, { mass = 0.002, stiffness = 3e5, damping = 0.5 }]
)"));
    const HumanModel& h = c.human[0];
    EXPECT_EQ(h.family, HumanFamily::multi_mode_grasp);
    EXPECT_EQ(h.hand_mass_kg, 0.0);  // the absorbers are the grasp: no hand unless given
    EXPECT_EQ(h.hand_stiffness_n_per_m, 500.0);
    ASSERT_EQ(h.mode_count, 2);
    EXPECT_EQ(h.modes[0].mass_kg, 0.01);
    EXPECT_EQ(h.modes[0].stiffness_n_per_m, 1e5);
    EXPECT_EQ(h.modes[0].damping_n_s_per_m, 0.0);
    EXPECT_EQ(h.modes[1].damping_n_s_per_m, 0.5);

    const std::string none = error_of("[human]\nmodel = \"multi-mode-grasp\"");
    EXPECT_NE(none.find("[device.sim.human] modes has 0 absorbers: allowed 1 to 8 tables"),
              std::string::npos)
        << none;
    std::string nine = "[human]\nmodel = \"multi-mode-grasp\"\n";
    for (int i = 0; i < 9; ++i) nine += "[[human.modes]]\nmass = 0.1\nstiffness = 10\n";
    EXPECT_NE(error_of(nine).find("] has 9 absorbers: allowed 1 to 8"), std::string::npos)
        << error_of(nine);
    EXPECT_NE(
        error_of("[human]\nmodel = \"multi-mode-grasp\"\nmodes = [{ mass = 0, stiffness = 1 }]")
            .find("[[device.sim.human.modes]] #1 mass = 0 is out of range: allowed > 0"),
        std::string::npos)
        << error_of("[human]\nmodel = \"multi-mode-grasp\"\nmodes = [{ mass = 0, stiffness = 1 }]");
    EXPECT_NE(error_of("[human]\nmodel = \"multi-mode-grasp\"\n"
                       "modes = [{ mass = 1, stiffness = 1 }, { mass = 1, stifness = 1 }]")
                  .find("stifness"),
              std::string::npos);
    EXPECT_NE(error_of("[human]\nmodel = \"multi-mode-grasp\"\nmodes = [1, 2]")
                  .find("[device.sim.human] modes = [1, 2] is not an array of tables"),
              std::string::npos)
        << error_of("[human]\nmodel = \"multi-mode-grasp\"\nmodes = [1, 2]");
    EXPECT_NE(error_of("[human]\nmodel = \"stiff-grasp\"\nmodes = [{ mass = 1, stiffness = 1 }]")
                  .find("modes is not used by model = \"stiff-grasp\""),
              std::string::npos);
}

TEST(SimConfig, LockstepFlagOverridesTheClock) {
    DeviceConfig d = config("clock = \"realtime\"");
    d.lockstep = true;
    EXPECT_EQ(parse_sim_config(d).clock, SimClock::lockstep);
}

TEST(SimConfig, OutOfRangeValuesNameFileKeyValueAndRange) {
    const std::string e = error_of("mass = -0.5");
    EXPECT_NE(e.find("lab.toml"), std::string::npos) << e;
    EXPECT_NE(e.find("[device.sim] mass"), std::string::npos) << e;
    EXPECT_NE(e.find("-0.5"), std::string::npos) << e;
    EXPECT_NE(e.find("> 0"), std::string::npos) << e;
    EXPECT_NE(e.find("kg"), std::string::npos) << e;

    EXPECT_NE(
        error_of("damping = -1").find("[device.sim] damping = -1 is out of range: allowed >= 0"),
        std::string::npos);
    EXPECT_NE(error_of("counts_per_meter = 0").find("[device.sim] counts_per_meter = 0"),
              std::string::npos);
    EXPECT_NE(error_of("force_limit = \"lots\"").find("[device.sim] force_limit = \"lots\""),
              std::string::npos);
    EXPECT_NE(error_of("coulomb = nan").find("[device.sim] coulomb = nan"), std::string::npos);
    const std::string clock = error_of("clock = \"wall\"");
    EXPECT_NE(clock.find("[device.sim] clock = \"wall\""), std::string::npos) << clock;
    EXPECT_NE(clock.find("\"lockstep\" or \"realtime\""), std::string::npos) << clock;
    EXPECT_NE(error_of("initial_position = [0.0]", 2).find("an array of 2 positions"),
              std::string::npos);
    EXPECT_NE(error_of("[human]\nmodel = \"stiff-grasp\"\nhand_stiffness = -5")
                  .find("[device.sim.human] hand_stiffness = -5"),
              std::string::npos);
    EXPECT_NE(error_of("[faults]\ndrop_probability = 1.5")
                  .find("[device.sim.faults] drop_probability = 1.5"),
              std::string::npos);
    EXPECT_NE(
        error_of("[faults]\njump_axis = 1").find("jump_axis = 1 is out of range: allowed 0..0"),
        std::string::npos);
    EXPECT_NE(error_of("[faults]\ndrop_at = [0.1, -2]").find("[device.sim.faults] drop_at = -2"),
              std::string::npos);
    const std::string model = error_of("[human]\nmodel = \"firm-grip\"");
    EXPECT_NE(model.find("[device.sim.human] model = \"firm-grip\""), std::string::npos) << model;
    EXPECT_NE(model.find("\"two-mass-grasp\""), std::string::npos) << model;
}

// [device.sim] delay: >= 0 and < 10 periods; at the 2000 Hz of config(), < 0.005 s.
TEST(SimConfig, DelayIsFiniteNonNegativeAndBelowTenPeriods) {
    EXPECT_EQ(parse_sim_config(config("delay = 0")).delay_s, 0.0);
    EXPECT_EQ(parse_sim_config(config("delay = 0.0")).delay_s, 0.0);
    EXPECT_EQ(parse_sim_config(config("delay = 0.0005")).delay_s, 0.0005);    // 1 period
    EXPECT_EQ(parse_sim_config(config("delay = 0.00499")).delay_s, 0.00499);  // 9.98 periods
    EXPECT_EQ(parse_sim_config(config("delay = 1.85e-4")).delay_s, 1.85e-4);  // 0.37 period
    for (const char* bad : {"-1e-3", "nan", "inf", "-inf", "0.005", "1e9", "\"1 ms\"", "true"}) {
        const std::string e = error_of(std::string("delay = ") + bad);
        SCOPED_TRACE(e);
        EXPECT_EQ(e.find("lab.toml:1: [device.sim] delay = "), 0u);
        EXPECT_NE(e.find(": allowed >= 0 and < 0.005 (s: 10 periods at [servo] rate_hz = 2000)"),
                  std::string::npos);
    }
    EXPECT_NE(error_of("delay = -1e-3").find("delay = -0.001 is out of range"), std::string::npos);
    EXPECT_NE(error_of("delay = nan").find("delay = nan is out of range"), std::string::npos);
    EXPECT_NE(error_of("delay = 0.005").find("delay = 0.005"), std::string::npos);
    EXPECT_NE(error_of("delay = 1e9").find("delay = 1e+09 is out of range"), std::string::npos);
    EXPECT_NE(error_of("delay = inf").find("delay = inf is out of range"), std::string::npos);
}

TEST(SimConfig, UnknownKeysAreErrors) {
    const std::string e = error_of("mass = 0.1\nmas = 0.2");
    EXPECT_NE(e.find("lab.toml:2: [device.sim] mas = 0.2 is not a known key"), std::string::npos)
        << e;
    EXPECT_NE(error_of("[human]\nmodel = \"heavy-hand\"\nhand_mas = 1")
                  .find("[device.sim.human] hand_mas = 1 is not a known key"),
              std::string::npos);
    EXPECT_NE(error_of("[faults]\ndisconnect = 1.0")
                  .find("[device.sim.faults] disconnect = 1.0 is not a known key"),
              std::string::npos);
    EXPECT_NE(error_of("[human]\nmodel = \"stiff-grasp\"\npush = { too = 1 }")
                  .find("[device.sim.human.push] too = 1 is not a known key"),
              std::string::npos);
    EXPECT_NE(error_of("[[human]]\n[[human]]\n[[human]]\nmodel = \"heavy-hand\"\nfoo = 1", 3)
                  .find("[[device.sim.human]] #3 foo = 1 is not a known key"),
              std::string::npos);
}

TEST(SimConfig, KeysTheModelDoesNotUseAreErrors) {
    const std::string e = error_of("[human]\nmodel = \"heavy-hand\"\nhand_stiffness = 100");
    EXPECT_NE(e.find("[device.sim.human] hand_stiffness is not used by model = \"heavy-hand\""),
              std::string::npos)
        << e;
    EXPECT_NE(error_of("[human]\nhand_mass = 1").find("not used by model = \"hands-off\""),
              std::string::npos);
    EXPECT_NE(error_of("[human]\nmodel = \"heavy-hand\"\nset_point = 0.1").find("set_point"),
              std::string::npos);
    EXPECT_NE(error_of("[human]\nmodel = \"two-mass-grasp\"\nhand_mass = 0").find("> 0"),
              std::string::npos);
}

TEST(SimConfig, BadDeviceSettingsAndBadTomlAreErrors) {
    EXPECT_NE(error_of("", 4).find("lab.toml: device.axes = 4"), std::string::npos);
    EXPECT_NE(error_of("mass = ").find("lab.toml:1:"), std::string::npos);
    EXPECT_NE(error_of("human = 3").find("[device.sim] human = 3"), std::string::npos);
    EXPECT_NE(error_of("[[human]]\n[[human]]", 3).find("3 tables [[device.sim.human]]"),
              std::string::npos);
    DeviceConfig d = config("");
    d.rate_hz = 0.0;
    SimDevice dev;
    try {
        dev.open(d);
        ADD_FAILURE() << "rate 0 accepted";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("servo.rate_hz = 0"), std::string::npos) << e.what();
    }
    dev.close();  // safe after a failed open
}

}  // namespace
}  // namespace hapticd::device::sim

namespace hapticd::device::sim {
namespace {

// The example of docs/sim-device.md, as the daemon passes it (the table's contents).
TEST(SimConfig, TheDocumentedExampleParses) {
    const SimConfig c = parse_sim_config(config(R"(
mass = 0.1
damping = 2.0
counts_per_meter = 1e5
clock = "lockstep"
initial_position = -0.01

[human]
model = "stiff-grasp"
hand_mass = 0.3
hand_stiffness = 500.0
hand_damping = 5.0
push = { to = 0.01, start = 0.5, ramp = 1.0, hold = 2.0 }

[faults]
drop_probability = 0.001
seed = 7
)"));
    EXPECT_EQ(c.human[0].push.set_point_m(0.0), -0.01);
    EXPECT_EQ(c.human[0].push.set_point_m(2.0), 0.01);
    EXPECT_EQ(c.faults.seed, 7u);
}

}  // namespace
}  // namespace hapticd::device::sim
