// haptic-tune conform against the reference firmware's binary on the emulated board (lockstep):
// every check of docs/protocol.md section 9 passes; a build of the same firmware without its
// watchdog (hapkit-broken-no-watchdog.elf, never to be flashed) fails the watchdog check,
// saying so, and nothing else.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "emulated_hapkit.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"

namespace hapticd::testing {
namespace {

nlohmann::json conform(const ScratchDir& dir, const EmulatedHapkit& board, int& exit_code) {
    const std::string config =
        dir.write("hapkit.toml",
                  "[servo]\nrate_hz = 1000.0\nrealtime = \"off\"\n[device]\n"
                  "plugin = \"serial\"\n[device.serial]\nport = \"" +
                      board.port() + "\"\nserial_number = \"HAPKIT3-0001\"\n");
    const CommandResult r =
        run_command(shell_quote(HAPTIC_TUNE_BIN) + " conform --lockstep --json --config " +
                    shell_quote(config));
    exit_code = r.exit_code;
    EXPECT_FALSE(r.out.empty()) << r.err;
    return r.out.empty() ? nlohmann::json() : nlohmann::json::parse(r.out);
}

TEST(FilConform, TheReferenceFirmwarePassesEveryCheck) {
    const ScratchDir dir;
    EmulatedHapkit board(dir, {"--clock", "lockstep"});
    int exit_code = -1;
    const nlohmann::json report = conform(dir, board, exit_code);
    EXPECT_EQ(exit_code, 0) << report.dump(2);
    ASSERT_TRUE(report.is_object());
    EXPECT_TRUE(report.at("passed").get<bool>());
    EXPECT_EQ(report.at("checks").size(), 10u);
    for (const nlohmann::json& check : report.at("checks")) {
        EXPECT_EQ(check.at("outcome"), "pass") << check;
        std::cout << "[fil] conform " << check.at("name").get<std::string>() << ": "
                  << check.at("detail").get<std::string>() << "\n";
    }
    EXPECT_EQ(report.at("identity").at("version"), 3);
    EXPECT_TRUE(report.at("identity").at("paced").get<bool>());
    board.stop();
    // Every command asked for zero force: the motor never moved.
    const PinRecord pins = board.pins();
    for (const double force : pins["motor_force_n"]) ASSERT_EQ(force, 0.0);
}

TEST(FilConform, AFirmwareWithoutItsWatchdogFailsTheWatchdogCheckAndNoOther) {
    const ScratchDir dir;
    EmulatedHapkit board(dir, {"--clock", "lockstep"}, HAPTICD_BROKEN_FIRMWARE_ELF);
    int exit_code = -1;
    const nlohmann::json report = conform(dir, board, exit_code);
    EXPECT_EQ(exit_code, 1);
    ASSERT_TRUE(report.is_object());
    EXPECT_FALSE(report.at("passed").get<bool>());
    for (const nlohmann::json& check : report.at("checks")) {
        if (check.at("name") == "watchdog") {
            EXPECT_EQ(check.at("outcome"), "fail");
            EXPECT_EQ(check.at("detail"),
                      "no watchdog fault 25 ms after the last command (timeout 20 ms): the force "
                      "would stay on with the host gone (5.4)");
        } else {
            EXPECT_EQ(check.at("outcome"), "pass") << check;
        }
    }
    board.stop();
}

}  // namespace
}  // namespace hapticd::testing
