// The servo tick and loop against a fake device and small environments, on virtual time:
// the tick, its faults and the run. What other threads ask of the loop, the causalities and
// the safety stages: servo_loop_requests_test.cpp.
#include "hapticd/servo/servo_loop.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <ostream>
#include <string>
#include <thread>

#include "servo_fakes.hpp"
#include "servo_loop_fixture.hpp"

namespace hapticd::servo {
namespace {

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

// A world that fails after a number of evaluations (as a plugin's does: failed(), failure()),
// until its reset.
struct FailingWorld : fakes::PlaneWall {
    int evaluations_left = 3;
    mutable int evaluations = 0;
    bool broken = false;
    PenaltyForce evaluate(const Vec3& x, const Vec3& v) const noexcept {
        ++evaluations;
        return fakes::PlaneWall::evaluate(x, v);
    }
    void commit(const Vec3&, const Vec3&) noexcept {
        broken = broken || evaluations > evaluations_left;
    }
    void reset(const Vec3&) noexcept {             // the first, at the first sample, too
        if (broken) evaluations_left = 1'000'000;  // restarted after its failure: it works
        broken = false;
        evaluations = 0;
    }
    bool failed() const noexcept { return broken; }
    std::string_view failure() const noexcept { return broken ? "evaluate() returned 7" : ""; }
};

TEST(ServoLoop, AWorldThatFailedIsAFaultWhoseReasonTheInboxKeepsUntilAReset) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(1000);
    FailingWorld environment;
    ServoConfig config = test_config();
    config.stop_on_fault = false;
    TestLoop<FailingWorld> loop(device, environment, config, nullptr, FakeClock{&time});
    EXPECT_EQ(loop.inbox().environment_failure(), "");
    for (int n = 0; n < 10 && loop.faults() == 0u; ++n) loop.tick();
    EXPECT_EQ(loop.faults(), kFaultEnvironment);
    EXPECT_FALSE(device.last_command.enable);
    EXPECT_EQ(loop.inbox().environment_failure(), "evaluate() returned 7");
    loop.tick();  // latched: the reason stays
    EXPECT_EQ(loop.inbox().environment_failure(), "evaluate() returned 7");
    std::thread([&] { loop.inbox().request_fault_reset(); }).join();
    loop.tick();  // the world restarts where the handle is
    EXPECT_EQ(loop.faults(), 0u);
    EXPECT_EQ(loop.inbox().environment_failure(), "");
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

}  // namespace
}  // namespace hapticd::servo
