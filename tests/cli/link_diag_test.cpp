// Link diagnostics (tools/haptic-tune/link_diag.hpp) against the sim plugin, whose faults are
// scripted: every count the report gives is checked against the faults that were injected.
#include "link_diag.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace hapticd::daemon {
namespace {

Config sim_config(const std::string& faults, const std::string& model = "",
                  const std::string& sim = "") {
    return parse_config(R"(
[servo]
rate_hz = 1000
realtime = "off"
[device]
plugin = "sim"
[device.model]
mass = 0.1
damping = 2.0
)" + model + R"(
[device.sim]
mass = 0.1
damping = 2.0
)" + sim + faults + R"(
[coupling]
stiffness = 3000
)",
                        "diag.toml", "");
}

DiagReport diagnose(const Config& config, double duration_s, bool lockstep) {
    DiagOptions options;
    options.duration_s = duration_s;
    options.lockstep = lockstep;
    std::ostringstream log;
    return run_link_diag(config, options, log);
}

TEST(DaemonLinkDiag, CountsEachScriptedDropAsLostAndEachLateSampleAsLate) {
    // Lockstep: exchange n happens at t = n ms exactly, so the faults land where scripted.
    const DiagReport r = diagnose(sim_config(R"(
[device.sim.faults]
drop_at = [0.100, 0.200, 0.300]
late_at = [0.150, 0.250]
)"),
                                  0.5, true);
    EXPECT_EQ(r.exchanges, 500u);
    EXPECT_EQ(r.no_reply, 3u);
    EXPECT_EQ(r.lost, 3u);  // the sim's late samples arrive (late), they are not lost
    EXPECT_EQ(r.late, 2u);
    EXPECT_EQ(r.sequence_gaps, 3u);  // a dropped sample still used a sequence number
    EXPECT_EQ(r.replies, 497u);
    EXPECT_EQ(r.disconnects, 0u);
    EXPECT_FALSE(r.clock_fit);  // virtual time: no drift estimate
    std::uint64_t binned = 0;
    for (const RttBin& bin : r.rtt_histogram) binned += bin.count;
    EXPECT_EQ(binned, r.replies);
}

TEST(DaemonLinkDiag, ADisconnectedDeviceIsCountedNotLost) {
    const DiagReport r = diagnose(sim_config(R"(
[device.sim.faults]
disconnect_at = 0.100
)"),
                                  0.2, true);
    EXPECT_GE(r.disconnects, 99u);
    EXPECT_LE(r.disconnects, 101u);
    EXPECT_EQ(r.lost, 0u);
    EXPECT_EQ(r.replies + r.disconnects, r.exchanges);
}

TEST(DaemonLinkDiag, RealtimeSimHasNoDriftAndAFastRoundTrip) {
    const DiagReport r = diagnose(sim_config(""), 1.0, false);
    EXPECT_EQ(r.exchanges, 1000u);
    EXPECT_EQ(r.lost, 0u);
    ASSERT_TRUE(r.clock_fit);
    // The sim's clock is the host's: the fit says so within the VM's noise.
    EXPECT_LT(std::abs(r.clock_drift_ppm), 2000.0);
    EXPECT_LT(r.rtt_p50_us, 200.0);  // no transport: the call itself
    // Paced on absolute deadlines: never faster than the rate; slower only by the periods
    // a loaded machine made it miss, and those are counted.
    EXPECT_GE(r.duration_s, 0.999);
    if (r.duration_s > 1.1) {
        EXPECT_GT(r.overruns, 0u);
    }
    // On a quiet machine the verdict is ok; a loaded one may preempt the host between the
    // write and the read, which the verdict rightly calls a slow round trip.
    // The sim has no delay of its own: its commands land as they are written, right after
    // the sample (the daemon's order), so the loop delay is the host's few microseconds.
    ASSERT_TRUE(r.delay_measured) << r.delay_missing;
    EXPECT_LT(r.delay_s.p50, 50e-6);
    EXPECT_TRUE(r.delay_split);
    if (r.rtt_p99_us < 300.0 && r.delay_s.p99 < 50e-6) {
        EXPECT_NE(diag_text(r).find("verdict: ok"), std::string::npos) << diag_text(r);
    } else {
        EXPECT_NE(diag_text(r).find("verdict: WARN: p99 round trip"), std::string::npos)
            << diag_text(r);
    }
}

