// UsbHil*: the unchanged hapticd executable with [device] plugin = "usb", through the `usb`
// plugin and unmodified libusb, against an emulated USB device (usb_testbed.hpp) that plays
// the pen display's physics in lockstep behind the protocol. hapticd runs as a child process
// and inherits libumockdev-preload and the testbed (LD_PRELOAD, UMOCKDEV_DIR); its URBs are
// answered by this process.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <string>
#include <thread>

#include "hapticd/device/sim/sim_config.hpp"
#include "hapticd/servo/faults.hpp"
#include "hapticd_run.hpp"
#include "operators.hpp"
#include "pen_display.hpp"
#include "transport_contact.hpp"
#include "tuned_gains.hpp"
#include "usb_testbed.hpp"
#include "wall_contact.hpp"

namespace hapticd::testing {
namespace {

constexpr double kWallStiffnessNPerM = kContactWallStiffnessNPerM;
constexpr double kStartM = kContactStartM;
constexpr double kDurationS = 6.0;
constexpr double kSettleS = 3.0;
constexpr const char* kSerial = "EMU-0001";

/// The sim-plugin config of the HIL tests, split in two: hapticd's own part with
/// [device] plugin = "usb" and [device.usb], and the [device.sim] table, which becomes the
/// emulated device's physics instead.
struct UsbRig {
    std::string daemon_toml;
    std::string sim_table;  ///< [device.sim]'s contents, sub-tables as [human]
};

UsbRig split(const DaemonConfig& config, const std::string& usb_table) {
    const std::string text = config.toml();
    const std::size_t sim = text.find("[device.sim]\n");
    UsbRig rig;
    rig.daemon_toml = text.substr(0, sim);
    const std::string plugin = "plugin = \"sim\"";
    rig.daemon_toml.replace(rig.daemon_toml.find(plugin), plugin.size(), "plugin = \"usb\"");
    rig.daemon_toml += "[device.usb]\n" + usb_table;
    rig.sim_table = text.substr(sim + std::string("[device.sim]\n").size());
    for (std::size_t at; (at = rig.sim_table.find("[device.sim.")) != std::string::npos;) {
        rig.sim_table.replace(at, std::string("[device.sim.").size(), "[");
    }
    return rig;
}

UsbDeviceSpec emulated_pen_display(const std::string& sim_table) {
    device::DeviceConfig sim;
    sim.lockstep = true;
    sim.plugin_table_toml = sim_table;
    sim.source = "emulated device";
    UsbDeviceSpec spec;
    spec.emulator.sim = device::sim::parse_sim_config(sim);
    spec.emulator.serial_number = kSerial;
    return spec;
}

class UsbHilWallContact : public ::testing::TestWithParam<OperatorCase> {};

// The encoder model's gains hold a stiff wall (HilEncoderGains with the sim plugin); through
// the USB transport, with the protocol's micronewton forces and integer counts, they must too.
TEST_P(UsbHilWallContact, StableThroughTheUsbPlugin) {
    const CouplingGains gains = size_coupling("encoder");
    ASSERT_GT(gains.stiffness_n_per_m, 0.0);
    DaemonConfig config;
    config.coupling = coupling_table(gains, "encoder");
    config.initial_position = toml_number(kStartM);
    config.humans = human_table(GetParam().human);
    const UsbRig rig = split(config, "serial_number = \"" + std::string(kSerial) + "\"\n");

    UsbTestbed testbed;
    EmulatedUsbDevice& device = testbed.add(emulated_pen_display(rig.sim_table));
    const ScratchDir dir;
    const DaemonRun run = run_hapticd(dir, {.config_toml = rig.daemon_toml,
                                            .scene_toml = wall_contact_scene(kWallStiffnessNPerM),
                                            .duration_s = kDurationS});

    if (!expect_stable_wall_contact(run, kDurationS, kSettleS, "[usb-hil] " + GetParam().name)) {
        return;
    }
    // Every command went over USB to the device: one per tick, plus the zero-force ones of
    // shut-down (the loop's, the daemon's, ProtocolDevice::close()'s).
    const std::uint64_t applied =
        device.with_emulator([](auto& e) { return e.counters().commands_applied; });
    EXPECT_GE(applied, static_cast<std::uint64_t>(kDurationS * kRateHz));
    EXPECT_LE(applied, static_cast<std::uint64_t>(kDurationS * kRateHz) + 5);
    EXPECT_GE(device.counts().out_submitted, applied);
    EXPECT_FALSE(device.with_emulator([](auto& e) { return e.session_open(); }));  // bye

    // The same run on the sim plugin. The transport rounds the force to whole micronewtons
    // (docs/protocol.md 2), which may move an encoder-count crossing by a tick; after that the
    // two quantised dithers about the contact point drift apart, so what must agree is the
    // operating point (the mean position once settled, within a count) and the size of the
    // difference (within the 8-count dither the contact judge allows).
    const ScratchDir sim_dir;
    const DaemonRun sim =
        run_hapticd(sim_dir, {.config_toml = config.toml(),
                              .scene_toml = wall_contact_scene(kWallStiffnessNPerM),
                              .duration_s = kDurationS});
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
    const auto& t = run.log.column("t_s");
    const auto& x_usb = run.log.column("x0_m");
    const auto& x_sim = sim.log.column("x0_m");
    ASSERT_EQ(x_usb.size(), x_sim.size());
    double worst_m = 0.0;
    double identical_until_s = -1.0;
    double mean_usb_m = 0.0;
    double mean_sim_m = 0.0;
    int settled = 0;
    for (std::size_t i = 0; i < x_usb.size(); ++i) {
        const double difference_m = std::abs(x_usb[i] - x_sim[i]);
        worst_m = std::max(worst_m, difference_m);
        if (difference_m > 0.0 && identical_until_s < 0.0) identical_until_s = t[i];
        if (t[i] >= kSettleS) {
            mean_usb_m += x_usb[i];
            mean_sim_m += x_sim[i];
            ++settled;
        }
    }
    mean_usb_m /= settled;
    mean_sim_m /= settled;
    std::cout << "[usb-hil] " << GetParam().name << ": usb vs sim plugin: identical until "
              << (identical_until_s < 0.0 ? std::string("the end")
                                          : std::to_string(identical_until_s) + " s")
              << ", largest difference " << worst_m / kCountM << " counts, settled means "
              << mean_usb_m / kCountM << " vs " << mean_sim_m / kCountM << " counts\n";
    EXPECT_LE(std::abs(mean_usb_m - mean_sim_m), kCountM);
    EXPECT_LE(worst_m, 8.0 * kCountM);
}

INSTANTIATE_TEST_SUITE_P(, UsbHilWallContact, ::testing::ValuesIn(transport_operator_cases()),
                         case_name);

constexpr std::uint32_t kFaultDeviceLost = 1u << 0;  // servo/faults.hpp
constexpr std::uint32_t kFlagNoSample = 1u << 6;     // servo/telemetry.hpp
constexpr std::uint32_t kFlagSoftStart = 1u << 3;
constexpr std::uint32_t kFlagLinkRecovered = 1u << 8;

/// Waits (generously, for a loaded VM) until `condition` holds; false if it never does.
template <typename Condition>
bool eventually(Condition condition, double timeout_s = 60.0) {
    const auto start = std::chrono::steady_clock::now();
    while (!condition()) {
        if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >
            timeout_s) {
            return false;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return true;
}

// The cable comes out while a hand presses the handle into the wall, and goes back in: the
// loop zeroes the force in the tick that sees the loss, reports device_lost, waits at zero
// force (the reconnect thread reopens the device at its new address), and once the samples
// have been good for reconnect_settle it starts over through the soft start, to contact again.
TEST(UsbHilReconnect, UnplugZeroesForceAndTheLoopRecoversWhenTheDeviceReturns) {
    constexpr double kRunS = 4.0;
    constexpr std::uint64_t kUnplugAtCommand = 1500;
    constexpr std::size_t kSettleRows = 500;  // [safety] reconnect_settle = 0.5 s (default)
    DaemonConfig config;
    config.coupling = coupling_table(size_coupling("encoder"), "encoder");
    config.initial_position = toml_number(kStartM);
    config.humans = human_table(stiff_grasp(push_toml(0.005, 0.8, 0.2, 100.0)));
    const UsbRig rig = split(
        config, "serial_number = \"" + std::string(kSerial) + "\"\nreconnect_interval_ms = 20.0\n");
    UsbTestbed testbed;
    EmulatedUsbDevice& device = testbed.add(emulated_pen_display(rig.sim_table));
    const ScratchDir dir;
    DaemonRun run;
    // The cable comes out between command 1500 and its reply (the device decides, so the
    // tick does not depend on timing); then it is out until the daemon has noticed and closed
    // its file, and back in (the same device and firmware state: a cable, not a power cycle),
    // at a new address.
    device.unplug_at_command(kUnplugAtCommand);
    std::thread daemon([&] {
        run = run_hapticd(dir, {.config_toml = rig.daemon_toml,
                                .scene_toml = wall_contact_scene(kWallStiffnessNPerM),
                                .duration_s = kRunS});
    });
    const bool pulled = eventually([&] { return !device.plugged(); });
    testbed.unplug(device);
    const bool noticed = eventually([&] { return device.counts().open_files == 0; });
    testbed.replug(device, /*fresh_emulator=*/false);
    daemon.join();
    ASSERT_TRUE(pulled);
    ASSERT_TRUE(noticed);

    EXPECT_EQ(run.exit_code, 0) << run.err;
    EXPECT_EQ(run.summary.at("exit"), "duration");
    EXPECT_EQ(fault_list(run), servo::fault_name(kFaultDeviceLost));
    EXPECT_EQ(run.summary.at("link_recoveries"), 1);
    EXPECT_NE(run.err.find("reconnected: usb 1209:0001 serial EMU-0001 (bus 1 device 3)"),
              std::string::npos)
        << run.err;
    ASSERT_EQ(run.log.rows(), static_cast<std::size_t>(kRunS * kRateHz));
    const auto& f = run.log.column("f0_n");
    const auto& faults = run.log.column("faults");
    const auto& flags = run.log.column("tick_flags");
    auto flag = [&](std::size_t row, std::uint32_t bit) {
        return (static_cast<std::uint32_t>(flags[row]) & bit) != 0u;
    };

    std::size_t lost = 0;  // the tick that latched device_lost
    while (lost < run.log.rows() && faults[lost] == 0.0) ++lost;
    ASSERT_LT(lost, run.log.rows());
    EXPECT_EQ(static_cast<std::uint32_t>(faults[lost]), kFaultDeviceLost);
    EXPECT_EQ(f[lost], 0.0);                // zero in that very tick
    EXPECT_GT(std::abs(f[lost - 1]), 1.0);  // pressing into the wall until then
    std::size_t back = lost;                // the first sample after the replug
    while (back < run.log.rows() && flag(back, kFlagNoSample)) ++back;
    ASSERT_LT(back + kSettleRows, run.log.rows());
    std::cout << "[usb-hil] unplugged at tick " << lost << ", samples again at tick " << back
              << ", recovered at tick " << back + kSettleRows << "\n";
    for (std::size_t i = lost; i < back + kSettleRows; ++i) {
        ASSERT_EQ(f[i], 0.0) << i;
        ASSERT_EQ(static_cast<std::uint32_t>(faults[i]), kFaultDeviceLost) << i;
    }
    EXPECT_TRUE(flag(back + kSettleRows - 1, kFlagLinkRecovered));
    const std::size_t recovered = back + kSettleRows;
    std::size_t first_force = recovered;
    while (first_force < run.log.rows() && f[first_force] == 0.0) ++first_force;
    ASSERT_LT(first_force, run.log.rows());
    EXPECT_TRUE(flag(first_force, kFlagSoftStart));  // force back only through the ramp
    for (std::size_t i = recovered; i < run.log.rows(); ++i) ASSERT_EQ(faults[i], 0.0) << i;
    EXPECT_GT(std::abs(f[run.log.rows() - 1]), 1.0);  // in contact again
}

// Without the udev rule a user may not open the usbfs node: hapticd says which rule to install.
// Emulated faithfully: hapticd runs as `nobody`, the node belongs to root, mode 0644, and
// libusb's open() gets EACCES, as it would on a machine without the rule.
TEST(UsbHilAccess, DeniedAccessNamesTheUdevRule) {
    UsbTestbed testbed;
    DaemonConfig config;
    config.coupling = no_coupling_table();
    const UsbRig rig = split(config, "serial_number = \"" + std::string(kSerial) + "\"\n");
    EmulatedUsbDevice& device = testbed.add(emulated_pen_display(rig.sim_table));
    testbed.open_to_other_users();
    const ScratchDir dir;
    ASSERT_EQ(::chmod(dir.path().c_str(), 0777), 0);
    const std::string cfg = dir.write("cfg.toml", rig.daemon_toml);
    dir.write("scene.toml", wall_contact_scene(kWallStiffnessNPerM));
    const CommandResult result = run_command(
        "setpriv --reuid=65534 --regid=65534 --clear-groups " + shell_quote(HAPTICD_BIN) +
        " --lockstep --no-status --duration 0.1 --config " + shell_quote(cfg));
    EXPECT_EQ(result.exit_code, 2) << result.err;
    EXPECT_NE(result.err.find("permission denied opening 1209:0001 at bus 1 device 2 "
                              "(/dev/bus/usb/001/002)"),
              std::string::npos)
        << result.err;
    EXPECT_NE(result.err.find("70-hapticd.rules"), std::string::npos) << result.err;
    EXPECT_NE(result.err.find("plugdev"), std::string::npos) << result.err;
    EXPECT_EQ(device.counts().claims, 0u);

    // The same run as root (who may open any node) gets the device: the refusal was the
    // node's permissions and nothing else.
    const CommandResult allowed =
        run_command(shell_quote(HAPTICD_BIN) + " --lockstep --no-status --duration 0.1 --config " +
                    shell_quote(cfg));
    EXPECT_EQ(allowed.exit_code, 0) << allowed.err;
    EXPECT_EQ(device.counts().claims, 1u);
}

TEST(UsbHilConfig, BadVidIsAnInputError) {
    UsbTestbed testbed;
    DaemonConfig config;
    config.coupling = no_coupling_table();
    const UsbRig rig = split(config, "vid = 0x12345\n");
    const ScratchDir dir;
    const DaemonRun run = run_hapticd(dir, {.config_toml = rig.daemon_toml,
                                            .scene_toml = wall_contact_scene(kWallStiffnessNPerM),
                                            .duration_s = 0.1});
    EXPECT_EQ(run.exit_code, 2) << run.err;
    EXPECT_NE(run.err.find("cfg.toml"), std::string::npos) << run.err;
    EXPECT_NE(run.err.find("[device.usb] vid"), std::string::npos) << run.err;
    EXPECT_NE(run.err.find("0x12345"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace hapticd::testing
