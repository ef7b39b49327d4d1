// haptic-tune diag's measurement (tools/haptic-tune/link_diag.hpp) through the serial plugin and a
// real tty (a pty pair) against the reference device: the faults injected at known requests are the
// faults it reports, the device's clock is fitted against the host's, and the loop delay it
// measures from protocol version 2's acknowledgements is the device's processing delay; a version-1
// firmware gets "not measured", and bad acknowledgements are counted.
#include <gtest/gtest.h>

#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "hapticd/daemon/config.hpp"
#include "link_diag.hpp"
#include "pty_device.hpp"

namespace hapticd::testing {
namespace {

namespace proto = device::protocol;

proto::EmulatorConfig emulator_config(double processing_delay_periods = 0.0) {
    proto::EmulatorConfig c;
    c.sim.axes = 1;
    c.sim.rate_hz = 500.0;
    c.sim.delay_s = processing_delay_periods / c.sim.rate_hz;
    c.serial_number = "PTY-DIAG";
    return c;
}

constexpr double kPeriodS = 1.0 / 500.0;

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

daemon::DiagReport diagnose(PtyDevice& device, double duration_s) {
    daemon::DiagOptions options;
    options.duration_s = duration_s;
    std::ostringstream log;
    return daemon::run_link_diag(diag_config(device.port()), options, log);
}

TEST(SerialLinkDiag, MeasuresTheDevicesProcessingDelayOverTheLink) {
    // The reference device's clock is virtual: it stands still between requests, and in it
    // each command arrives at the instant the sample it was computed from was latched, so
    // the delay measured is its processing delay, exactly: to the wire's 1 us, whatever the
    // pty and the host's scheduling did. That is the tolerance.
    for (const double periods : {0.5, 1.5}) {
        PtyDevice device(emulator_config(periods));
        const daemon::DiagReport r = diagnose(device, 1.0);
        ASSERT_TRUE(r.delay_measured) << periods << ": " << r.delay_missing;
        EXPECT_EQ(r.protocol_version, 2);
        EXPECT_FALSE(r.samples_at_read);
        EXPECT_GE(r.delay_commands, 490u) << periods;  // all but the last few, and any lost
        EXPECT_NEAR(r.delay_s.p50, periods * kPeriodS, 1e-6) << periods;
        EXPECT_NEAR(r.delay_s.p99, periods * kPeriodS, 1e-6) << periods;
        EXPECT_NEAR(r.delay_s.max, periods * kPeriodS, 1e-6) << periods;
        EXPECT_NEAR(r.recommended_delay_s, periods * kPeriodS, 1e-9) << periods;
        // The host held each sample until its next tick: most of a period.
        EXPECT_GT(r.host_s.p50, 0.2 * kPeriodS) << periods;
        EXPECT_EQ(r.bad_ack_command + r.bad_ack_time + r.acausal + r.clock_backwards, 0u);
        const std::string text = daemon::diag_text(r);
        std::cout << "processing delay " << periods << " periods:\n"
                  << text;  // docs/link-diagnostics.md
        EXPECT_NE(text.find("loop delay (encoder sample -> force in effect, device clock)"),
                  std::string::npos)
            << text;
        if (periods < 1.0) {
            // Less delay than the host held the sample: the virtual clock shows itself, and
            // no split is made up.
            EXPECT_FALSE(r.delay_split);
            EXPECT_NE(text.find("link and device: not split"), std::string::npos) << text;
        }
    }
}

TEST(SerialLinkDiag, AVersion1FirmwareCannotHaveItsDelayMeasuredAndSaysWhy) {
    proto::EmulatorConfig config = emulator_config(0.5);
    config.max_version = 1;  // a firmware from before the acknowledgements
    PtyDevice device(config);
    const daemon::DiagReport r = diagnose(device, 0.2);
    EXPECT_EQ(r.protocol_version, 1);
    EXPECT_EQ(r.replies, 100u);
    EXPECT_FALSE(r.delay_measured);
    EXPECT_EQ(r.delay_commands, 0u);
    EXPECT_EQ(r.applied_unsupported, 100u);
    EXPECT_NE(r.delay_missing.find("protocol version 1"), std::string::npos) << r.delay_missing;
    EXPECT_NE(r.delay_missing.find("applied_lag and applied_age_us"), std::string::npos)
        << r.delay_missing;
    const std::string text = daemon::diag_text(r);
    std::cout << text;  // docs/link-diagnostics.md
    EXPECT_NE(text.find("loop delay: not measured: the device speaks protocol version 1"),
              std::string::npos)
        << text;
    EXPECT_EQ(text.find("[device.model] delay = "), std::string::npos) << text;  // no number
    if (r.rtt_p99_us < 0.3e6 * kPeriodS) {  // a loaded machine's slow pty is its own WARN
        EXPECT_NE(text.find("verdict: ok"), std::string::npos) << text;  // the link is fine
    }
    const nlohmann::json j = nlohmann::json::parse(daemon::diag_json(r));
    EXPECT_FALSE(j["loop_delay"]["measured"].get<bool>());
    EXPECT_TRUE(j["loop_delay"]["s"].is_null());
    EXPECT_TRUE(j["loop_delay"]["recommended_s"].is_null());
    EXPECT_EQ(j["loop_delay"]["protocol_version"], 1);
}

TEST(SerialLinkDiag, BadAcknowledgementsAreCountedAndReportedNeverUsed) {
    PtyDevice device(emulator_config(0.5));
    // As above: commands from request 5. At exchange 100 the answer names a command never
    // sent; at 200 the device clock jumps 5 ms back; at 300 the command in effect claims to
    // have taken effect 2.5 ms earlier than it did, before the one before it.
    constexpr std::uint64_t kFirstCommand = 5;
    device.set_request_hook([](proto::DeviceEmulator& emulator, std::uint64_t requests) {
        if (requests + 1 == kFirstCommand + 100) emulator.faults().applied_unsent = 1;
        if (requests + 1 == kFirstCommand + 200) emulator.faults().clock_back_us = 5000;
        if (requests + 1 == kFirstCommand + 300) emulator.faults().applied_early_us = 2500;
    });
    const daemon::DiagReport r = diagnose(device, 1.0);
    EXPECT_EQ(r.replies, 500u);  // every sample arrived and was used by the servo's side
    EXPECT_EQ(r.bad_ack_command, 1u);
    EXPECT_EQ(r.bad_ack_time, 2u);
    EXPECT_EQ(r.clock_backwards, 1u);
    EXPECT_EQ(r.acausal, 0u);
    // The rest is measured as before, none of the bad ones in it.
    ASSERT_TRUE(r.delay_measured);
    EXPECT_GE(r.delay_commands, 490u);
    EXPECT_NEAR(r.delay_s.max, 0.5 * kPeriodS, 1e-6);
    EXPECT_NEAR(r.delay_s.p50, 0.5 * kPeriodS, 1e-6);
    const std::string text = daemon::diag_text(r);
    EXPECT_NE(text.find("bad: 1 naming a command never sent, 2 with inconsistent times"),
              std::string::npos)
        << text;
    if (r.rtt_p99_us < 0.3e6 * kPeriodS) {  // else the slow round trip is the verdict
        EXPECT_NE(
            text.find("verdict: WARN: the device's timestamps or acknowledgements contradict"),
            std::string::npos)
            << text;
    }
}

}  // namespace
}  // namespace hapticd::testing
