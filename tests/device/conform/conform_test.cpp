// haptic-tune conform end to end against the C++ reference device (DeviceEmulator) behind a
// pseudo-terminal, through the serial transport: it passes the checklist, and each way of
// breaking it that the emulator can play fails the right check with its reason. The firmware's
// own binary, and a build of it without the watchdog, are in tests/fil/fil_conform_test.cpp.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "pty_device.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"

namespace hapticd::testing {
namespace {

namespace proto = device::protocol;

/// The reference device as a lab's firmware would be: 1 kHz, its clock running while it is
/// polled (a real device's clock does; the emulator's runs with requests).
proto::EmulatorConfig reference_device() {
    proto::EmulatorConfig c;
    c.sim.axes = 1;
    c.sim.rate_hz = 1000.0;
    c.serial_number = "EMU-CONFORM";
    c.poll_advances_period = true;
    return c;
}

std::string device_config(const std::string& port, double rate_hz = 1000.0,
                          const std::string& plugin = "serial") {
    return "[servo]\nrate_hz = " + std::to_string(rate_hz) +
           "\nrealtime = \"off\"\n[device]\nplugin = \"" + plugin +
           "\"\n[device.serial]\nport = \"" + port + "\"\nserial_number = \"EMU-CONFORM\"\n";
}

// NOLINTNEXTLINE(bugprone-exception-escape): nlohmann::json's noexcept move is reported as throwing
struct Conform {
    int exit_code = -1;
    nlohmann::json report;
    std::string err;
    /// The check named `name`.
    const nlohmann::json& check(const std::string& name) const {
        for (const nlohmann::json& c : report.at("checks")) {
            if (c.at("name") == name) return c;
        }
        throw std::runtime_error("no check " + name);
    }
};

Conform conform(const ScratchDir& dir, const std::string& config_toml,
                const std::string& options = "--lockstep --exchanges 200") {
    const std::string config = dir.write("device.toml", config_toml);
    const CommandResult r = run_command(shell_quote(HAPTIC_TUNE_BIN) + " conform --json " +
                                        options + " --config " + shell_quote(config));
    Conform out;
    out.exit_code = r.exit_code;
    out.err = r.err;
    if (!r.out.empty()) out.report = nlohmann::json::parse(r.out);
    return out;
}

TEST(HapticTuneConform, TheReferenceDevicePassesEveryCheck) {
    const ScratchDir dir;
    PtyDevice device(reference_device());
    const Conform c = conform(dir, device_config(device.port()));
    ASSERT_EQ(c.exit_code, 0) << c.report.dump(2) << c.err;
    EXPECT_TRUE(c.report.at("passed").get<bool>());
    const std::vector<std::string> names = {
        "handshake", "versions",     "sessions",       "configure", "commands",
        "timing",    "frame_errors", "message_errors", "watchdog",  "bye"};
    ASSERT_EQ(c.report.at("checks").size(), names.size());
    for (std::size_t i = 0; i < names.size(); ++i) {
        EXPECT_EQ(c.report.at("checks")[i].at("name"), names[i]);
        EXPECT_EQ(c.report.at("checks")[i].at("outcome"), "pass") << c.report.at("checks")[i];
    }
    const nlohmann::json& identity = c.report.at("identity");
    EXPECT_EQ(identity.at("version"), 2);  // the emulator's newest
    EXPECT_EQ(identity.at("serial"), "EMU-CONFORM");
    EXPECT_EQ(identity.at("period_us"), 1000);
    // The evidence is the device's own numbers. The watchdog counts from the command's
    // arrival; the sample it is measured from was latched a period later (the emulator holds
    // the command for its period first), so 19 ms.
    EXPECT_NE(c.check("watchdog")
                  .at("detail")
                  .get<std::string>()
                  .find("watchdog fault 19 ms after the last command (timeout 20 ms)"),
              std::string::npos)
        << c.check("watchdog");
    EXPECT_NE(c.check("timing").at("detail").get<std::string>().find(
                  "200 of 200 commands answered; the device's clock p50 1000 us apart"),
              std::string::npos)
        << c.check("timing");
    EXPECT_NE(c.check("versions")
                  .at("detail")
                  .get<std::string>()
                  .find("highest common version 2; speaks version 1"),
              std::string::npos);
}

TEST(HapticTuneConform, AClockThatStandsStillFailsTheWatchdogCheckWithItsReason) {
    // The emulator's own default: polls do not let time pass, so with the host only polling
    // the watchdog never sees its timeout go by.
    const ScratchDir dir;
    proto::EmulatorConfig still = reference_device();
    still.poll_advances_period = false;
    PtyDevice device(still);
    const Conform c = conform(dir, device_config(device.port()));
    EXPECT_EQ(c.exit_code, 1);
    EXPECT_FALSE(c.report.at("passed").get<bool>());
    EXPECT_EQ(c.check("watchdog").at("outcome"), "fail");
    EXPECT_NE(c.check("watchdog")
                  .at("detail")
                  .get<std::string>()
                  .find("no watchdog fault 25 ms after the last command (timeout 20 ms)"),
              std::string::npos)
        << c.check("watchdog");
    EXPECT_EQ(c.check("commands").at("outcome"), "pass");
}

TEST(HapticTuneConform, ADeviceAtAnotherRateFailsTheHandshakeAndTheTextTableSaysSo) {
    const ScratchDir dir;
    PtyDevice device(reference_device());
    const std::string config = dir.write("device.toml", device_config(device.port(), 500.0));
    const CommandResult r =
        run_command(shell_quote(HAPTIC_TUNE_BIN) + " conform --lockstep --exchanges 20 --config " +
                    shell_quote(config));
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.out.find("FAIL  handshake       5.1, 4.2   the identity's period is 1000 us; the "
                         "host's rate needs 2000 us ([servo] rate_hz)"),
              std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("FAIL: "), std::string::npos) << r.out;
}

TEST(HapticTuneConform, BadInputIsRefusedWithExit2) {
    const ScratchDir dir;
    const Conform sim = conform(dir, "[device]\nplugin = \"sim\"\n");
    EXPECT_EQ(sim.exit_code, 2);
    EXPECT_NE(
        sim.err.find("[device] plugin = \"sim\": conform tests a device on the open protocol"),
        std::string::npos)
        << sim.err;
    PtyDevice device(reference_device());
    const Conform watchdog =
        conform(dir, device_config(device.port()), "--lockstep --watchdog 1.5");
    EXPECT_EQ(watchdog.exit_code, 2);
    EXPECT_NE(watchdog.err.find("the watchdog timeout 1500 us is out of range: allowed two periods "
                                "(2000 us) to 1000000 us"),
              std::string::npos)
        << watchdog.err;
    const Conform absent = conform(dir, device_config(dir.file("no-such-tty")), "--lockstep");
    EXPECT_EQ(absent.exit_code, 2);
    EXPECT_NE(absent.err.find("haptic-tune: device error: "), std::string::npos) << absent.err;
}

}  // namespace
}  // namespace hapticd::testing
