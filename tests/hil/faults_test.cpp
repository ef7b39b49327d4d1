// HilFaults: the sim plugin's fault injection, end to end through the daemon
// (docs/architecture.md §7.1, §7.8: a fault zeroes force in the same tick and is latched;
// hapticd stops on it with exit 1, except a link fault with [safety] reconnect, which clears by
// itself once the device has answered again for reconnect_settle, or ends the run
// reconnect_timeout after the fault). The handle is pressed into the wall by a stiff grasp, so
// that the force before the fault is well away from zero and the zero after it means something.
#include "hapticd/servo/faults.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>

#include "hapticd_run.hpp"
#include "operators.hpp"
#include "pen_display.hpp"
#include "tuned_gains.hpp"
#include "wall_contact.hpp"

namespace hapticd::testing {
namespace {

constexpr double kDurationS = 4.0;
constexpr double kFaultAtS = 1.5;                    ///< lockstep: hits sample 1500
constexpr std::uint32_t kFaultDeviceLost = 1u << 0;  // servo/faults.hpp
constexpr std::uint32_t kFaultReadTimeout = 1u << 1;
constexpr std::uint32_t kFaultEncoderJump = 1u << 2;
constexpr std::uint32_t kFaultEncoderStale = 1u << 8;
constexpr std::uint32_t kFlagNoSample = 1u << 6;  // servo/telemetry.hpp
constexpr std::uint32_t kFlagSoftStart = 1u << 3;
constexpr std::uint32_t kFlagLinkRecovered = 1u << 8;

/// `safety`: extra [safety] keys, e.g. "reconnect = false\n".
DaemonRun run_with_faults(const ScratchDir& dir, const std::string& faults,
                          const std::string& safety = "") {
    DaemonConfig config;
    config.coupling = coupling_table(size_coupling("encoder"), "encoder");
    config.initial_position = "-0.001";
    config.humans = human_table(stiff_grasp(push_toml(0.005, 0.8, 0.2, 100.0)));
    config.faults = faults;
    std::string toml = config.toml();
    toml.insert(toml.find("[safety]\n") + 9, safety);
    return run_hapticd(
        dir,
        {.config_toml = toml, .scene_toml = wall_contact_scene(1e5), .duration_s = kDurationS});
}

std::uint32_t faults_at(const TelemetryLog& log, std::size_t row) {
    return static_cast<std::uint32_t>(log.column("faults")[row]);
}

std::uint32_t flags_at(const TelemetryLog& log, std::size_t row) {
    return static_cast<std::uint32_t>(log.column("tick_flags")[row]);
}

TEST(HilFaults, DisconnectStopsTheRunWithZeroForce) {
    const ScratchDir dir;
    const DaemonRun run = run_with_faults(dir, "disconnect_at = " + toml_number(kFaultAtS) + "\n",
                                          "reconnect = false\n");
    EXPECT_EQ(run.exit_code, 1) << run.err;
    EXPECT_EQ(run.summary.at("exit"), "fault");
    EXPECT_EQ(fault_list(run), servo::fault_name(kFaultDeviceLost));
    // Stopped at the fault, long before the end of --duration.
    const auto ticks = run.summary.at("ticks").get<std::size_t>();
    EXPECT_EQ(ticks, static_cast<std::size_t>(kFaultAtS * kRateHz) + 1);
    ASSERT_EQ(run.log.rows(), ticks);
    const std::size_t last = run.log.rows() - 1;
    const auto& f = run.log.column("f0_n");
    EXPECT_EQ(f[last], 0.0);
    EXPECT_EQ(faults_at(run.log, last), std::uint32_t{kFaultDeviceLost});
    EXPECT_GT(std::abs(f[last - 1]), 1.0);  // pressing into the wall until then
    EXPECT_EQ(faults_at(run.log, last - 1), 0u);
}

// The sim's disconnect never comes back. With reconnect (the default) the loop goes on at
// zero force, waiting for the device, and gives up reconnect_timeout after the fault.
TEST(HilFaults, ADeviceThatNeverReturnsEndsTheRunAfterTheReconnectTimeout) {
    constexpr double kTimeoutS = 1.0;
    const ScratchDir dir;
    const DaemonRun run = run_with_faults(dir, "disconnect_at = " + toml_number(kFaultAtS) + "\n",
                                          "reconnect_timeout = " + toml_number(kTimeoutS) + "\n");
    EXPECT_EQ(run.exit_code, 1) << run.err;
    EXPECT_EQ(run.summary.at("exit"), "fault");
    EXPECT_EQ(fault_list(run), servo::fault_name(kFaultDeviceLost));
    EXPECT_EQ(run.summary.at("link_recoveries"), 0);
    const auto fault_row = static_cast<std::size_t>(kFaultAtS * kRateHz);
    const auto ticks = run.summary.at("ticks").get<std::size_t>();
    EXPECT_EQ(ticks, fault_row + static_cast<std::size_t>(kTimeoutS * kRateHz));
    ASSERT_EQ(run.log.rows(), ticks);
    const auto& f = run.log.column("f0_n");
    EXPECT_GT(std::abs(f[fault_row - 1]), 1.0);  // pressing into the wall until then
    EXPECT_EQ(faults_at(run.log, fault_row - 1), 0u);
    for (std::size_t i = fault_row; i < run.log.rows(); ++i) {  // zero from the fault on
        ASSERT_EQ(f[i], 0.0) << i;
        ASSERT_EQ(faults_at(run.log, i), std::uint32_t{kFaultDeviceLost}) << i;
    }
    EXPECT_NE(run.err.find("did not come back within [safety] reconnect_timeout = 1 s"),
              std::string::npos)
        << run.err;
}

// Dropped replies (what corrupted or missing frames look like to the loop) latch
// read_timeout and zero the force in that tick; once the sim answers again, the latch clears
// exactly reconnect_settle (0.5 s) later, and the force comes back only through the soft
// start (a still handle, then the ramp): the run goes on to its end with exit 0.
TEST(HilFaults, DroppedRepliesLatchThenRecoverThroughTheSoftStart) {
    constexpr std::size_t kSettleRows = 500;  // [safety] reconnect_settle = 0.5 s (default)
    const ScratchDir dir;
    const DaemonRun run = run_with_faults(dir, "drop_at = [1.5, 1.501, 1.502, 1.503]\n");
    EXPECT_EQ(run.exit_code, 0) << run.err;
    EXPECT_EQ(run.summary.at("exit"), "duration");
    EXPECT_EQ(fault_list(run), servo::fault_name(kFaultReadTimeout));
    EXPECT_EQ(run.summary.at("link_recoveries"), 1);
    ASSERT_EQ(run.log.rows(), static_cast<std::size_t>(kDurationS * kRateHz));
    const auto& f = run.log.column("f0_n");

    std::size_t faulted = 0;  // the tick that latched read_timeout
    while (faulted < run.log.rows() && faults_at(run.log, faulted) == 0u) ++faulted;
    ASSERT_LT(faulted, run.log.rows());
    EXPECT_EQ(faults_at(run.log, faulted), std::uint32_t{kFaultReadTimeout});
    EXPECT_EQ(f[faulted], 0.0);
    EXPECT_GT(std::abs(f[faulted - 3]), 1.0);  // before the drops (the device held it: ZOH)

    std::size_t back = faulted;  // the first sample after the drops
    while (back < run.log.rows() && (flags_at(run.log, back) & kFlagNoSample) != 0u) ++back;
    ASSERT_LT(back + kSettleRows, run.log.rows());
    for (std::size_t i = faulted; i < back + kSettleRows; ++i) {
        ASSERT_EQ(f[i], 0.0) << i;
        ASSERT_EQ(faults_at(run.log, i), std::uint32_t{kFaultReadTimeout}) << i;
    }
    EXPECT_NE(flags_at(run.log, back + kSettleRows - 1) & kFlagLinkRecovered, 0u);
    EXPECT_EQ(faults_at(run.log, back + kSettleRows), 0u);

    // After the recovery: zero force for at least the soft start's still time (0.2 s), then
    // the ramp (flagged), and contact again by the end of the run.
    const std::size_t recovered = back + kSettleRows;
    std::size_t first_force = recovered;
    while (first_force < run.log.rows() && f[first_force] == 0.0) ++first_force;
    ASSERT_LT(first_force, run.log.rows());
    EXPECT_GE(first_force - recovered, 200u);
    EXPECT_NE(flags_at(run.log, first_force) & kFlagSoftStart, 0u);
    for (std::size_t i = recovered; i < run.log.rows(); ++i) {
        ASSERT_EQ(faults_at(run.log, i), 0u) << i;
    }
    EXPECT_GT(std::abs(f[run.log.rows() - 1]), 1.0);
}

TEST(HilFaults, EncoderJumpLatchesAndZeroesForceInTheSameTick) {
    constexpr std::int64_t kJumpCounts = 1000;  // 10 mm in one tick: 10 m/s, not a hand
    const ScratchDir dir;
    const DaemonRun run =
        run_with_faults(dir, "jump_at = " + toml_number(kFaultAtS) +
                                 "\njump_counts = " + std::to_string(kJumpCounts) + "\n");
    EXPECT_EQ(run.exit_code, 1) << run.err;
    EXPECT_EQ(run.summary.at("exit"), "fault");
    EXPECT_EQ(fault_list(run), servo::fault_name(kFaultEncoderJump));
    ASSERT_GT(run.log.rows(), 2u);

    // The first faulted row is the tick that read the jump: its force is already zero.
    std::size_t faulted = 0;
    while (faulted < run.log.rows() && faults_at(run.log, faulted) == 0u) ++faulted;
    ASSERT_LT(faulted, run.log.rows());
    ASSERT_GT(faulted, 0u);
    const auto& x = run.log.column("x0_m");
    const auto& f = run.log.column("f0_n");
    EXPECT_EQ(faults_at(run.log, faulted), std::uint32_t{kFaultEncoderJump});
    EXPECT_EQ(run.log.column("tick")[faulted], kFaultAtS * kRateHz);
    EXPECT_NEAR((x[faulted] - x[faulted - 1]) / kCountM, static_cast<double>(kJumpCounts), 2.0);
    EXPECT_EQ(f[faulted], 0.0);
    EXPECT_GT(std::abs(f[faulted - 1]), 1.0);
    // Latched: every row after it (if the loop logged any) keeps the fault and zero force.
    for (std::size_t i = faulted; i < run.log.rows(); ++i) {
        EXPECT_NE(faults_at(run.log, i) & kFaultEncoderJump, 0u);
        EXPECT_EQ(f[i], 0.0);
    }
}

// docs/architecture.md §7.1: a stale sample latches encoder_stale and zeroes the force in the
// tick that read it (with stale_at = 0.75 the status bit was once ignored, the held force
// moved the handle 31 mm and the summary said "faults: none").
TEST(HilFaults, StaleEncoderLatchesAndZeroesForceInTheSameTick) {
    constexpr std::uint32_t kStatusStale = 1u << 1;  // servo/io.hpp
    const ScratchDir dir;
    const DaemonRun run = run_with_faults(dir, "stale_at = " + toml_number(kFaultAtS) + "\n");
    EXPECT_EQ(run.exit_code, 1) << run.err;
    EXPECT_EQ(run.summary.at("exit"), "fault");
    EXPECT_EQ(fault_list(run), servo::fault_name(kFaultEncoderStale));
    std::size_t faulted = 0;
    while (faulted < run.log.rows() && faults_at(run.log, faulted) == 0u) ++faulted;
    ASSERT_LT(faulted, run.log.rows());
    ASSERT_GT(faulted, 0u);
    const auto& f = run.log.column("f0_n");
    const auto& x = run.log.column("x0_m");
    EXPECT_EQ(run.log.column("tick")[faulted], kFaultAtS * kRateHz);
    EXPECT_NE(static_cast<std::uint32_t>(run.log.column("status")[faulted]) & kStatusStale, 0u);
    EXPECT_EQ(f[faulted], 0.0);
    EXPECT_GT(std::abs(f[faulted - 1]), 1.0);
    // The run ends there: the handle has not been pushed anywhere by a held force.
    EXPECT_NEAR(x.back(), x[faulted - 1], 1e-4);
}

}  // namespace
}  // namespace hapticd::testing
