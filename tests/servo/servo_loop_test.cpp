// The servo tick and loop against a fake device and small environments, on virtual time.
#include "hapticd/servo/servo_loop.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <ostream>
#include <string>
#include <thread>

#include "servo_fakes.hpp"

namespace hapticd::servo {
namespace {

using fakes::FakeClock;
using fakes::FakeDevice;
using fakes::PlaneWall;
using fakes::VirtualTime;

constexpr double kCountsPerMeter = 1e6;  // 1 um per count

ServoConfig test_config() {
    ServoConfig config;
    config.rate_hz = 1000.0;
    config.axes = 1;
    config.counts_per_meter = kCountsPerMeter;
    config.coupling = {.stiffness_n_per_m = 2000.0, .damping_n_s_per_m = 0.0};
    config.safety.max_force_n = 10.0;
    config.safety.soft_start = {.still_speed_mps = 1.0, .still_time_s = 0.0, .ramp_time_s = 0.0};
    config.safety.passivity.mode = PassivityMode::observe;
    config.realtime.mode = RealtimeMode::off;
    config.link_recovery.enabled = false;  // a lost device ends the run
    return config;
}

template <typename Environment>
using TestLoop = ServoLoop<FakeDevice, Environment, FakeClock>;

TEST(ServoLoop, WallTickCommandsTheSeriesSpringForce) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(-2000);  // 2 mm inside the wall
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    TelemetryRing ring(16);
    TestLoop<PlaneWall> loop(device, wall, test_config(), &ring, FakeClock{&time});

    const TelemetryRecord& record = loop.tick();
    // k_c k_w / (k_c + k_w) = 1500 N/m, 2 mm: 3 N out of the wall (+x).
    EXPECT_NEAR(device.last_command.force_n[0], 3.0, 1e-12);
    EXPECT_TRUE(device.last_command.enable);
    EXPECT_EQ(device.last_command.force_n[1], 0.0);
    EXPECT_EQ(wall.resets, 1);
    EXPECT_EQ(wall.commits, 1);
    EXPECT_EQ(record.tick, 0u);
    EXPECT_DOUBLE_EQ(record.x_m[0], -0.002);
    EXPECT_NEAR(record.xe_m[0], -0.0005, 1e-15);
    EXPECT_NEAR(record.f_n[0], 3.0, 1e-12);

    TelemetryRecord popped;
    ASSERT_TRUE(ring.try_pop(popped));
    EXPECT_EQ(popped.tick, 0u);
    EXPECT_NEAR(popped.f_n[0], 3.0, 1e-12);
    EXPECT_EQ(loop.inbox().status().tick, 0u);
    EXPECT_NEAR(loop.inbox().status().f_n[0], 3.0, 1e-12);
}

TEST(ServoLoop, VelocityIsTheBackwardDifference) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(10'000);  // free space, 1 cm out
    device.counts_per_read[0] = 50;      // 50 um per 1 ms tick = 0.05 m/s
    PlaneWall wall{.wall_m = 0.0};
    TestLoop<PlaneWall> loop(device, wall, test_config(), nullptr, FakeClock{&time});
    EXPECT_EQ(loop.tick().v_mps[0], 0.0);  // the first tick has no previous sample
    for (int n = 0; n < 5; ++n) EXPECT_NEAR(loop.tick().v_mps[0], 0.05, 1e-12);
}

TEST(ServoLoop, NonFiniteEnvironmentZeroesForceInTheSameTick) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(1000);
    fakes::NanAfter environment{.after_evaluations = 3};
    ServoConfig config = test_config();
    config.stop_on_fault = false;
    TestLoop<fakes::NanAfter> loop(device, environment, config, nullptr, FakeClock{&time});

    // Free space converges in one evaluation per tick: ticks 0-2 are fine, tick 3 sees NaN.
    for (int n = 0; n < 3; ++n) {
        loop.tick();
        EXPECT_TRUE(device.last_command.enable) << n;
    }
    const std::int64_t writes_before = device.writes;
    const TelemetryRecord& record = loop.tick();
    EXPECT_EQ(device.writes, writes_before + 1);  // this tick wrote...
    EXPECT_FALSE(device.last_command.enable);     // ...a disabled zero command
    EXPECT_EQ(device.last_command.force_n[0], 0.0);
    EXPECT_EQ(record.faults, kFaultNonFinite);
    EXPECT_EQ(record.f_n[0], 0.0);
    EXPECT_EQ(loop.faults(), kFaultNonFinite);
    // Latched.
    environment.after_evaluations = 1'000'000;
    loop.tick();
    EXPECT_FALSE(device.last_command.enable);
    // Reset from another thread takes effect at the next tick.
    std::thread([&] { loop.inbox().request_fault_reset(); }).join();
    loop.tick();
    EXPECT_EQ(loop.faults(), 0u);
    EXPECT_TRUE(device.last_command.enable);
    ASSERT_EQ(loop.summary().faults.size(), 1u);
    EXPECT_EQ(loop.summary().faults[0], "non_finite");
}

// A sample the device flags as bad faults in the tick that reads it: its fault latches and the
// force is zero in that tick, and stays zero after a good sample until a reset. An encoder
// jump (kStatusJump) and, docs/architecture.md §7.1, a stale sample (the counts repeat the
// last good ones: ignored, it once let the held force move the handle 31 mm).
struct BadSample {
    const char* name;
    std::uint32_t status;  ///< what the device reports
    std::uint32_t fault;   ///< what the loop latches
    const char* fault_name;
};

void PrintTo(const BadSample& bad, std::ostream* os) { *os << bad.name; }

class ServoLoopBadSample : public ::testing::TestWithParam<BadSample> {};

