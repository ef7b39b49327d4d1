// Link diagnostics (daemon/link_diag.hpp) against the sim plugin, whose faults are scripted:
// every count the report gives is checked against the faults that were injected.
#include "hapticd/daemon/link_diag.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace hapticd::daemon {
namespace {

Config sim_config(const std::string& faults) {
    return parse_config(R"(
[servo]
rate_hz = 1000
realtime = "off"
[device]
plugin = "sim"
[device.model]
mass = 0.1
damping = 2.0
[device.sim]
mass = 0.1
damping = 2.0
)" + faults + R"(
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
    if (r.rtt_p99_us < 300.0) {
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
}

TEST(DaemonLinkDiag, RefusesADurationOutOfRange) {
    try {
        (void)diagnose(sim_config(""), 0.0, true);
        FAIL();
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("--duration 0 is not allowed"), std::string::npos);
    }
}

}  // namespace
}  // namespace hapticd::daemon
