// haptic-tune autotune measures the loop delay over the link before its identification run
// (tools/haptic-tune/cmd_autotune.cpp): the real executable, the serial plugin and the
// reference device behind a pty, in real time. A device on protocol version 2 gets its delay
// measured and used; a version-1 firmware, with no delay stated anywhere, is refused before
// anything runs, naming what is missing.
#include <gtest/gtest.h>

#include <string>

#include "pty_device.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "text_file.hpp"

namespace hapticd::testing {
namespace {

namespace proto = device::protocol;

proto::EmulatorConfig emulator(double processing_delay_periods, std::uint8_t max_version) {
    proto::EmulatorConfig c;
    c.sim.axes = 1;
    c.sim.rate_hz = 500.0;
    c.sim.delay_s = processing_delay_periods / c.sim.rate_hz;
    c.max_version = max_version;
    c.serial_number = "PTY-TUNE";
    return c;
}

/// A lab's config `name` in `dir` for the device on `port`, [device.model] with or without a
/// delay.
std::string write_config(const ScratchDir& dir, const std::string& name, const std::string& port,
                         const std::string& model_extra) {
    return dir.write(name,
                     "[servo]\nrate_hz = 500\nrealtime = \"off\"\n"
                     "[device]\nplugin = \"serial\"\n"
                     "[device.model]\nmass = 0.1\ndamping = 2.0\n" +
                         model_extra + "[device.serial]\nport = \"" + port +
                         "\"\nreply_timeout_ms = 500\nreconnect = false\n"
                         "[coupling]\nstiffness = 100\n");
}

TEST(SerialAutotune, MeasuresTheLoopDelayBeforeTheIdentificationRun) {
    const ScratchDir dir;
    PtyDevice device(emulator(1.5, proto::kProtocolVersion2));
    const std::string config = write_config(dir, "lab.toml", device.port(), "");
    const std::string before = read_file(config);
    // No hapticd to run: autotune measures the delay, says what it found, then stops at the
    // identification run, writing nothing.
    const CommandResult r = run_command(std::string("'") + HAPTIC_TUNE + "' autotune --config '" +
                                        config + "' --hapticd /nonexistent/hapticd");
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("measuring the loop delay over the link"), std::string::npos) << r.err;
    // 1.5 periods at 500 Hz, exactly (the emulator's virtual clock: serial_diag_test).
    EXPECT_NE(r.err.find("p50 1.5 periods, p99 1.5 periods; sized for 0.003 s (1.5 periods: "
                         "the p99 rounded up to the next 0.05 period)"),
              std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("cannot run /nonexistent/hapticd"), std::string::npos) << r.err;
    EXPECT_EQ(read_file(config), before);
}

TEST(SerialAutotune, AVersion1FirmwareWithNoDelayStatedIsRefusedNamingWhatIsMissing) {
    const ScratchDir dir;
    PtyDevice device(emulator(0.5, proto::kProtocolVersion1));
    const std::string config = write_config(dir, "lab.toml", device.port(), "");
    const std::string before = read_file(config);
    const CommandResult r = run_command(std::string("'") + HAPTIC_TUNE + "' autotune --config '" +
                                        config + "' --hapticd /nonexistent/hapticd");
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("the loop delay is unknown: it could not be measured over the link "
                         "(the device speaks protocol version 1"),
              std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("applied_lag and applied_age_us"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("give --delay SECONDS"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("running /nonexistent/hapticd"), std::string::npos) << r.err;
    EXPECT_EQ(read_file(config), before);

    // With [device.model] delay stated, autotune goes on with it, saying it was not measured.
    const std::string stated = write_config(dir, "stated.toml", device.port(), "delay = 0.002\n");
    const CommandResult s = run_command(std::string("'") + HAPTIC_TUNE + "' autotune --config '" +
                                        stated + "' --hapticd /nonexistent/hapticd");
    EXPECT_EQ(s.exit_code, 2) << s.err;
    EXPECT_NE(s.err.find("loop delay 0.002 s (1 period): [device.model] delay; not measured: "
                         "the device speaks protocol version 1"),
              std::string::npos)
        << s.err;
    EXPECT_NE(s.err.find("cannot run /nonexistent/hapticd"), std::string::npos) << s.err;
}

}  // namespace
}  // namespace hapticd::testing
