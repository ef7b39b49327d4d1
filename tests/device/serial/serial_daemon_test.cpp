// SerialDaemon: the real hapticd executable with `plugin = "serial"` against the reference
// device behind a pseudo-terminal (this process serves the master side; hapticd opens the
// slave as it would open /dev/ttyACM0). The device plays the pen display of the HIL tests
// (tests/support/pen_display.hpp), so the closed loop must hold the stiff wall of HilEncoderGains
// just as stably through the protocol and the serial line as against the sim plugin. Then the
// error paths end to end: a reply corrupted, truncated, of another session or lost, a device
// fault, and the device going away and coming back: in each case the loop zeroes the force in
// the tick of the fault, reports the fault, and (for link faults) recovers by itself. And the
// control socket's status, which reports the link's counts that the serial plugin keeps.
#include <gtest/gtest.h>
#include <signal.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <string>
#include <thread>

#include "control_daemon.hpp"
#include "hapticd/device/sim/sim_config.hpp"
#include "hapticd/servo/faults.hpp"
#include "hapticd_run.hpp"
#include "operators.hpp"
#include "pen_display.hpp"
#include "pty_device.hpp"
#include "transport_contact.hpp"
#include "tuned_gains.hpp"
#include "wall_contact.hpp"

namespace hapticd::testing {
namespace {

namespace proto = device::protocol;

constexpr double kWallStiffnessNPerM = kContactWallStiffnessNPerM;
constexpr double kStartM = kContactStartM;
constexpr std::uint64_t kFaultAtCommand = 1500;

/// The emulated device: the pen display with `human` ([device.sim.human] keys) on its handle.
proto::EmulatorConfig pen_display_device(const std::string& human, double rate_hz = kRateHz) {
    device::DeviceConfig sim;
    sim.axes = 1;
    sim.rate_hz = rate_hz;
    sim.lockstep = true;
    sim.source = "emulator";
    sim.plugin_table_toml = "mass = " + toml_number(kPenMassKg) +
                            "\ndamping = " + toml_number(kPenDampingNsPerM) +
                            "\ncounts_per_meter = " + toml_number(kCountsPerMeter) +
                            "\nforce_limit = " + toml_number(kForceLimitN) +
                            "\nclock = \"lockstep\"\ninitial_position = " + toml_number(kStartM) +
                            "\n[human]\n" + human;
    proto::EmulatorConfig c;
    c.sim = device::sim::parse_sim_config(sim);
    c.serial_number = "PEN-SERIAL-1";
    return c;
}

/// hapticd's config: the pen display's model, the `encoder` gains, the wall scene, and the
/// serial plugin on `port`.
std::string daemon_config(const std::string& port, const std::string& serial_extra = "",
                          const std::string& safety_extra = "") {
    return "[servo]\nrate_hz = " + toml_number(kRateHz) + "\nrealtime = \"off\"\n" +
           "[device]\nplugin = \"serial\"\naxes = 1\n" +
           "[device.model]\nmass = " + toml_number(kPenMassKg) +
           "\ndamping = " + toml_number(kPenDampingNsPerM) + "\n" +
           coupling_table(size_coupling("encoder"), "encoder") +
           "[scene]\nfile = \"scene.toml\"\n" +
           "[safety]\nmax_force = " + toml_number(kForceLimitN) +
           "\nmax_speed = 1.0\nsoft_start_ramp = 0.5\n" + safety_extra +
           "[device.serial]\nport = \"" + port + "\"\nbaud = 2000000\n" + serial_extra;
}

/// A grasp pressing the handle 5 mm into the wall from 0.8 s on: about 2.3 N of contact
/// force, so that a zero after a fault means something (as HilFaults).
std::string pressing_grasp() { return stiff_grasp(push_toml(0.005, 0.8, 0.2, 100.0)); }

std::uint32_t faults_at(const TelemetryLog& log, std::size_t row) {
    return static_cast<std::uint32_t>(log.column("faults")[row]);
}

std::size_t first_faulted_row(const TelemetryLog& log, std::size_t from = 0) {
    std::size_t row = from;
    while (row < log.rows() && faults_at(log, row) == 0u) ++row;
    return row;
}

class SerialDaemonContact : public ::testing::TestWithParam<OperatorCase> {};

TEST_P(SerialDaemonContact, HoldsAStiffWallStably) {
    constexpr double kDurationS = 8.0;
    constexpr double kSettleS = 3.0;
    PtyDevice device(pen_display_device(GetParam().human));
    const ScratchDir dir;
    const DaemonRun run = run_hapticd(dir, {.config_toml = daemon_config(device.port()),
                                            .scene_toml = wall_contact_scene(kWallStiffnessNPerM),
                                            .duration_s = kDurationS});
    // The same bounds as HilEncoderGains against the sim plugin.
    if (!expect_stable_wall_contact(
            run, kDurationS, kSettleS,
            "[serial] hapticd over the pty, encoder gains, " + GetParam().name)) {
        return;
    }
    EXPECT_EQ(run.summary.at("read_timeouts").get<double>(), 0.0);

    // Every tick went over the line: one command per tick (the daemon's closing zero command
    // included), nothing dropped.
    device.with_emulator([&](proto::DeviceEmulator& e) {
        EXPECT_GE(e.counters().commands_applied, static_cast<std::uint64_t>(kDurationS * kRateHz));
        EXPECT_EQ(e.counters().dropped_requests, 0u);
        EXPECT_FALSE(e.session_open());  // hapticd said bye
        EXPECT_EQ(e.output_force_n()[0], 0.0);
    });
}

INSTANTIATE_TEST_SUITE_P(, SerialDaemonContact, ::testing::ValuesIn(transport_operator_cases()),
                         case_name);

struct ReplyFault {
    std::string name;
    void (*arm)(proto::EmulatorFaults&);
};
void PrintTo(const ReplyFault& f, std::ostream* out) { *out << f.name; }

class SerialDaemonReplyFault : public ::testing::TestWithParam<ReplyFault> {};

// Three replies in a row go wrong (the servo holds the last force over up to
// read_timeouts_allowed = 2 missing samples, ZOH): the third missing sample latches
// read_timeout and that tick's force is zero. The device answers again, the link fault clears
// after [safety] reconnect_settle, and the force comes back through the soft start.
TEST_P(SerialDaemonReplyFault, ZeroesForceInThatTickAndRecovers) {
    constexpr double kDurationS = 4.0;
    PtyDevice device(pen_display_device(pressing_grasp()));
    const auto arm = GetParam().arm;
    device.set_request_hook([arm](proto::DeviceEmulator& e, std::uint64_t) {
        // Once: the request that follows is command 1501, and then commands_applied moves on.
        if (e.counters().commands_applied == kFaultAtCommand) arm(e.faults());
    });
    const ScratchDir dir;
    const DaemonRun run =
        run_hapticd(dir, {.config_toml = daemon_config(device.port(), "reply_timeout_ms = 50\n"),
                          .scene_toml = wall_contact_scene(kWallStiffnessNPerM),
                          .duration_s = kDurationS});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_EQ(run.summary.at("exit"), "duration");
    EXPECT_EQ(fault_list(run), servo::fault_name(servo::kFaultReadTimeout));
    EXPECT_EQ(run.summary.at("link_recoveries").get<int>(), 1);
    EXPECT_EQ(run.summary.at("read_timeouts").get<double>(), 3.0);

    const TelemetryLog& log = run.log;
    const auto& f = log.column("f0_n");
    const std::size_t faulted = first_faulted_row(log);
    ASSERT_LT(faulted, log.rows());
    ASSERT_GE(faulted, 3u);
    EXPECT_EQ(faults_at(log, faulted), std::uint32_t{servo::kFaultReadTimeout});
    EXPECT_EQ(f[faulted], 0.0);  // zero force in the tick that latched it
    // Before: pressing into the wall, and two ticks without a sample (the force held).
    EXPECT_GT(std::abs(f[faulted - 3]), 1.0);
    const auto status = [&](std::size_t row) {
        return static_cast<std::uint32_t>(log.column("status")[row]);
    };
    EXPECT_NE(status(faulted) & servo::kStatusDropped, 0u);
    EXPECT_NE(status(faulted - 1) & servo::kStatusDropped, 0u);
    EXPECT_NE(status(faulted - 2) & servo::kStatusDropped, 0u);
    EXPECT_EQ(status(faulted - 3) & servo::kStatusDropped, 0u);
    EXPECT_NEAR(log.column("t_s")[faulted], 1.5, 0.01);  // about command 1500

    // Recovered: the latch clears, and the force is back (pressing again) well before the end.
    std::size_t cleared = faulted;
    while (cleared < log.rows() && faults_at(log, cleared) != 0u) ++cleared;
    ASSERT_LT(cleared, log.rows()) << "the fault never cleared";
    const double cleared_at_s = log.column("t_s")[cleared];
    EXPECT_NEAR(cleared_at_s - log.column("t_s")[faulted], 0.5, 0.05);  // reconnect_settle
    for (std::size_t row = faulted; row < cleared; ++row) ASSERT_EQ(f[row], 0.0) << row;
    EXPECT_GT(std::abs(f.back()), 1.0);
    std::cout << "[serial] " << GetParam().name
              << ": read_timeout at t = " << log.column("t_s")[faulted] << " s, cleared at "
              << cleared_at_s << " s, force at the end " << f.back() << " N\n";
}

INSTANTIATE_TEST_SUITE_P(
    , SerialDaemonReplyFault,
    ::testing::Values(
        ReplyFault{"corrupt_crc", [](proto::EmulatorFaults& f) { f.corrupt_crc = 3; }},
        ReplyFault{"truncate", [](proto::EmulatorFaults& f) { f.truncate = 3; }},
        ReplyFault{"wrong_session", [](proto::EmulatorFaults& f) { f.wrong_session = 3; }},
        ReplyFault{"drop", [](proto::EmulatorFaults& f) { f.drop = 3; }}),
    [](const auto& param_info) { return param_info.param.name; });

// A fault the device reports itself is not a link fault: zero force in that tick, reported,
// latched until an operator resets it; hapticd stops on it (exit 1).
TEST(SerialDaemon, ADeviceFaultZeroesForceAndStopsTheRun) {
    PtyDevice device(pen_display_device(pressing_grasp()));
    device.set_request_hook([](proto::DeviceEmulator& e, std::uint64_t) {
        if (e.counters().commands_applied == kFaultAtCommand) {
            e.faults().device_faults = proto::kDeviceFaultOverCurrent;
        }
    });
    const ScratchDir dir;
    const DaemonRun run = run_hapticd(dir, {.config_toml = daemon_config(device.port()),
                                            .scene_toml = wall_contact_scene(kWallStiffnessNPerM),
                                            .duration_s = 4.0});
    EXPECT_EQ(run.exit_code, 1) << run.err;
    EXPECT_EQ(run.summary.at("exit"), "fault");
    EXPECT_EQ(fault_list(run), servo::fault_name(servo::kFaultDeviceFault));
    const TelemetryLog& log = run.log;
    const std::size_t faulted = first_faulted_row(log);
    ASSERT_LT(faulted, log.rows());
    ASSERT_GT(faulted, 0u);
    EXPECT_EQ(log.column("f0_n")[faulted], 0.0);
    EXPECT_GT(std::abs(log.column("f0_n")[faulted - 1]), 1.0);
    EXPECT_EQ(faulted + 1, log.rows());  // the run ended on it
    device.with_emulator([](proto::DeviceEmulator& e) {
        EXPECT_EQ(e.output_force_n()[0], 0.0);
        EXPECT_NE(e.latched_faults() & proto::kDeviceFaultOverCurrent, 0u);
    });
}

/// The real-time serial runs below: `rate_hz`, no coupling, the spring of kSpringScene, the
/// device on `port`; `safety_lines` end [safety], `serial_lines` end [device.serial].
std::string serial_spring_config(double rate_hz, const std::string& port,
                                 const std::string& safety_lines, const std::string& serial_lines) {
    return "[servo]\nrate_hz = " + toml_number(rate_hz) + "\nrealtime = \"off\"\n" +
           "[device]\nplugin = \"serial\"\naxes = 1\n[device.model]\nmass = " +
           toml_number(kPenMassKg) + "\ndamping = " + toml_number(kPenDampingNsPerM) + "\n" +
           no_coupling_table() + "[scene]\nfile = \"scene.toml\"\n" +
           "[safety]\nmax_force = " + toml_number(kForceLimitN) + "\nmax_speed = 1.0\n" +
           safety_lines + "[device.serial]\nport = \"" + port + "\"\nreply_timeout_ms = 8\n" +
           serial_lines;
}

/// A spring pulling the handle toward +4 mm: the force is the point, not contact stability.
constexpr const char* kSpringScene =
    "[scene]\nname = \"serial-spring\"\naxes = 1\n[[spring]]\nanchor = [0.004]\n"
    "stiffness = 200.0\n";

// The device goes away (the pty's master closes: hapticd's port hangs up, as when a USB serial
// adapter is pulled out) and comes back on a new pty behind the same path (a symlink, as
// /dev/serial/by-id/... is).
//
// In real time, at 100 Hz. The outage is wall time, and in lockstep a lost device does not
// pace the loop (its read() returns at once), so a lockstep run would tick through thousands
// of virtual periods while the device is away: not a fixed test. 100 Hz leaves this loaded
// 2-core VM 10 ms per round trip through the pty (p99 of a few ms under load). No coupling
// and a spring instead of the wall: the point is the force, not contact stability.
TEST(SerialDaemon, RecoversWhenTheDeviceComesBack) {
    constexpr double kRate = 100.0;
    constexpr std::uint64_t kHangUpAtCommand = 200;  // 2 s
    const ScratchDir dir;
    const std::string stable = dir.file("ttyHAPTIC");
    // The grasp holds the handle near -1 mm; the spring pulls it toward +4 mm: about 0.7 N.
    PtyDevice device(pen_display_device(stiff_grasp(""), kRate), stable);
    std::atomic<bool> reached{false};
    device.set_request_hook([&reached](proto::DeviceEmulator& e, std::uint64_t) {
        if (e.counters().commands_applied >= kHangUpAtCommand) reached = true;
    });
    const std::string config =
        serial_spring_config(kRate, stable, "", "reconnect_interval_ms = 20\n");
    const std::string scene = kSpringScene;
    DaemonRun run;
    std::thread daemon([&] {
        run = run_hapticd(
            dir,
            {.config_toml = config, .scene_toml = scene, .duration_s = 6.0, .lockstep = false});
    });
    for (int waited_ms = 0; !reached && waited_ms < 20'000; ++waited_ms) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    const bool got_there = reached.load();
    device.hang_up();
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    device.plug_in();
    daemon.join();
    ASSERT_TRUE(got_there) << "hapticd never reached command " << kHangUpAtCommand << "\n"
                           << run.err;

    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_EQ(run.summary.at("exit"), "duration");
    const std::string faults = fault_list(run);
    EXPECT_NE(faults.find("device_lost"), std::string::npos) << faults;
    EXPECT_GE(run.summary.at("link_recoveries").get<int>(), 1);
    EXPECT_NE(run.err.find("reconnected: serial " + stable), std::string::npos) << run.err;

    const TelemetryLog& log = run.log;
    const auto& f = log.column("f0_n");
    const auto& t = log.column("t_s");
    // The first tick that saw the device gone: zero force in it, pulling before it.
    std::size_t lost = 0;
    while (lost < log.rows() && (faults_at(log, lost) & servo::kFaultDeviceLost) == 0u) ++lost;
    ASSERT_LT(lost, log.rows());
    ASSERT_GT(lost, 0u);
    EXPECT_EQ(f[lost], 0.0);
    // Before the first fault of any kind the spring pulled. (On a loaded machine a reply
    // can miss its 8 ms budget before the unplug and latch read_timeout first; the force is
    // zero from that fault on, which the loop below checks from the loss.)
    std::size_t first_fault = 0;
    while (first_fault < lost && faults_at(log, first_fault) == 0u) ++first_fault;
    EXPECT_EQ(f[first_fault], 0.0);
    double pulled = 0.0;
    for (std::size_t row = 0; row < first_fault; ++row) pulled = std::max(pulled, std::abs(f[row]));
    EXPECT_GT(pulled, 0.5);
    EXPECT_NE(static_cast<std::uint32_t>(log.column("status")[lost]) & servo::kStatusDisconnected,
              0u);
    // Back: the latch cleared, and the spring pulls again at the end.
    std::size_t cleared = lost;
    while (cleared < log.rows() && faults_at(log, cleared) != 0u) ++cleared;
    ASSERT_LT(cleared, log.rows()) << "never recovered";
    for (std::size_t row = lost; row < cleared; ++row) ASSERT_EQ(f[row], 0.0) << row;
    EXPECT_GT(std::abs(f.back()), 0.5);
    const double outage_s = t[cleared] - t[lost];
    std::cout << "[serial] device lost at t = " << t[lost] << " s, latch cleared " << outage_s
              << " s later (0.3 s unplugged, the reconnect, 0.5 s settle); faults seen: " << faults
              << "\n";
    EXPECT_GT(outage_s, 0.3 + 0.5 - 0.05);
}

// `status` over the control socket (docs/control.md) while hapticd runs on the serial plugin:
// the device's link counts arrive (counted), and three corrupted replies show as bad frames
// and reply timeouts, in the JSON and in hapticctl's text. In real time at 100 Hz, as above.
TEST(SerialDaemon, StatusReportsTheLinksBadFramesAndReplyTimeouts) {
    constexpr double kRate = 100.0;
    constexpr std::uint64_t kCorruptAtCommand = 150;
    const ScratchDir dir;
    PtyDevice device(pen_display_device(stiff_grasp(""), kRate));
    std::atomic<bool> corrupted{false};
    device.set_request_hook([&corrupted](proto::DeviceEmulator& e, std::uint64_t) {
        if (!corrupted && e.counters().commands_applied >= kCorruptAtCommand) {
            e.faults().corrupt_crc = 3;
            corrupted = true;
        }
    });
    dir.write("scene.toml", kSpringScene);
    const std::string config = serial_spring_config(
        kRate, device.port(), "max_missed_periods = 1000\nmax_consecutive_overruns = 1000\n", "");
    Daemon d(dir, "serial", ConfigText{config});
    ASSERT_TRUE(d.process.wait_for_socket(d.socket)) << d.process.messages();

    const nlohmann::json first = status_of(d.socket);
    ASSERT_FALSE(first.is_null());
    const nlohmann::json& link = first.at("link");
    EXPECT_EQ(link.at("counted"), true) << first.dump();
    EXPECT_GT(link.at("frames_sent").get<std::uint64_t>(), 0u) << first.dump();
    EXPECT_GT(link.at("frames_received").get<std::uint64_t>(), 0u) << first.dump();

    const nlohmann::json after = status_when(
        d.socket,
        // Each counter is its own relaxed atomic: wait for all three, not for two of them
        // (a status between one read's two counts once showed read_timeouts 2).
        [](const nlohmann::json& s) {
            return s["link"]["bad_frames"] >= 3 && s["link"]["reply_timeouts"] >= 3 &&
                   s["link"]["read_timeouts"] >= 3;
        },
        std::chrono::seconds(20));
    ASSERT_FALSE(after.is_null());
    EXPECT_TRUE(corrupted.load());
    EXPECT_GE(after["link"]["bad_frames"].get<std::uint64_t>(), 3u) << after.dump();
    EXPECT_GE(after["link"]["reply_timeouts"].get<std::uint64_t>(), 3u) << after.dump();
    EXPECT_GE(after["link"]["read_timeouts"].get<std::uint64_t>(), 3u) << after.dump();
    EXPECT_GE(after["link"]["frames_sent"].get<std::uint64_t>(), kCorruptAtCommand);
    EXPECT_EQ(after["link"]["disconnects"], 0) << after.dump();

    const CommandResult text = hapticctl(d.socket, "status");
    EXPECT_EQ(text.exit_code, 0) << text.err;
    EXPECT_NE(text.out.find("\nlink      "), std::string::npos) << text.out;
    EXPECT_NE(text.out.find("\nframes    "), std::string::npos) << text.out;
    EXPECT_NE(text.out.find(" bad, "), std::string::npos) << text.out;
    std::cout << "[serial] status: " << after["link"].dump() << "\n";
    (void)d.process.stop();
}

}  // namespace
}  // namespace hapticd::testing
