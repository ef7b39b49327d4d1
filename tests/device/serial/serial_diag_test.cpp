// haptic-tune diag's measurement (daemon/link_diag.hpp) through the serial plugin and a real
// tty (a pty pair) against the reference device: the faults injected at known requests are
// the faults it reports, and the device's clock is fitted against the host's.
#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/link_diag.hpp"
#include "pty_device.hpp"

namespace hapticd::testing {
namespace {

namespace proto = device::protocol;

proto::EmulatorConfig emulator_config() {
    proto::EmulatorConfig c;
    c.sim.axes = 1;
    c.sim.rate_hz = 500.0;
    c.serial_number = "PTY-DIAG";
    return c;
}

daemon::Config diag_config(const std::string& port) {
    // A generous reply timeout: on a loaded VM a pty round trip can take milliseconds, and
    // this test counts only the faults it injects.
    return daemon::parse_config(R"(
[servo]
rate_hz = 500
realtime = "off"
[device]
plugin = "serial"
[device.model]
mass = 0.1
damping = 2.0
[device.serial]
port = ")" + port + R"("
reply_timeout_ms = 500
reconnect = false
[coupling]
stiffness = 1000
)",
                                "diag.toml", "");
}

TEST(SerialLinkDiag, ReportsTheInjectedLossesAndLateRepliesThroughARealTty) {
    PtyDevice device(emulator_config());
    // Requests: hello, configure, poll (handshake), the diag's first poll, then one command
    // per exchange. Drop the reply to exchange 100 and hold back the reply to exchange 300.
    constexpr std::uint64_t kFirstCommand = 5;
    device.set_request_hook([](proto::DeviceEmulator& emulator, std::uint64_t requests) {
        if (requests + 1 == kFirstCommand + 100) emulator.faults().drop = 1;
        if (requests + 1 == kFirstCommand + 300) emulator.faults().delay = 1;
    });
    daemon::DiagOptions options;
    options.duration_s = 1.0;
    std::ostringstream log;
    const daemon::DiagReport r = daemon::run_link_diag(diag_config(device.port()), options, log);

    EXPECT_EQ(r.plugin, "serial");
    EXPECT_EQ(r.serial, "PTY-DIAG");
    EXPECT_EQ(r.exchanges, 500u);
    EXPECT_EQ(r.no_reply, 2u);       // the dropped reply, and the held-back one in its period
    EXPECT_EQ(r.late, 1u);           // the held-back reply came in the next period
    EXPECT_EQ(r.lost, 1u);           // only the dropped one never came
    EXPECT_EQ(r.sequence_gaps, 2u);  // neither sample reached the servo
    EXPECT_EQ(r.replies, 498u);
    EXPECT_EQ(r.disconnects + r.errors, 0u);
    EXPECT_GT(r.rtt_p50_us, 0.0);
    EXPECT_LT(r.rtt_p50_us, 500'000.0);  // within the reply timeout, by construction
    ASSERT_TRUE(r.clock_fit);
    EXPECT_NE(daemon::diag_text(r).find("lost: 1"), std::string::npos) << daemon::diag_text(r);
}

}  // namespace
}  // namespace hapticd::testing