TEST_P(ServoLoopBadSample, FaultsInTheSameTick) {
    const BadSample& bad = GetParam();
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(-2000);
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    TestLoop<PlaneWall> loop(device, wall, test_config(), nullptr, FakeClock{&time});
    loop.tick();
    ASSERT_GT(device.last_command.force_n[0], 2.9);
    device.next.status = bad.status;
    loop.tick();
    EXPECT_FALSE(device.last_command.enable);
    EXPECT_EQ(device.last_command.force_n[0], 0.0);
    EXPECT_EQ(loop.faults(), bad.fault);
    ASSERT_EQ(loop.summary().faults.size(), 1u);
    EXPECT_EQ(loop.summary().faults[0], bad.fault_name);
    // Latched: a fresh sample does not bring the force back without a reset.
    device.next.status = 0;
    loop.tick();
    EXPECT_FALSE(device.last_command.enable);
}

INSTANTIATE_TEST_SUITE_P(
    ServoLoop, ServoLoopBadSample,
    ::testing::Values(BadSample{"EncoderJump", kStatusJump, kFaultEncoderJump, "encoder_jump"},
                      BadSample{"StaleSample", kStatusStale, kFaultEncoderStale, "encoder_stale"}),
    [](const auto& param_info) { return std::string(param_info.param.name); });

// docs/architecture.md §3.1, §7.6: a host stalled between its wake and the read (kill -STOP)
// once saw the handle's move over the stall as one period's and commanded max_force. The
// backward difference spans the time between the samples, from the device's clock.
TEST(ServoLoop, VelocitySpansTheDeviceClockAcrossAStall) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(10'000);  // free space
    device.counts_per_read[0] = 50;      // 50 um per read
    PlaneWall wall{.wall_m = 0.0};
    ServoConfig config = test_config();
    config.coupling.damping_n_s_per_m = 2.0;
    TestLoop<PlaneWall> loop(device, wall, config, nullptr, FakeClock{&time});
    loop.tick();
    EXPECT_NEAR(loop.tick().v_mps[0], 0.05, 1e-12);
    device.next.device_time_s += 0.054;  // 55 ms between this sample and the last
    const TelemetryRecord& after = loop.tick();
    EXPECT_NEAR(after.v_mps[0], 50e-6 / 0.055, 1e-12);
    EXPECT_EQ(after.flags & kFlagIntervalUnknown, 0u);
    EXPECT_NEAR(loop.tick().v_mps[0], 0.05, 1e-12);  // and one period again
    // Jitter within half a period is the nominal period.
    device.next.device_time_s += 0.0004;
    EXPECT_NEAR(loop.tick().v_mps[0], 0.05, 1e-12);
}

// A device that paces the loop (lockstep) numbers the samples it produced, not the periods
// between them. The protocol's reference device answers the poll after a lost reply one
// period after the last sample the host took, but two sequence numbers on; hung for four
// periods, it answers with the next sequence number. The serial fault campaign found both
// (seed 1: a reply held back behind the next answer gave half the velocity). The backward
// difference spans the device's clock.
TEST(ServoLoop, APacedDeviceDifferencesOverItsClockNotItsSampleCount) {
    VirtualTime time;
    FakeDevice device;  // no virtual time of its own: one period of its clock per read
    device.set_position_counts(10'000);  // free space
    device.counts_per_read[0] = 50;      // 50 um per read
    PlaneWall wall{.wall_m = 0.0};
    ServoConfig config = test_config();
    config.device_paces_loop = true;
    TestLoop<PlaneWall> loop(device, wall, config, nullptr, FakeClock{&time});
    loop.tick();
    EXPECT_NEAR(loop.tick().v_mps[0], 0.05, 1e-12);
    device.next.sequence += 1;  // a sample lost on the way, and its period with it ...
    EXPECT_NEAR(loop.tick().v_mps[0], 0.05, 1e-12);  // ... but 50 um in one period of its clock
    device.next.device_time_s += 0.004;              // hung for four periods: 50 um in five
    const TelemetryRecord& after = loop.tick();
    EXPECT_NEAR(after.v_mps[0], 50e-6 / 0.005, 1e-12);
    EXPECT_EQ(after.flags & kFlagIntervalUnknown, 0u);
    EXPECT_NEAR(loop.tick().v_mps[0], 0.05, 1e-12);
}

// A write that fails after a good read (the device unplugged between the two) latches the
// fault in that tick, and the tick's record holds zero force, like every record with a fault
// latched: the command the servo tried last, not the one that never arrived. The serial
// fault campaign found it (seed 24: -2.4 N recorded with device_lost latched).
TEST(ServoLoop, AFailedWriteRecordsTheZeroForceItTriedLast) {
    for (const IoResult failure : {IoResult::disconnected, IoResult::error}) {
        VirtualTime time;
        FakeDevice device;
        device.set_position_counts(-2000);  // 2 mm inside the wall
        PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
        TestLoop<PlaneWall> loop(device, wall, test_config(), nullptr, FakeClock{&time});
        for (int n = 0; n < 3; ++n) loop.tick();
        ASSERT_GT(device.last_command.force_n[0], 1.0);
        device.write_result = failure;
        const TelemetryRecord& record = loop.tick();
        EXPECT_NE(record.faults, 0u);
        EXPECT_EQ(record.f_n[0], 0.0);
        EXPECT_FALSE(device.last_command.enable);  // one more try, at zero force
        EXPECT_EQ(device.last_command.force_n[0], 0.0);
    }
}

// A device clock that stands still or runs backwards leaves the interval unknown: no
// velocity-based force in that tick (zero force), the history starts again there.
TEST(ServoLoop, UnknownIntervalZeroesTheForceAndRestartsTheHistory) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(-2000);  // 2 mm inside the wall
    device.counts_per_read[0] = -10;
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0, .damping_n_s_per_m = 5.0};
    ServoConfig config = test_config();
    config.coupling.damping_n_s_per_m = 2.0;
    TestLoop<PlaneWall> loop(device, wall, config, nullptr, FakeClock{&time});
    for (int n = 0; n < 3; ++n) loop.tick();
    ASSERT_GT(device.last_command.force_n[0], 2.9);
    device.next.device_time_s -= 0.005;  // the clock went backwards
    const TelemetryRecord& record = loop.tick();
    EXPECT_NE(record.flags & kFlagIntervalUnknown, 0u);
    EXPECT_EQ(record.v_mps[0], 0.0);
    EXPECT_EQ(device.last_command.force_n[0], 0.0);
    EXPECT_EQ(loop.faults(), 0u);
    EXPECT_EQ(loop.stats().intervals_unknown, 1u);
    EXPECT_EQ(wall.resets, 2);
    // The next sample differences against that one, over one period of its clock.
    EXPECT_NEAR(loop.tick().v_mps[0], -0.01, 1e-12);
    device.next.device_time_s = device.next.device_time_s - 0.001;  // stood still
    EXPECT_NE(loop.tick().flags & kFlagIntervalUnknown, 0u);
    EXPECT_EQ(loop.summary().intervals_unknown, 2u);
}

