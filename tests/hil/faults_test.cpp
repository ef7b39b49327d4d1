// HilFaults: the sim plugin's fault injection, end to end through the daemon (DESIGN.md
// "Safety model": a fault zeroes force in the same tick and is latched; hapticd stops on it
// with exit 1). The handle is pressed into the wall by a stiff grasp, so that the force
// before the fault is well away from zero and the zero after it means something.
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
constexpr std::uint32_t kFaultEncoderJump = 1u << 2;

DaemonRun run_with_faults(const ScratchDir& dir, const std::string& faults) {
    DaemonConfig config;
    config.coupling = coupling_table(size_coupling("encoder"), "encoder");
    config.initial_position = "-0.001";
    config.humans = human_table(stiff_grasp(push_toml(0.005, 0.8, 0.2, 100.0)));
    config.faults = faults;
    return run_hapticd(dir, {.config_toml = config.toml(),
                             .scene_toml = wall_contact_scene(1e5),
                             .duration_s = kDurationS});
}

std::uint32_t faults_at(const TelemetryLog& log, std::size_t row) {
    return static_cast<std::uint32_t>(log.column("faults")[row]);
}

TEST(HilFaults, DisconnectStopsTheRunWithZeroForce) {
    const ScratchDir dir;
    const DaemonRun run = run_with_faults(dir, "disconnect_at = " + toml_number(kFaultAtS) + "\n");
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

}  // namespace
}  // namespace hapticd::testing
