// HidClosedLoop: the real hapticd executable with `[device] plugin = "hid"`, its servo loop
// closed through hidapi's hidraw backend and an emulated hidraw node to the reference device
// playing the pen display's physics in lockstep (emulated_hid_device.hpp), against the HIL
// tests' stiff wall (tests/support/wall_contact.hpp) with the coupling the `encoder` model sizes.
// The contact must be as stable as it is on the sim plugin (HilEncoderGains). Also: a user
// who may not open the hidraw node is told about the udev rule.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>

#include "emulated_hid_device.hpp"
#include "hapticd/servo/telemetry.hpp"
#include "hapticd_run.hpp"
#include "pen_display.hpp"
#include "transport_contact.hpp"
#include "tuned_gains.hpp"
#include "wall_contact.hpp"

namespace hapticd::testing {
namespace {

constexpr double kWallStiffnessNPerM = 1e5;
constexpr double kStartM = -0.001;  ///< 1 mm in front of the wall
constexpr double kDurationS = 4.0;
constexpr double kSettleS = 2.0;
/// Each handshake step waits for a reply that comes; on a loaded machine the emulated node's
/// round trip can take longer than the 200 ms default (hid_device_server.hpp, "Timing").
constexpr const char* kHandshakeTimeout = "handshake_timeout_ms = 10000\n";

/// hapticd's config for the pen display on the `hid` plugin (cf. DaemonConfig::toml()).
std::string hid_daemon_config(const EmulatedHidDevice& device, const CouplingGains& gains) {
    return "[servo]\nrate_hz = " + toml_number(kRateHz) + "\nrealtime = \"off\"\n" +
           "[device]\nplugin = \"hid\"\naxes = 1\n" +
           "[device.model]\nmass = " + toml_number(kPenMassKg) +
           "\ndamping = " + toml_number(kPenDampingNsPerM) + "\n" +
           coupling_table(gains, "encoder") + "[scene]\nfile = \"scene.toml\"\n" +
           "[safety]\nmax_force = " + toml_number(kForceLimitN) +
           "\nmax_speed = 1.0\nsoft_start_ramp = 0.5\npassivity = \"observe\"\n" +
           "[device.hid]\n" + device.table_toml() + kHandshakeTimeout;
}

device::protocol::EmulatorConfig pen_display_at_start() {
    device::protocol::EmulatorConfig c = pen_display_emulator();
    c.sim.initial_position_m[0] = kStartM;  // hands-off: the scene's preload brings it in
    return c;
}

TEST(HidClosedLoop, TheDaemonHoldsAStiffWallStablyThroughHid) {
    const CouplingGains gains = size_coupling("encoder");
    ASSERT_GT(gains.stiffness_n_per_m, 0.0);
    EmulatedHidDevice device(pen_display_at_start());
    const ScratchDir dir;
    const DaemonRun run = run_hapticd(dir, {.config_toml = hid_daemon_config(device, gains),
                                            .scene_toml = wall_contact_scene(kWallStiffnessNPerM),
                                            .duration_s = kDurationS});

    // Hands-off: the preload brings the handle to the wall gently, so the transient is a few
    // counts, not ten.
    if (!expect_stable_wall_contact(run, kDurationS, kSettleS, "[hid] closed loop through hidapi",
                                    {.min_transient_m = 2.0 * kCountM})) {
        return;
    }
    // Every tick went through the node: one command report per tick (and the handshake's).
    EXPECT_GE(device.server().output_reports(), static_cast<std::uint64_t>(kDurationS * kRateHz));

    // The handle rests where the preload and the wall balance: 0.5 N / K inside the wall.
    const auto& x = run.log.column("x0_m");
    EXPECT_NEAR(x.back(), 0.5 / kWallStiffnessNPerM, 3.0 * kCountM);

    // The same run on the sim plugin: the same physics with no transport in between. The
    // trajectories are the same tick for tick until the contact (lockstep: deterministic);
    // there the wire's whole micronewtons tip an encoder count the other way now and then,
    // and the two dither apart by no more than the dither itself. Lockstep is deterministic
    // as long as every reply comes within the lockstep reply timeout (1 s); on a loaded
    // machine the emulated node now and then answers later (hid_device_server.hpp,
    // "Timing"), the servo goes on without that sample (a tick with kFlagNoSample, counted in
    // read_timeouts), and from that tick the runs part: they are compared up to it.
    DaemonConfig sim;
    sim.coupling = coupling_table(gains, "encoder");
    sim.initial_position = toml_number(kStartM);
    const ScratchDir sim_dir;
    const DaemonRun direct =
        run_hapticd(sim_dir, {.config_toml = sim.toml(),
                              .scene_toml = wall_contact_scene(kWallStiffnessNPerM),
                              .duration_s = kDurationS});
    ASSERT_EQ(direct.exit_code, 0) << direct.err;
    const auto& x_sim = direct.log.column("x0_m");
    ASSERT_EQ(x_sim.size(), x.size());
    const auto& flags = run.log.column("tick_flags");
    std::size_t compared = x.size();
    for (std::size_t i = 0; i < flags.size(); ++i) {
        if ((static_cast<std::uint32_t>(flags[i]) & servo::kFlagNoSample) != 0u) {
            compared = i;
            break;
        }
    }
    std::size_t first_difference = compared;
    double worst_m = 0.0;
    for (std::size_t i = 0; i < compared; ++i) {
        const double difference_m = std::abs(x[i] - x_sim[i]);
        if (difference_m > 0.0 && first_difference == compared) first_difference = i;
        worst_m = std::max(worst_m, difference_m);
    }
    std::cout << "[hid] against the sim plugin: the same until tick " << first_difference
              << ", then at most " << worst_m / kCountM << " counts apart";
    if (compared < x.size()) {
        std::cout << " (compared up to tick " << compared << ", the first of "
                  << run.summary.at("read_timeouts") << " without a sample in time)";
    }
    std::cout << "\n";
    // Contact: about 1.2 s.
    EXPECT_GE(first_difference, std::min(compared, static_cast<std::size_t>(kRateHz)));
    EXPECT_LE(worst_m, 4.0 * kCountM);
}

TEST(HidClosedLoop, AUserWhoMayNotOpenTheNodeIsToldAboutTheUdevRule) {
    EmulatedHidDevice device;
    const std::string node = device.testbed().root_dir() + device.devnode();
    const std::string pty = std::filesystem::read_symlink(node).string();
    ScratchDir dir;
    std::string prefix;
    if (geteuid() == 0) {
        // root opens anything: run hapticd as nobody, who may read the testbed and reach its
        // ioctl socket (libumockdev-preload connects to it in open()), but not open the pty
        // behind the node (root's, mode 0620).
        const std::string root = device.testbed().root_dir();
        ASSERT_EQ(chmod(root.c_str(), 0755), 0);
        ASSERT_EQ(chmod((root + "/ioctl" + device.devnode()).c_str(), 0777), 0);
        ASSERT_EQ(chmod(dir.path().c_str(), 0777), 0);
        prefix = "setpriv --reuid=65534 --regid=65534 --clear-groups ";
    } else {
        ASSERT_EQ(chmod(pty.c_str(), 0), 0);
    }
    const std::string config =
        dir.write("cfg.toml",
                  "[servo]\nrate_hz = 1000.0\nrealtime = \"off\"\n[device]\nplugin = \"hid\"\n"
                  "axes = 1\n[device.model]\nmass = 0.1\ndamping = 2.0\n" +
                      no_coupling_table() + "[device.hid]\n" + device.table_toml());
    const CommandResult result = run_command(prefix + shell_quote(HAPTICD_BIN) +
                                             " --lockstep --no-status --duration 0.1 "
                                             "--config " +
                                             shell_quote(config));
    if (!prefix.empty() && result.err.rfind("setpriv:", 0) == 0) {
        GTEST_SKIP() << "cannot run as nobody here: " << result.err;
    }
    std::cout << "[hid] as a user without access, hapticd says:\n" << result.err;
    EXPECT_NE(result.exit_code, 0);
    EXPECT_NE(result.err.find("hid: permission denied opening /dev/hidraw0 1209:4841"),
              std::string::npos)
        << result.err;
    EXPECT_NE(result.err.find("config/udev/70-hapticd.rules"), std::string::npos) << result.err;
    EXPECT_NE(result.err.find("KERNEL==\"hidraw*\", SUBSYSTEM==\"hidraw\", "
                              "ATTRS{idVendor}==\"1209\", ATTRS{idProduct}==\"4841\", "
                              "MODE=\"0660\", GROUP=\"plugdev\", TAG+=\"uaccess\""),
              std::string::npos)
        << result.err;
}

}  // namespace
}  // namespace hapticd::testing