TEST(ServoLoop, ServoSideJumpCheckFaults) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(5000);
    PlaneWall wall{.wall_m = 0.0};
    ServoConfig config = test_config();
    config.safety.encoder_jump_m = 0.001;  // 1 mm per tick
    TestLoop<PlaneWall> loop(device, wall, config, nullptr, FakeClock{&time});
    loop.tick();
    device.set_position_counts(5900);  // 0.9 mm: allowed
    loop.tick();
    EXPECT_EQ(loop.faults(), 0u);
    device.set_position_counts(7000);  // 1.1 mm: a jump
    loop.tick();
    EXPECT_EQ(loop.faults(), kFaultEncoderJump);
    EXPECT_FALSE(device.last_command.enable);
}

TEST(ServoLoop, DisconnectEndsTheRunAtZeroForce) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(-2000);
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    ServoConfig config = test_config();
    config.stop_on_fault = false;  // a lost device ends the run anyway
    TestLoop<PlaneWall> loop(device, wall, config, nullptr, FakeClock{&time});
    loop.tick();
    device.read_result = IoResult::disconnected;
    const std::atomic<bool> stop{false};
    EXPECT_EQ(loop.run(stop, 100), RunExit::fault);
    EXPECT_EQ(loop.stats().ticks, 2u);
    EXPECT_EQ(loop.faults(), kFaultDeviceLost);
    EXPECT_FALSE(device.last_command.enable);
    EXPECT_EQ(device.last_command.force_n[0], 0.0);
}

TEST(ServoLoop, ReadTimeoutsAreToleratedUpToTheBudget) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(-2000);
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    ServoConfig config = test_config();
    config.safety.read_timeouts_allowed = 2;
    TestLoop<PlaneWall> loop(device, wall, config, nullptr, FakeClock{&time});
    loop.tick();
    device.read_result = IoResult::timeout;
    const std::int64_t writes = device.writes;
    loop.tick();
    loop.tick();
    EXPECT_EQ(loop.faults(), 0u);
    EXPECT_EQ(device.writes, writes);  // nothing written: the device holds its force
    EXPECT_TRUE(loop.last_record().flags & kFlagNoSample);
    // ...and the telemetry logs the force the device holds, not a zero it never received.
    EXPECT_EQ(loop.last_record().f_n[0], device.last_command.force_n[0]);
    EXPECT_NE(loop.last_record().f_n[0], 0.0);
    loop.tick();
    EXPECT_EQ(loop.faults(), kFaultReadTimeout);
    EXPECT_EQ(device.writes, writes + 1);
    EXPECT_FALSE(device.last_command.enable);
    EXPECT_EQ(loop.stats().read_timeouts, 3u);
}

TEST(ServoLoop, OverrunBudgetFaultsAndIsCounted) {
    VirtualTime time;
    FakeDevice device;
    device.time = &time;
    device.read_cost_ns = 3'000'000;  // every tick takes 3 periods
    device.set_position_counts(5000);
    PlaneWall wall{.wall_m = 0.0};
    ServoConfig config = test_config();
    config.overrun.max_consecutive_overruns = 3;
    TestLoop<PlaneWall> loop(device, wall, config, nullptr, FakeClock{&time});
    const std::atomic<bool> stop{false};
    EXPECT_EQ(loop.run(stop, 100), RunExit::fault);
    // Tick 0 is on time; ticks 1..4 overrun, each missing 2 periods; the 4th in a row faults.
    EXPECT_EQ(loop.stats().ticks, 5u);
    EXPECT_EQ(loop.stats().overruns, 4u);
    EXPECT_EQ(loop.stats().missed_periods, 8u);
    EXPECT_EQ(loop.faults(), kFaultOverrunBudget);
    EXPECT_FALSE(device.last_command.enable);
    // Time in the record follows the schedule: tick 4 belongs to period 12 (0, 3, 6, 9, 12).
    EXPECT_NEAR(loop.last_record().t_s, 0.012, 1e-12);
    EXPECT_EQ(loop.summary().overruns, 4u);
    // The summary names the overrun that broke the budget, beside the budget.
    ASSERT_TRUE(loop.summary().overrun_budget.has_value());
    const OverrunBudgetBreach breach = *loop.summary().overrun_budget;
    EXPECT_EQ(breach.consecutive_overruns, 4);
    EXPECT_EQ(breach.missed_periods, 2);
    EXPECT_EQ(breach.max_consecutive_overruns, 3);
    EXPECT_EQ(breach.max_missed_periods, 20);
    EXPECT_NEAR(breach.late_ms, 2.0, 1e-9);  // woke for period 12 at 12 ms + 2 missed
}