TEST(DaemonLinkDiag, JsonCarriesEveryFigure) {
    const DiagReport r = diagnose(sim_config("[device.sim.faults]\ndrop_at = [0.05]\n"), 0.1, true);
    const nlohmann::json j = nlohmann::json::parse(diag_json(r));
    EXPECT_EQ(j["plugin"], "sim");
    EXPECT_EQ(j["exchanges"], 100);
    EXPECT_EQ(j["lost"], 1);
    EXPECT_EQ(j["rtt_histogram"].size(), r.rtt_histogram.size());
    EXPECT_TRUE(j["rtt_histogram"].back()["hi_us"].is_null());  // the open last bin
    EXPECT_TRUE(j["clock_drift_ppm"].is_null());
    EXPECT_DOUBLE_EQ(j["rtt_us"]["p99"].get<double>(), r.rtt_p99_us);
    EXPECT_NE(diag_text(r).find("WARN"), std::string::npos);  // 1 % lost
    // The sim says when each command took effect: no delay of its own, none measured.
    ASSERT_TRUE(j["loop_delay"]["measured"].get<bool>());
    EXPECT_EQ(j["loop_delay"]["s"]["p99"].get<double>(), 0.0);
    EXPECT_EQ(j["loop_delay"]["recommended_s"].get<double>(), 0.0);
    EXPECT_FALSE(std::signbit(r.recommended_delay_s));        // 0, not -0: it goes into a config
    EXPECT_TRUE(j["loop_delay"]["link_device_s"].is_null());  // lockstep: not split
}

TEST(DaemonLinkDiag, MeasuresTheSimsLoopDelayExactlyInLockstep) {
    // [device.sim] delay = 1.5 periods: every command lands 1.5 ms after the sample it was
    // computed from, in virtual time, exactly.
    const DiagReport r = diagnose(sim_config("", "", "delay = 0.0015\n"), 0.5, true);
    ASSERT_TRUE(r.delay_measured) << r.delay_missing;
    EXPECT_TRUE(r.samples_at_read);
    EXPECT_EQ(r.protocol_version, 0);
    EXPECT_EQ(r.delay_commands, 498u);  // the last two land after the run
    EXPECT_NEAR(r.delay_s.p50, 1.5e-3, 1e-12);
    EXPECT_NEAR(r.delay_s.p99, 1.5e-3, 1e-12);
    EXPECT_NEAR(r.delay_s.max, 1.5e-3, 1e-12);
    EXPECT_NEAR(r.recommended_delay_s, 1.5e-3, 1e-12);  // on the 0.05-period grid already
    EXPECT_FALSE(r.delay_split);                        // lockstep: host time is not physical
    EXPECT_EQ(r.bad_ack_command + r.bad_ack_time + r.acausal + r.clock_backwards, 0u);
    const std::string text = diag_text(r);
    EXPECT_NE(text.find("p50 1.500 ms (1.500 periods)"), std::string::npos) << text;
    EXPECT_NE(text.find("[device.model] delay = 0.0015  # s: the p99 rounded up"),
              std::string::npos)
        << text;
    // The config assumed no delay: the verdict says so and what to set.
    EXPECT_NE(text.find("verdict: WARN: [device.model] delay = 0 s is below the measured loop "
                        "delay (p99 0.0015 s)"),
              std::string::npos)
        << text;
    EXPECT_NE(text.find("set delay = 0.0015"), std::string::npos) << text;

    // With the delay in the config the verdict is ok.
    const DiagReport stated =
        diagnose(sim_config("", "delay = 0.0015\n", "delay = 0.0015\n"), 0.2, true);
    EXPECT_NE(diag_text(stated).find("covers it"), std::string::npos) << diag_text(stated);
    EXPECT_NE(diag_text(stated).find("verdict: ok"), std::string::npos) << diag_text(stated);
}

TEST(DaemonLinkDiag, AFractionalDelayIsRoundedUpToTheNextTwentiethOfAPeriod) {
    const DiagReport r = diagnose(sim_config("", "", "delay = 0.00062\n"), 0.2, true);
    ASSERT_TRUE(r.delay_measured);
    EXPECT_NEAR(r.delay_s.p99, 0.62e-3, 1e-9);
    EXPECT_NEAR(r.recommended_delay_s, 0.65e-3, 1e-12);
}