// One long stall (a host that stops the VM for 55 ms) is measured and named.
TEST(ServoLoop, OneLongStallBreaksTheMissedPeriodBudgetAndIsNamed) {
    VirtualTime time;
    FakeDevice device;
    device.time = &time;
    device.set_position_counts(5000);
    PlaneWall wall{.wall_m = 0.0};
    ServoConfig config = test_config();
    config.overrun.max_missed_periods = 20;
    TelemetryRing ring(16);
    TestLoop<PlaneWall> loop(device, wall, config, &ring, FakeClock{&time});
    device.counts_per_read[0] = 10;
    device.stall_at_read = 3;  // between the wake of tick 3 and its read
    device.stall_ns = 55'300'000;
    const std::atomic<bool> stop{false};
    EXPECT_EQ(loop.run(stop, 10), RunExit::fault);
    EXPECT_EQ(loop.stats().ticks, 5u);  // tick 4 (due at 4 ms) woke at 58.3 ms
    EXPECT_EQ(loop.faults(), kFaultOverrunBudget);
    TelemetryRecord record;
    for (int n = 0; n < 4; ++n) ASSERT_TRUE(ring.try_pop(record));
    // Tick 3 read 56.3 ms after tick 2: 10 um over 56 periods, not over one.
    EXPECT_EQ(record.tick, 3u);
    EXPECT_NEAR(record.v_mps[0], 10e-6 / 0.056, 1e-12);
    ASSERT_TRUE(loop.summary().overrun_budget.has_value());
    const OverrunBudgetBreach breach = *loop.summary().overrun_budget;
    EXPECT_EQ(breach.missed_periods, 54);
    EXPECT_NEAR(breach.late_ms, 54.3, 1e-9);
    EXPECT_EQ(breach.consecutive_overruns, 1);
    EXPECT_EQ(describe(breach).substr(0, 45), "woke 54.3 ms late (54 periods missed, 1 overr");
    EXPECT_NE(describe(breach).find("the budget is 20 periods in one overrun ([safety] "
                                    "max_missed_periods)"),
              std::string::npos);
}

TEST(ServoLoop, RunStopsOnTickLimitWithStatsAndZeroForce) {
    VirtualTime time{.wake_latency_ns = 12'000};
    FakeDevice device;
    device.time = &time;
    device.read_cost_ns = 400;
    device.set_position_counts(-2000);
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    TelemetryRing ring(1024);
    TestLoop<PlaneWall> loop(device, wall, test_config(), &ring, FakeClock{&time});
    const std::atomic<bool> stop{false};
    EXPECT_EQ(loop.run(stop, 500), RunExit::tick_limit);
    EXPECT_FALSE(device.last_command.enable);  // zero force on exit
    const Summary summary = loop.summary();
    EXPECT_EQ(summary.ticks, 500u);
    EXPECT_EQ(summary.overruns, 0u);
    EXPECT_EQ(summary.rate_hz, 1000.0);
    EXPECT_NEAR(summary.wake_latency_us.p50, 12.0, 12.0 / 64.0);
    EXPECT_NEAR(summary.wake_latency_us.max, 12.0, 1e-9);
    EXPECT_NEAR(summary.tick_compute_us.p50, 0.4, 0.01);
    EXPECT_NEAR(summary.max_force_n, 3.0, 1e-9);
    EXPECT_TRUE(summary.faults.empty());
    EXPECT_EQ(summary.telemetry_dropped, 0u);
    EXPECT_EQ(ring.size(), 500u);
    // Virtual time advanced by 500 periods plus latency: the loop really paced itself.
    EXPECT_GE(time.now_ns, 500 * 1'000'000);
}

TEST(ServoLoop, StopFlagEndsTheRun) {
    VirtualTime time;
    FakeDevice device;
    PlaneWall wall;
    TestLoop<PlaneWall> loop(device, wall, test_config(), nullptr, FakeClock{&time});
    const std::atomic<bool> stop{true};
    EXPECT_EQ(loop.run(stop), RunExit::stopped);
    EXPECT_EQ(loop.stats().ticks, 0u);
    EXPECT_EQ(device.writes, 1);  // the zero command on exit
}

TEST(ServoLoop, DestructorWritesZeroForce) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(-2000);
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    {
        TestLoop<PlaneWall> loop(device, wall, test_config(), nullptr, FakeClock{&time});
        loop.tick();
        ASSERT_TRUE(device.last_command.enable);
    }
    EXPECT_FALSE(device.last_command.enable);
    EXPECT_EQ(device.last_command.force_n[0], 0.0);
}

TEST(ServoLoop, DisarmZeroesAndArmSoftStartsAgain) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(-2000);
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    ServoConfig config = test_config();
    config.safety.soft_start = {
        .still_speed_mps = 0.01, .still_time_s = 0.002, .ramp_time_s = 0.002};
    TestLoop<PlaneWall> loop(device, wall, config, nullptr, FakeClock{&time});
    for (int n = 0; n < 5; ++n) loop.tick();
    EXPECT_NEAR(device.last_command.force_n[0], 3.0, 1e-12);
    loop.inbox().disarm();
    loop.tick();
    EXPECT_FALSE(device.last_command.enable);
    EXPECT_TRUE(loop.last_record().flags & kFlagDisarmed);
    loop.inbox().arm();
    loop.tick();  // still for 1 ms: zero
    EXPECT_EQ(device.last_command.force_n[0], 0.0);
    loop.tick();  // still for 2 ms: the ramp starts next tick
    loop.tick();
    EXPECT_NEAR(device.last_command.force_n[0], 1.5, 1e-12);
    EXPECT_TRUE(loop.last_record().flags & kFlagSoftStart);
    loop.tick();
    EXPECT_NEAR(device.last_command.force_n[0], 3.0, 1e-12);
}

// scene_load's path through the loop: an offered environment is taken at the start of the
// next tick, reset where the handle is, and rendered through the soft start; the one it
// replaced is not touched again. A second offer waits for the first; a withdrawn one is
// never taken.
TEST(ServoLoop, AnOfferedEnvironmentIsTakenAtATicksStartThroughTheSoftStart) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(-2000);  // 2 mm inside the first wall, 4 mm inside the second
    PlaneWall first{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    PlaneWall second{.wall_m = 0.002, .stiffness_n_per_m = 6000.0};
    ServoConfig config = test_config();
    config.safety.soft_start = {
        .still_speed_mps = 0.01, .still_time_s = 0.002, .ramp_time_s = 0.002};
    TestLoop<PlaneWall> loop(device, first, config, nullptr, FakeClock{&time});
    for (int n = 0; n < 5; ++n) loop.tick();
    EXPECT_NEAR(device.last_command.force_n[0], 3.0, 1e-12);  // 1500 N/m in series, 2 mm
    const int first_commits = first.commits;
    const int first_resets = first.resets;

    ASSERT_TRUE(loop.inbox().offer_environment(second));
    EXPECT_FALSE(loop.inbox().offer_taken());
    EXPECT_FALSE(loop.inbox().offer_environment(first)) << "a second offer while one waits";
    loop.tick();  // taken: the soft start begins again, still for 1 ms
    EXPECT_TRUE(loop.inbox().offer_taken());
    EXPECT_FALSE(loop.inbox().withdraw_environment(second)) << "taken already";
    EXPECT_EQ(second.resets, 1);
    EXPECT_EQ(device.last_command.force_n[0], 0.0);
    EXPECT_EQ(loop.inbox().status().state, ServoState::arming);
    loop.tick();
    loop.tick();  // half the ramp: half of 1500 N/m x 4 mm
    EXPECT_NEAR(device.last_command.force_n[0], 3.0, 1e-12);
    loop.tick();
    EXPECT_NEAR(device.last_command.force_n[0], 6.0, 1e-12);
    EXPECT_EQ(loop.inbox().status().state, ServoState::running);
    EXPECT_EQ(first.commits, first_commits) << "the replaced environment was rendered again";
    EXPECT_EQ(first.resets, first_resets);

    ASSERT_TRUE(loop.inbox().offer_environment(first));
    EXPECT_TRUE(loop.inbox().withdraw_environment(first));
    EXPECT_TRUE(loop.inbox().offer_taken());
    for (int n = 0; n < 3; ++n) loop.tick();
    EXPECT_EQ(first.commits, first_commits) << "a withdrawn offer was taken";
    EXPECT_NEAR(device.last_command.force_n[0], 6.0, 1e-12) << "the soft start restarted";
}

// An open-loop source (the control socket's identify): a constant force for `ticks` commits.
struct ConstantForceSource final : OpenLoopSource {
    double force_n = 2.0;
    int ticks = 5;
    int commits = 0;
    int resets = 0;
    PenaltyForce evaluate(const Vec3& /*x*/, const Vec3& /*v*/) const noexcept override {
        PenaltyForce out;
        out.force_n.x = commits < ticks ? force_n : 0.0;
        return out;
    }
    void commit(const Vec3& /*x*/, const Vec3& /*v*/) noexcept override { ++commits; }
    void reset(const Vec3& /*x*/) noexcept override { ++resets; }
    bool done() const noexcept override { return commits >= ticks; }
};