TEST(DaemonLinkDiag, MeasuresTheSimsLoopDelayOnTheRealtimeClock) {
    // Half a period: the daemon's order (read, then write) leaves the sim's own delay to
    // show, and the host's part is the few microseconds between the two calls.
    const DiagReport r =
        diagnose(sim_config("", "delay = 0.0005\n", "delay = 0.0005\n"), 0.5, false);
    ASSERT_TRUE(r.delay_measured) << r.delay_missing;
    // The sim lands each command 0.5 ms after its sample, to 2^-20 period, unless the write
    // came later than that (a preempted host): then at the write.
    EXPECT_NEAR(r.delay_s.p50, 0.5e-3, 2e-9);
    EXPECT_GE(r.delay_s.p99, 0.5e-3 - 2e-9);
    EXPECT_LT(r.host_s.p50, 100e-6);
    EXPECT_TRUE(r.delay_split);
    EXPECT_NEAR(r.link_s.p50, r.delay_s.p50 - r.host_s.p50, 50e-6);
    const nlohmann::json j = nlohmann::json::parse(diag_json(r));
    const nlohmann::json& d = j.at("loop_delay");
    EXPECT_TRUE(d.at("measured").get<bool>());
    EXPECT_NEAR(d.at("periods").at("p50").get<double>(), 0.5, 2e-6);
    EXPECT_TRUE(d.at("split").get<bool>());
    EXPECT_TRUE(d.at("protocol_version").is_null());
    EXPECT_EQ(d.at("bad_command"), 0);
    EXPECT_EQ(d.at("configured_s").get<double>(), 0.0005);
}

// The verdict's rules in their order, on reports built by hand: each case breaks one more
// rule than the one before, and the verdict names the first broken rule only.
TEST(DaemonLinkDiag, TheVerdictNamesTheFirstFigureThatFails) {
    using Level = DiagVerdict::Level;
    DiagReport r;
    r.rate_hz = 1000.0;
    r.exchanges = 10000;
    r.replies = 10000;
    r.rtt_p99_us = 120.0;
    EXPECT_EQ(r.verdict().level, Level::ok);
    EXPECT_EQ(r.verdict().text, "ok: the link keeps up with 1000 Hz");

    r.delay_measured = true;  // the configured delay (0 s) is below the measured p99
    r.delay_s.p99 = 0.0012;
    r.recommended_delay_s = 0.0012;
    EXPECT_EQ(r.verdict().level, Level::warn);
    EXPECT_EQ(r.verdict().text.rfind("WARN: [device.model] delay = 0 s is below", 0), 0u)
        << r.verdict().text;
    r.configured_delay_s = 0.00116;  // within 0.05 period of the p99: covered
    EXPECT_TRUE(r.verdict().ok()) << r.verdict().text;
    r.configured_delay_s = 0.0;

    r.clock_backwards = 1;
    EXPECT_NE(r.verdict().text.find("(0 bad acknowledgements, 1 sample with the device clock"),
              std::string::npos)
        << r.verdict().text;

    r.lost = 6;  // 0.06 % + 0.05 % > 0.1 %
    r.late = 5;
    EXPECT_EQ(r.verdict().text, "WARN: more than 0.1 % of exchanges lost or late");
    r.late = 4;  // exactly 0.1 %: not more
    EXPECT_NE(r.verdict().text.find("contradict themselves"), std::string::npos);
    r.late = 5;

    r.rtt_p99_us = 301.0;  // over 30 % of the 1000 us period
    EXPECT_EQ(r.verdict().text.rfind("WARN: p99 round trip 301 us is over 30 % of the 1000 us", 0),
              0u)
        << r.verdict().text;

    r.replies = 0;
    EXPECT_EQ(r.verdict().level, Level::fail);
    EXPECT_EQ(r.verdict().text, "FAIL: the device never answered");

    // The text report's last line and the JSON carry the same verdict.
    const std::string text = diag_text(r);
    EXPECT_NE(text.find("\nverdict: FAIL: the device never answered\n"), std::string::npos);
    const nlohmann::json j = nlohmann::json::parse(diag_json(r));
    EXPECT_FALSE(j.at("verdict").at("ok").get<bool>());
    EXPECT_EQ(j.at("verdict").at("text"), "FAIL: the device never answered");
}

TEST(DaemonLinkDiag, RefusesADurationOutOfRange) {
    try {
        (void)diagnose(sim_config(""), 0.0, true);
        FAIL();
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find(
                      "--duration = 0 is out of range: allowed > 0 and <= 3600 (s)"),
                  std::string::npos)
            << e.what();
    }
}

}  // namespace
}  // namespace hapticd::daemon