// identify's path through the loop: play_open_loop arms a disarmed loop, and the tick that
// takes the source hands its force straight to the handle: no soft start (the scene's takes
// 2 ms), no passivity controller although the source is active and the mode is control; the
// environment is not touched and an offer waits. The tick after the source is done lets it
// go, disarmed; arming again renders the environment through the soft start.
TEST(ServoLoop, AnOpenLoopSourcePlaysStraightToTheHandleAndIsLetGoDisarmed) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(-2000);  // 2 mm inside the wall
    device.counts_per_read[0] = 10;     // 0.01 m/s, the way the source pushes
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    PlaneWall next_wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    ServoConfig config = test_config();
    config.arm_at_start = false;
    config.safety.soft_start = {
        .still_speed_mps = 1.0, .still_time_s = 0.002, .ramp_time_s = 0.002};
    config.safety.passivity.mode = PassivityMode::control;
    TestLoop<PlaneWall> loop(device, wall, config, nullptr, FakeClock{&time});
    for (int n = 0; n < 3; ++n) loop.tick();
    EXPECT_EQ(loop.inbox().status().state, ServoState::disabled);
    const int wall_commits = wall.commits;
    const int wall_resets = wall.resets;

    ConstantForceSource source;
    ConstantForceSource other;
    ASSERT_TRUE(loop.inbox().play_open_loop(source));
    EXPECT_FALSE(loop.inbox().play_open_loop(other)) << "a second source while one is offered";
    EXPECT_FALSE(loop.inbox().open_loop_idle());
    for (int n = 0; n < source.ticks; ++n) {
        const TelemetryRecord& record = loop.tick();
        EXPECT_EQ(device.last_command.force_n[0], 2.0) << n;
        EXPECT_TRUE(device.last_command.enable);
        EXPECT_NE(record.flags & kFlagOpenLoop, 0u) << n;
        EXPECT_EQ(record.flags & (kFlagSoftStart | kFlagPassivityControl), 0u) << n;
        EXPECT_EQ(record.xe_m[0], record.x_m[0]) << "no coupling: the tool is the handle";
        EXPECT_EQ(loop.inbox().status().state, ServoState::running);
        if (n == 1) {
            ASSERT_TRUE(loop.inbox().offer_environment(next_wall));
        }
    }
    EXPECT_EQ(source.resets, 1);
    EXPECT_EQ(source.commits, source.ticks);
    EXPECT_LT(loop.inbox().status().energy_j, 0.0) << "the source did work on the handle";
    EXPECT_EQ(wall.commits, wall_commits);
    EXPECT_EQ(wall.resets, wall_resets);
    EXPECT_FALSE(loop.inbox().offer_taken()) << "an offer waits while the source plays";
    EXPECT_FALSE(loop.inbox().open_loop_idle());

    const TelemetryRecord& after = loop.tick();  // done: let go
    EXPECT_TRUE(loop.inbox().open_loop_idle());
    EXPECT_EQ(after.flags & kFlagOpenLoop, 0u);
    EXPECT_NE(after.flags & kFlagDisarmed, 0u);
    EXPECT_EQ(device.last_command.force_n[0], 0.0);
    EXPECT_FALSE(device.last_command.enable);
    EXPECT_EQ(loop.inbox().status().state, ServoState::disabled);
    EXPECT_EQ(loop.inbox().status().energy_j, 0.0) << "the observer counts from zero again";
    EXPECT_TRUE(loop.inbox().offer_taken());
    EXPECT_EQ(next_wall.resets, 1) << "taken where the handle is";
    EXPECT_EQ(source.commits, source.ticks) << "played after it was done";

    loop.inbox().arm();
    loop.tick();
    EXPECT_EQ(loop.inbox().status().state, ServoState::arming);
    EXPECT_EQ(next_wall.resets, 2) << "arming restarts it where the handle is";
    EXPECT_EQ(device.last_command.force_n[0], 0.0) << "the soft start waits for a still handle";
    ASSERT_TRUE(loop.inbox().play_open_loop(other)) << "the loop takes a new source once idle";
}

// A disarm ends a source before it is done, and so does a fault: the tick after lets it go,
// with zero force, and the loop stays disarmed after the fault is reset.
TEST(ServoLoop, ADisarmOrAFaultEndsAnOpenLoopSource) {
    VirtualTime time;
    FakeDevice device;
    PlaneWall wall{.wall_m = 0.0};
    ServoConfig config = test_config();
    config.arm_at_start = false;
    TestLoop<PlaneWall> loop(device, wall, config, nullptr, FakeClock{&time});
    ConstantForceSource source;
    source.ticks = 100;
    ASSERT_TRUE(loop.inbox().play_open_loop(source));
    for (int n = 0; n < 3; ++n) loop.tick();
    EXPECT_EQ(device.last_command.force_n[0], 2.0);
    loop.inbox().disarm();
    loop.tick();
    EXPECT_TRUE(loop.inbox().open_loop_idle());
    EXPECT_EQ(device.last_command.force_n[0], 0.0);
    EXPECT_EQ(source.commits, 3);
    EXPECT_FALSE(source.done());

    ConstantForceSource faulted;
    faulted.ticks = 100;
    ASSERT_TRUE(loop.inbox().play_open_loop(faulted));
    loop.tick();
    EXPECT_EQ(device.last_command.force_n[0], 2.0);
    device.next.status |= kStatusDeviceFault;
    loop.tick();  // the fault zeroes the force in this tick
    EXPECT_EQ(device.last_command.force_n[0], 0.0);
    EXPECT_FALSE(device.last_command.enable);
    device.next.status &= ~kStatusDeviceFault;
    loop.tick();  // and the source is let go
    EXPECT_TRUE(loop.inbox().open_loop_idle());
    EXPECT_EQ(faulted.commits, 1);
    loop.inbox().request_fault_reset();
    loop.tick();
    EXPECT_EQ(loop.inbox().status().state, ServoState::disabled);
    EXPECT_EQ(device.last_command.force_n[0], 0.0);
}

// A disarm between the offer and the tick that would take it withdraws the source unplayed:
// a later arm renders the environment, and never plays the source on whoever then holds the
// handle.
TEST(ServoLoop, ADisarmBeforeTheFirstTickWithdrawsAnOpenLoopSource) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(-2000);
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    ServoConfig config = test_config();
    config.arm_at_start = false;
    TestLoop<PlaneWall> loop(device, wall, config, nullptr, FakeClock{&time});
    loop.tick();
    ConstantForceSource source;
    ASSERT_TRUE(loop.inbox().play_open_loop(source));
    loop.inbox().disarm();
    const TelemetryRecord& withdrawn = loop.tick();
    EXPECT_TRUE(loop.inbox().open_loop_idle());
    EXPECT_EQ(withdrawn.flags & kFlagOpenLoop, 0u);
    EXPECT_EQ(source.resets, 0);
    EXPECT_EQ(source.commits, 0);
    EXPECT_EQ(device.last_command.force_n[0], 0.0);
    loop.inbox().arm();
    for (int n = 0; n < 3; ++n) {
        const TelemetryRecord& record = loop.tick();
        EXPECT_EQ(record.flags & kFlagOpenLoop, 0u) << n;
    }
    EXPECT_EQ(source.commits, 0) << "an arm after the withdrawal does not play it";

    // An offer made after a disarm is played: the disarms before it do not withdraw it.
    loop.inbox().disarm();
    loop.tick();
    ConstantForceSource later;
    ASSERT_TRUE(loop.inbox().play_open_loop(later));
    loop.tick();
    EXPECT_EQ(later.commits, 1);
    EXPECT_EQ(device.last_command.force_n[0], 2.0);
}

TEST(ServoLoop, AdmittanceProxyGivesTheCouplingSpringForce) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(-2000);
    fakes::ProxyPlane proxy{.wall_m = 0.0};
    TestLoop<fakes::ProxyPlane> loop(device, proxy, test_config(), nullptr, FakeClock{&time});
    loop.tick();
    loop.tick();  // the tool has settled on the surface: v_e = 0
    // (22): the tool sits on the surface, x_e = 0; handle force -k_c (x_d - x_e) = 4 N.
    EXPECT_NEAR(device.last_command.force_n[0], 4.0, 1e-12);
    EXPECT_EQ(loop.last_record().xe_m[0], 0.0);
}

TEST(ServoLoop, WithoutCouplingTheWallActsOnTheDeviceDirectly) {
    // The conventional design: no coupling, so the handle gets the wall's own force,
    // k_w * 1 mm = 6 N, and the tool is the device: x_e = x_d.
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(-1000);
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    ServoConfig config = test_config();
    config.coupling_enabled = false;
    config.coupling = {};
    TestLoop<PlaneWall> loop(device, wall, config, nullptr, FakeClock{&time});
    loop.tick();
    EXPECT_NEAR(device.last_command.force_n[0], 6.0, 1e-12);
    EXPECT_EQ(loop.last_record().xe_m[0], loop.last_record().x_m[0]);
    EXPECT_EQ(wall.commits, 1);
}

TEST(ServoLoop, AdmittanceEnvironmentNeedsTheCoupling) {
    VirtualTime time;
    FakeDevice device;
    fakes::ProxyPlane proxy{.wall_m = 0.0};
    ServoConfig config = test_config();
    config.coupling_enabled = false;
    EXPECT_THROW((TestLoop<fakes::ProxyPlane>(device, proxy, config, nullptr, FakeClock{&time})),
                 std::invalid_argument);
}

TEST(ServoLoop, LockstepBackpressureLogsEveryTick) {
    // A lockstep device paces the loop; with backpressure the run waits for the consumer
    // between ticks, so a ring of 8 carries all 5000 records and nothing is dropped.
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(-2000);
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    ServoConfig config = test_config();
    config.device_paces_loop = true;
    config.telemetry_backpressure = true;
    TelemetryRing ring(8);
    TestLoop<PlaneWall> loop(device, wall, config, &ring, FakeClock{&time});
    std::atomic<bool> stop{false};
    std::uint64_t popped = 0;
    std::uint64_t next_tick = 0;
    bool in_order = true;
    std::thread consumer([&] {
        TelemetryRecord record;
        while (popped < 5000) {
            if (ring.try_pop(record)) {
                in_order = in_order && record.tick == next_tick;
                ++next_tick;
                ++popped;
            } else {
                std::this_thread::yield();
            }
        }
    });
    EXPECT_EQ(loop.run(stop, 5000), RunExit::tick_limit);
    consumer.join();
    EXPECT_EQ(popped, 5000u);
    EXPECT_TRUE(in_order);
    EXPECT_EQ(ring.dropped(), 0u);

    ServoConfig wall_clock = test_config();
    wall_clock.telemetry_backpressure = true;  // without a pacing device: refused
    EXPECT_THROW((TestLoop<PlaneWall>(device, wall, wall_clock, &ring, FakeClock{&time})),
                 std::invalid_argument);
}

TEST(ServoLoop, SaturationLimitsTheCommandedForce) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(-20'000);  // 2 cm deep: 30 N unsaturated
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    TestLoop<PlaneWall> loop(device, wall, test_config(), nullptr, FakeClock{&time});
    loop.tick();
    EXPECT_DOUBLE_EQ(device.last_command.force_n[0], 10.0);
    EXPECT_TRUE(loop.last_record().flags & kFlagSaturated);
    EXPECT_EQ(loop.summary().max_force_n, 10.0);
}

TEST(ServoLoop, PassivityControllerTamesAnActiveEnvironment) {
    // The handle moves at a constant 0.05 m/s against a negative damper: the coupling's
    // steady state pushes the handle along its motion (F = c v), generating energy.
    auto run_with = [](PassivityMode mode) {
        VirtualTime time;
        FakeDevice device;
        device.counts_per_read[0] = 50;
        fakes::ActiveDamper environment{.gain_n_s_per_m = 5.0};
        ServoConfig config = test_config();
        config.coupling = {.stiffness_n_per_m = 2000.0, .damping_n_s_per_m = 10.0};
        config.safety.passivity = {.mode = mode, .max_damping_n_s_per_m = 1000.0};
        TestLoop<fakes::ActiveDamper> loop(device, environment, config, nullptr, FakeClock{&time});
        double min_energy = 0.0;
        for (int n = 0; n < 1000; ++n) min_energy = std::min(min_energy, loop.tick().energy_j);
        return std::pair{min_energy, loop.stats().passivity_control_ticks};
    };
    const auto [observed_min, observed_control] = run_with(PassivityMode::observe);
    EXPECT_LT(observed_min, -1e-3);  // ~ -c v^2 t = -5 * 0.0025 * 1 s
    EXPECT_EQ(observed_control, 0u);
    const auto [controlled_min, control_ticks] = run_with(PassivityMode::control);
    EXPECT_GE(controlled_min, -1e-12);
    EXPECT_GT(control_ticks, 900u);
}

TEST(ServoLoop, RejectsBadConfigNamingTheField) {
    VirtualTime time;
    FakeDevice device;
    PlaneWall wall;
    ServoConfig config = test_config();
    config.counts_per_meter = 0.0;
    try {
        TestLoop<PlaneWall> loop(device, wall, config, nullptr, FakeClock{&time});
        FAIL() << "no exception";
    } catch (const std::invalid_argument& error) {
        EXPECT_NE(std::string(error.what()).find("counts_per_meter"), std::string::npos);
    }
    config = test_config();
    config.axes = 4;
    EXPECT_THROW(TestLoop<PlaneWall>(device, wall, config, nullptr, FakeClock{&time}),
                 std::invalid_argument);
}

// The daemon instantiates the loop with an abstract device class (virtual read/write).
class AbstractDevice {
  public:
    virtual ~AbstractDevice() = default;
    virtual IoResult read(Sample& sample) noexcept = 0;
    virtual IoResult write(const Command& command) noexcept = 0;
};
class ConcreteDevice final : public AbstractDevice {
  public:
    FakeDevice fake;
    IoResult read(Sample& sample) noexcept override { return fake.read(sample); }
    IoResult write(const Command& command) noexcept override { return fake.write(command); }
};
static_assert(ServoDevice<AbstractDevice>);

TEST(ServoLoop, RealClockRunThroughAnAbstractDevice) {
    // No assertion on timing: only that the real pacer runs, records and stops.
    ConcreteDevice concrete;
    concrete.fake.set_position_counts(-1000);
    AbstractDevice& device = concrete;
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    ServoConfig config = test_config();
    config.rate_hz = 2000.0;
    ServoLoop<AbstractDevice, PlaneWall> loop(device, wall, config);
    const std::atomic<bool> stop{false};
    loop.run(stop, 20);
    EXPECT_EQ(loop.stats().ticks, 20u);
    EXPECT_EQ(loop.stats().wake_latency.count(), 20u);  // every paced tick records one
    EXPECT_FALSE(concrete.fake.last_command.enable);
    EXPECT_NEAR(concrete.fake.max_abs_force_n, 1.5, 1e-9);
}

TEST(ServoSeqlock, ReaderNeverSeesATornSnapshot) {
    Seqlock<StatusSnapshot> seqlock;
    std::atomic<bool> done{false};
    std::atomic<bool> reading{false};  // the writer starts once the reader does (a loaded
                                       // machine once ran all the stores before one read)
    std::thread writer([&] {
        while (!reading.load(std::memory_order_acquire)) std::this_thread::yield();
        StatusSnapshot snapshot;
        for (std::uint64_t i = 1; i <= 200'000; ++i) {
            snapshot.tick = i;
            snapshot.t_s = static_cast<double>(i);
            snapshot.x_m = {static_cast<double>(i), static_cast<double>(i), static_cast<double>(i)};
            snapshot.overruns = i;
            seqlock.store(snapshot);
        }
        done.store(true, std::memory_order_release);
    });
    std::uint64_t reads = 0;
    bool consistent = true;
    std::uint64_t last = 0;
    bool monotonic = true;
    reading.store(true, std::memory_order_release);
    do {
        const StatusSnapshot snapshot = seqlock.load();
        const auto i = static_cast<double>(snapshot.tick);
        if (snapshot.t_s != i || snapshot.x_m[2] != i || snapshot.overruns != snapshot.tick) {
            consistent = false;
        }
        if (snapshot.tick < last) monotonic = false;
        last = snapshot.tick;
        ++reads;
    } while (!done.load(std::memory_order_acquire));
    writer.join();
    EXPECT_TRUE(consistent);
    EXPECT_TRUE(monotonic);
    EXPECT_GT(reads, 0u);
    EXPECT_EQ(seqlock.load().tick, 200'000u);
}

// The servo tick's side of a seqlock another thread writes (the coupling gains): one attempt,
// no retry. What it takes is never torn, and its version is the store it came from.
TEST(ServoSeqlock, TryLoadTakesWholeValuesAndTheirVersionWithoutWaiting) {
    Seqlock<StatusSnapshot> seqlock;
    StatusSnapshot value;
    std::uint64_t version = 99;
    ASSERT_TRUE(seqlock.try_load(value, version));
    EXPECT_EQ(version, 0u);
    std::atomic<bool> done{false};
    std::atomic<bool> reading{false};
    std::thread writer([&] {
        while (!reading.load(std::memory_order_acquire)) std::this_thread::yield();
        StatusSnapshot snapshot;
        for (std::uint64_t i = 1; i <= 200'000; ++i) {
            snapshot.tick = i;
            snapshot.t_s = static_cast<double>(i);
            snapshot.x_m = {static_cast<double>(i), static_cast<double>(i), static_cast<double>(i)};
            seqlock.store(snapshot);
        }
        done.store(true, std::memory_order_release);
    });
    std::uint64_t taken = 0;
    bool consistent = true;
    reading.store(true, std::memory_order_release);
    do {
        if (!seqlock.try_load(value, version)) continue;
        ++taken;
        const auto i = static_cast<double>(value.tick);
        if (value.t_s != i || value.x_m[2] != i || version != value.tick) consistent = false;
    } while (!done.load(std::memory_order_acquire));
    writer.join();
    EXPECT_TRUE(consistent);
    EXPECT_GT(taken, 0u);
    ASSERT_TRUE(seqlock.try_load(value, version));
    EXPECT_EQ(version, 200'000u);
    EXPECT_EQ(value.tick, 200'000u);
}

}  // namespace
}  // namespace hapticd::servo
