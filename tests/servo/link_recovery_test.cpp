// Link-fault recovery (docs/architecture.md §7.8: on every link error the loop zeroes force
// in that tick, reports the fault, and recovers when the device returns): the LinkRecovery
// counter on its own, then the servo loop against a scripted device on virtual time, tick by
// tick.
#include "hapticd/servo/link_recovery.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <optional>
#include <vector>

#include "hapticd/servo/servo_loop.hpp"
#include "servo_fakes.hpp"

namespace hapticd::servo {
namespace {

using fakes::FakeClock;
using fakes::FakeDevice;
using fakes::PlaneWall;
using fakes::VirtualTime;

// --- LinkRecovery alone ---------------------------------------------------------------

LinkRecovery counter(double settle_s = 0.005, double timeout_s = 0.02) {
    return LinkRecovery({.enabled = true, .settle_s = settle_s, .timeout_s = timeout_s}, 1000.0);
}

TEST(LinkRecovery, TheLinkFaultsAreExactlyLostTimeoutAndIo) {
    EXPECT_EQ(kLinkFaults, kFaultDeviceLost | kFaultReadTimeout | kFaultDeviceIo);
    EXPECT_TRUE(only_link_faults(kFaultDeviceLost | kFaultReadTimeout));
    EXPECT_TRUE(only_link_faults(kFaultDeviceIo));
    EXPECT_FALSE(only_link_faults(0u));
    for (const std::uint32_t operator_fault :
         {kFaultEncoderJump, kFaultDeviceFault, kFaultOverspeed, kFaultNonFinite,
          kFaultOverrunBudget}) {
        EXPECT_FALSE(only_link_faults(operator_fault)) << fault_name(operator_fault);
        EXPECT_FALSE(only_link_faults(operator_fault | kFaultDeviceLost))
            << fault_name(operator_fault);
    }
}

TEST(LinkRecovery, SettleAndTimeoutAreTicksAtTheRate) {
    const LinkRecovery r = counter(0.5, 5.0);
    EXPECT_EQ(r.settle_ticks(), 500u);
    EXPECT_EQ(r.timeout_periods(), 5000u);
    EXPECT_EQ(counter(0.5, 0.0).timeout_periods(), 0u);  // wait for ever
    EXPECT_EQ(
        LinkRecovery({.enabled = true, .settle_s = 1e-6, .timeout_s = 0.0}, 1000.0).settle_ticks(),
        1u);  // at least one good tick
}

TEST(LinkRecovery, RecoversOnTheSettleThGoodTickAndABadTickStartsAgain) {
    LinkRecovery r = counter();                                         // 5 ticks
    EXPECT_EQ(r.update(kFaultDeviceLost, false, 1), LinkAction::none);  // the fault's tick
    for (int n = 0; n < 4; ++n) EXPECT_EQ(r.update(kFaultDeviceLost, true, 1), LinkAction::none);
    EXPECT_EQ(r.good_ticks(), 4u);
    EXPECT_EQ(r.update(kFaultDeviceLost, false, 1), LinkAction::none);  // a bad one
    EXPECT_EQ(r.good_ticks(), 0u);
    for (int n = 0; n < 4; ++n) EXPECT_EQ(r.update(kFaultDeviceLost, true, 1), LinkAction::none);
    EXPECT_EQ(r.update(kFaultDeviceLost, true, 1), LinkAction::recover);
    EXPECT_EQ(r.good_ticks(), 0u);
    EXPECT_EQ(r.latched_periods(), 0u);
}

TEST(LinkRecovery, NeverClearsAFaultThatNeedsAnOperator) {
    LinkRecovery r = counter();
    for (int n = 0; n < 100; ++n) {
        EXPECT_EQ(r.update(kFaultEncoderJump, true, 1), LinkAction::none);
        EXPECT_EQ(r.update(kFaultDeviceLost | kFaultDeviceFault, true, 1), LinkAction::none);
    }
    EXPECT_FALSE(r.recoverable(kFaultDeviceLost | kFaultEncoderJump));
    EXPECT_TRUE(r.recoverable(kFaultDeviceLost));
}

TEST(LinkRecovery, GivesUpWhenTheLatchOutlivesTheTimeout) {
    LinkRecovery r = counter(0.005, 0.02);  // 5 good ticks within 20 periods of the fault
    for (int n = 0; n < 19; ++n) EXPECT_EQ(r.update(kFaultDeviceLost, false, 1), LinkAction::none);
    EXPECT_EQ(r.update(kFaultDeviceLost, false, 1), LinkAction::give_up);
    EXPECT_TRUE(r.gave_up());
    EXPECT_EQ(r.update(kFaultDeviceLost, true, 1), LinkAction::give_up);  // for good
    r.reset();                                                            // an operator's reset
    EXPECT_FALSE(r.gave_up());

    // Overrun ticks count every period they cover.
    LinkRecovery overrun = counter(0.005, 0.02);
    EXPECT_EQ(overrun.update(kFaultReadTimeout, false, 10), LinkAction::none);
    EXPECT_EQ(overrun.update(kFaultReadTimeout, false, 10), LinkAction::give_up);

    // Without a timeout it waits for ever.
    LinkRecovery patient = counter(0.005, 0.0);
    for (int n = 0; n < 100'000; ++n)
        ASSERT_EQ(patient.update(kFaultDeviceLost, false, 1), LinkAction::none);
}

TEST(LinkRecovery, DisabledOrNoFaultDoesNothing) {
    LinkRecovery off({.enabled = false}, 1000.0);
    for (int n = 0; n < 10'000; ++n)
        ASSERT_EQ(off.update(kFaultDeviceLost, true, 1), LinkAction::none);
    LinkRecovery r = counter();
    for (int n = 0; n < 100; ++n) EXPECT_EQ(r.update(0u, true, 1), LinkAction::none);
}

TEST(LinkRecovery, RejectsBadSettingsNamingTheField) {
    auto message = [](const LinkRecoverySettings& settings) -> std::string {
        try {
            settings.validate();
        } catch (const std::invalid_argument& error) {
            return error.what();
        }
        return "";
    };
    EXPECT_NE(message({.enabled = true, .settle_s = 0.0}).find("settle_s"), std::string::npos);
    EXPECT_NE(message({.enabled = true, .settle_s = 61.0}).find("settle_s"), std::string::npos);
    EXPECT_NE(message({.enabled = true, .settle_s = 0.5, .timeout_s = 0.5}).find("timeout_s"),
              std::string::npos);
    EXPECT_NE(message({.enabled = true, .settle_s = 0.5, .timeout_s = -1.0}).find("timeout_s"),
              std::string::npos);
    EXPECT_EQ(message({.enabled = true, .settle_s = 0.5, .timeout_s = 0.0}), "");
    ServoConfig config;
    config.counts_per_meter = 1e6;
    config.coupling = {.stiffness_n_per_m = 1000.0};
    config.link_recovery.settle_s = -1.0;
    EXPECT_THROW(config.validate(), std::invalid_argument);
}

// --- the servo loop ---------------------------------------------------------------------

constexpr int kSettleTicks = 50;  // 0.05 s at 1 kHz
constexpr double kWallForceN = 3.0;

ServoConfig recovery_config() {
    ServoConfig config;
    config.rate_hz = 1000.0;
    config.axes = 1;
    config.counts_per_meter = 1e6;  // 1 um per count
    config.coupling = {.stiffness_n_per_m = 2000.0, .damping_n_s_per_m = 0.0};
    config.safety.max_force_n = 10.0;
    // Still for 5 ms (5 ticks), then a 4 ms ramp: 0.75, 1.5, 2.25, 3 N against the wall.
    config.safety.soft_start = {
        .still_speed_mps = 0.01, .still_time_s = 0.005, .ramp_time_s = 0.004};
    config.safety.encoder_jump_m = 0.001;
    config.realtime.mode = RealtimeMode::off;
    config.stop_on_fault = true;
    config.link_recovery = {.enabled = true, .settle_s = 0.05, .timeout_s = 1.0};
    return config;
}

/// What the link does on one tick.
enum class Link {
    good,
    disconnected,  ///< read() and write() say the device is gone (ENODEV)
    lost_status,   ///< read() ok, but the sample says kStatusDisconnected
    timeout,       ///< read() timed out
    dropped,       ///< read() ok with kStatusDropped (a corrupted or missing reply)
    read_error,    ///< read() failed (IoResult::error)
    write_error,   ///< the sample is fine, the command is not accepted
    jump,          ///< the device flags an encoder jump (not a link fault)
    device_fault,  ///< the device reports a fault of its own (not a link fault)
};

/// One tick's outcome: what was commanded and what was latched.
struct Trace {
    double f_n = 0.0;
    bool enable = false;
    bool wrote = false;
    std::uint32_t faults = 0;
    std::uint32_t flags = 0;
};

class LinkRecoveryLoop : public ::testing::Test {
  protected:
    using Loop = ServoLoop<FakeDevice, PlaneWall, FakeClock>;

    void SetUp() override { device_.set_position_counts(-2000); }  // 2 mm into the wall

    Loop& loop(const ServoConfig& config = recovery_config()) {
        loop_.emplace(device_, wall_, config, nullptr, FakeClock{&time_});
        return *loop_;
    }

    Trace step(Link link) {
        device_.read_result = IoResult::ok;
        device_.write_result = IoResult::ok;
        device_.next.status = 0;
        switch (link) {
            case Link::good:
                break;
            case Link::disconnected:
                device_.read_result = IoResult::disconnected;
                device_.write_result = IoResult::disconnected;
                device_.next.status = kStatusDisconnected;
                break;
            case Link::lost_status:
                device_.next.status = kStatusDisconnected;
                break;
            case Link::timeout:
                device_.read_result = IoResult::timeout;
                break;
            case Link::dropped:
                device_.next.status = kStatusDropped;
                break;
            case Link::read_error:
                device_.read_result = IoResult::error;
                break;
            case Link::write_error:
                device_.write_result = IoResult::error;
                break;
            case Link::jump:
                device_.next.status = kStatusJump;
                break;
            case Link::device_fault:
                device_.next.status = kStatusDeviceFault;
                break;
        }
        const std::int64_t writes = device_.writes;
        const TelemetryRecord& record = loop_->tick();
        return {.f_n = record.f_n[0],
                .enable = device_.last_command.enable,
                .wrote = device_.writes > writes,
                .faults = record.faults,
                .flags = record.flags};
    }

    std::vector<Trace> steps(Link link, int ticks) {
        std::vector<Trace> traces;
        traces.reserve(static_cast<std::size_t>(ticks));
        for (int n = 0; n < ticks; ++n) traces.push_back(step(link));
        return traces;
    }

    /// Good ticks until the soft start has ramped the force to the wall's 3 N.
    void press_into_the_wall() {
        for (int n = 0; n < 20; ++n) step(Link::good);
        ASSERT_NEAR(device_.last_command.force_n[0], kWallForceN, 1e-9);
        ASSERT_TRUE(device_.last_command.enable);
    }

    VirtualTime time_;
    FakeDevice device_;
    PlaneWall wall_{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    std::optional<Loop> loop_;
};

TEST_F(LinkRecoveryLoop, DisconnectZeroesForceThenRecoversSettleTicksAfterTheDeviceIsBack) {
    constexpr int kGoneTicks = 30;
    loop();
    press_into_the_wall();

    // Gone: zero force written from the very tick that saw it; device_lost only (a lost
    // device is not also a read timeout).
    const std::vector<Trace> gone = steps(Link::disconnected, kGoneTicks);
    for (const Trace& t : gone) {
        EXPECT_EQ(t.f_n, 0.0);
        EXPECT_TRUE(t.wrote);
        EXPECT_FALSE(t.enable);
        EXPECT_EQ(t.faults, std::uint32_t{kFaultDeviceLost});
    }

    // Back: still latched (zero force) for exactly kSettleTicks good ticks; the last of them
    // carries the recovery flag and the latch is clear after it.
    const std::vector<Trace> settling = steps(Link::good, kSettleTicks);
    for (int n = 0; n < kSettleTicks; ++n) {
        const Trace& t = settling[static_cast<std::size_t>(n)];
        EXPECT_EQ(t.f_n, 0.0) << n;
        EXPECT_FALSE(t.enable) << n;
        EXPECT_EQ(t.faults, std::uint32_t{kFaultDeviceLost}) << n;
        EXPECT_EQ((t.flags & kFlagLinkRecovered) != 0u, n == kSettleTicks - 1) << n;
    }
    EXPECT_EQ(loop_->faults(), 0u);
    EXPECT_EQ(loop_->stats().link_recoveries, 1u);

    // Then the soft start: 5 still ticks at zero force, then the ramp to the wall's force.
    const std::vector<Trace> after = steps(Link::good, 10);
    for (int n = 0; n < 5; ++n) EXPECT_EQ(after[static_cast<std::size_t>(n)].f_n, 0.0) << n;
    EXPECT_NEAR(after[5].f_n, 0.75, 1e-9);
    EXPECT_NEAR(after[6].f_n, 1.5, 1e-9);
    EXPECT_NEAR(after[7].f_n, 2.25, 1e-9);
    EXPECT_NEAR(after[8].f_n, kWallForceN, 1e-9);
    EXPECT_NE(after[6].flags & kFlagSoftStart, 0u);
    for (const Trace& t : after) EXPECT_EQ(t.faults, 0u);

    const Summary summary = loop_->summary();
    EXPECT_EQ(summary.link_recoveries, 1u);
    ASSERT_EQ(summary.faults.size(), 1u);
    EXPECT_EQ(summary.faults[0], "device_lost");
    EXPECT_EQ(loop_->faults_seen(), std::uint32_t{kFaultDeviceLost});
    // Where the handle was: at the start, at the first sample back (the position history
    // starts again after the gap) and after the recovery.
    EXPECT_EQ(wall_.resets, 3);
}

TEST_F(LinkRecoveryLoop, ForceRampsInOnlyOnceTheHandleIsStill) {
    loop();
    press_into_the_wall();
    steps(Link::disconnected, 10);
    device_.counts_per_read[0] = -50;  // it comes back moving deeper in, at 0.05 m/s
    steps(Link::good, kSettleTicks);
    ASSERT_EQ(loop_->faults(), 0u);
    for (const Trace& t : steps(Link::good, 40)) EXPECT_EQ(t.f_n, 0.0);  // moving: no force
    device_.counts_per_read[0] = 0;                                      // still now
    const std::vector<Trace> still = steps(Link::good, 10);
    // The first still tick still sees the last step (backward difference), then 5 still
    // ticks, then the ramp.
    for (int n = 0; n < 6; ++n) EXPECT_EQ(still[static_cast<std::size_t>(n)].f_n, 0.0) << n;
    EXPECT_GT(still[6].f_n, 0.0);
    EXPECT_GT(still[9].f_n, still[6].f_n);
}

TEST_F(LinkRecoveryLoop, TheHandleMayMoveWhileTheDeviceIsGone) {
    // 5 cm further while unplugged: no encoder jump (the position history starts again with
    // the first sample back), and the coupling and the wall start again where the handle is.
    loop();
    press_into_the_wall();
    steps(Link::disconnected, 5);
    device_.set_position_counts(48'000);  // out of the wall, 5 cm from where it was
    steps(Link::good, kSettleTicks);
    EXPECT_EQ(loop_->faults(), 0u);
    EXPECT_EQ(loop_->faults_seen(), std::uint32_t{kFaultDeviceLost});
    for (const Trace& t : steps(Link::good, 20)) EXPECT_EQ(t.f_n, 0.0);  // free space
    EXPECT_DOUBLE_EQ(loop_->last_record().xe_m[0], 0.048);
}

TEST_F(LinkRecoveryLoop, AFlappingDeviceNeverRecoversBeforeSettle) {
    loop();
    press_into_the_wall();
    step(Link::disconnected);
    // Good runs one tick short of the settle, broken by every kind of link error.
    for (const Link bad : {Link::disconnected, Link::timeout, Link::dropped, Link::read_error,
                           Link::write_error, Link::lost_status, Link::disconnected}) {
        for (const Trace& t : steps(Link::good, kSettleTicks - 1)) {
            EXPECT_EQ(t.f_n, 0.0);
            EXPECT_NE(t.faults, 0u);
            EXPECT_EQ(t.flags & kFlagLinkRecovered, 0u);
        }
        const Trace t = step(bad);
        EXPECT_EQ(t.f_n, 0.0);
        EXPECT_NE(t.faults, 0u);
    }
    EXPECT_EQ(loop_->stats().link_recoveries, 0u);
    // A full settle of good ticks, and it recovers.
    steps(Link::good, kSettleTicks);
    EXPECT_EQ(loop_->faults(), 0u);
    EXPECT_EQ(loop_->stats().link_recoveries, 1u);
}

TEST_F(LinkRecoveryLoop, ReadTimeoutsAndIoErrorsRecoverToo) {
    ServoConfig config = recovery_config();
    config.safety.read_timeouts_allowed = 2;
    loop(config);
    press_into_the_wall();

    // Corrupted frames (dropped samples): the third in a row latches read_timeout.
    const std::vector<Trace> dropped = steps(Link::dropped, 3);
    EXPECT_EQ(dropped[1].faults, 0u);
    EXPECT_FALSE(dropped[1].wrote);  // within the budget the device holds its force (ZOH)
    EXPECT_EQ(dropped[2].faults, std::uint32_t{kFaultReadTimeout});
    EXPECT_TRUE(dropped[2].wrote);
    EXPECT_EQ(dropped[2].f_n, 0.0);
    EXPECT_FALSE(dropped[2].enable);
    steps(Link::good, kSettleTicks);
    EXPECT_EQ(loop_->faults(), 0u);

    // A failed write: device_io in that tick, zero force at once (the one more try).
    for (int n = 0; n < 20; ++n) step(Link::good);
    const Trace failed = step(Link::write_error);
    EXPECT_EQ(failed.faults, std::uint32_t{kFaultDeviceIo});
    EXPECT_EQ(device_.last_command.force_n[0], 0.0);
    EXPECT_FALSE(device_.last_command.enable);
    steps(Link::good, kSettleTicks - 1);
    EXPECT_EQ(loop_->faults(), std::uint32_t{kFaultDeviceIo});
    step(Link::good);
    EXPECT_EQ(loop_->faults(), 0u);

    // A read error.
    EXPECT_EQ(step(Link::read_error).faults, std::uint32_t{kFaultDeviceIo});
    steps(Link::good, kSettleTicks);
    EXPECT_EQ(loop_->faults(), 0u);
    EXPECT_EQ(loop_->stats().link_recoveries, 3u);
    EXPECT_EQ(loop_->faults_seen(), kFaultReadTimeout | kFaultDeviceIo);
}

TEST_F(LinkRecoveryLoop, FaultsThatNeedAnOperatorAreNeverCleared) {
    for (const Link fault : {Link::jump, Link::device_fault}) {
        loop();
        press_into_the_wall();
        const Trace t = step(fault);
        EXPECT_EQ(t.f_n, 0.0);
        EXPECT_FALSE(t.enable);
        for (const Trace& later : steps(Link::good, 10 * kSettleTicks)) {
            EXPECT_EQ(later.f_n, 0.0);
            EXPECT_NE(later.faults, 0u);
        }
        EXPECT_EQ(loop_->stats().link_recoveries, 0u);
        EXPECT_TRUE(loop_->faults() == kFaultEncoderJump || loop_->faults() == kFaultDeviceFault);
    }
    // A device that comes back reporting a fault of its own: device_lost | device_fault
    // stays latched.
    loop();
    press_into_the_wall();
    steps(Link::disconnected, 5);
    step(Link::device_fault);
    steps(Link::good, 10 * kSettleTicks);
    EXPECT_EQ(loop_->faults(), kFaultDeviceLost | kFaultDeviceFault);
    EXPECT_EQ(loop_->stats().link_recoveries, 0u);
    // The servo-side jump check still works for consecutive samples while settling.
    loop();
    press_into_the_wall();
    steps(Link::disconnected, 5);
    steps(Link::good, 3);
    device_.set_position_counts(10'000);  // 12 mm in one tick
    step(Link::good);
    steps(Link::good, 10 * kSettleTicks);
    EXPECT_EQ(loop_->faults(), kFaultDeviceLost | kFaultEncoderJump);
}

TEST_F(LinkRecoveryLoop, OperatorResetStillWorksAndForgetsTheProgress) {
    loop();
    press_into_the_wall();
    step(Link::disconnected);
    steps(Link::good, 10);
    loop_->inbox().request_fault_reset();
    const Trace t = step(Link::good);
    EXPECT_EQ(t.faults, 0u);
    EXPECT_EQ(loop_->stats().link_recoveries, 0u);
    EXPECT_EQ(loop_->link_recovery().good_ticks(), 0u);
}

// --- run() ------------------------------------------------------------------------------

/// Disconnected for read indices [gone_from, back_at); good otherwise.
struct UnpluggedDevice {
    FakeDevice inner{};
    std::int64_t gone_from = 0;
    std::int64_t back_at = 0;  ///< 0: never
    std::int64_t reads = 0;
    bool gone() const noexcept { return reads >= gone_from && (back_at == 0 || reads < back_at); }
    IoResult read(Sample& sample) noexcept {
        const bool lost = gone();
        inner.read_result = lost ? IoResult::disconnected : IoResult::ok;
        inner.next.status = lost ? kStatusDisconnected : 0u;
        ++reads;
        return inner.read(sample);
    }
    IoResult write(const Command& command) noexcept {
        inner.write(command);
        return reads - 1 >= gone_from && (back_at == 0 || reads - 1 < back_at)
                   ? IoResult::disconnected
                   : IoResult::ok;
    }
};

TEST(LinkRecoveryRun, RunKeepsTickingThroughALinkFaultAndRecovers) {
    VirtualTime time;
    UnpluggedDevice device{.gone_from = 100, .back_at = 300};
    device.inner.set_position_counts(-2000);
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    TelemetryRing ring(1024);
    ServoLoop<UnpluggedDevice, PlaneWall, FakeClock> loop(device, wall, recovery_config(), &ring,
                                                          FakeClock{&time});
    const std::atomic<bool> stop{false};
    EXPECT_EQ(loop.run(stop, 600), RunExit::tick_limit);
    EXPECT_EQ(loop.stats().ticks, 600u);
    EXPECT_EQ(loop.stats().link_recoveries, 1u);
    EXPECT_EQ(loop.faults(), 0u);
    EXPECT_GE(time.now_ns, 600 * 1'000'000);  // paced all along

    std::vector<TelemetryRecord> records;
    TelemetryRecord record;
    while (ring.try_pop(record)) records.push_back(record);
    ASSERT_EQ(records.size(), 600u);
    EXPECT_NEAR(records[99].f_n[0], kWallForceN, 1e-9);
    for (std::size_t n = 100; n < 300 + kSettleTicks; ++n) {
        EXPECT_EQ(records[n].f_n[0], 0.0) << n;
        EXPECT_EQ(records[n].faults, std::uint32_t{kFaultDeviceLost}) << n;
    }
    EXPECT_NE(records[300 + kSettleTicks - 1].flags & kFlagLinkRecovered, 0u);
    EXPECT_EQ(records[300 + kSettleTicks].faults, 0u);
    EXPECT_NEAR(records[599].f_n[0], kWallForceN, 1e-9);  // after the soft start
}

TEST(LinkRecoveryRun, ADeviceThatNeverReturnsEndsTheRunAfterTheTimeout) {
    VirtualTime time;
    UnpluggedDevice device{.gone_from = 100};
    device.inner.set_position_counts(-2000);
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    ServoConfig config = recovery_config();
    config.link_recovery.timeout_s = 0.2;  // 200 periods
    ServoLoop<UnpluggedDevice, PlaneWall, FakeClock> loop(device, wall, config, nullptr,
                                                          FakeClock{&time});
    const std::atomic<bool> stop{false};
    EXPECT_EQ(loop.run(stop, 10'000), RunExit::fault);
    EXPECT_EQ(loop.stats().ticks, 100u + 200u);  // the fault's tick and 199 more
    EXPECT_TRUE(loop.link_recovery().gave_up());
    EXPECT_EQ(loop.faults(), std::uint32_t{kFaultDeviceLost});
    EXPECT_FALSE(device.inner.last_command.enable);
    EXPECT_EQ(device.inner.last_command.force_n[0], 0.0);
}

TEST(LinkRecoveryRun, WithoutRecoveryAnyFaultEndsTheRunAsBefore) {
    VirtualTime time;
    UnpluggedDevice device{.gone_from = 100, .back_at = 110};
    device.inner.set_position_counts(-2000);
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    ServoConfig config = recovery_config();
    config.link_recovery.enabled = false;
    ServoLoop<UnpluggedDevice, PlaneWall, FakeClock> loop(device, wall, config, nullptr,
                                                          FakeClock{&time});
    const std::atomic<bool> stop{false};
    EXPECT_EQ(loop.run(stop, 1000), RunExit::fault);
    EXPECT_EQ(loop.stats().ticks, 101u);
    EXPECT_EQ(loop.faults(), std::uint32_t{kFaultDeviceLost});
    EXPECT_FALSE(device.inner.last_command.enable);
}

TEST(LinkRecoveryRun, AnOperatorFaultStillStopsTheRun) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(-2000);
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    ServoLoop<FakeDevice, PlaneWall, FakeClock> loop(device, wall, recovery_config(), nullptr,
                                                     FakeClock{&time});
    loop.tick();
    device.next.status = kStatusJump;
    const std::atomic<bool> stop{false};
    EXPECT_EQ(loop.run(stop, 1000), RunExit::fault);
    EXPECT_EQ(loop.stats().ticks, 2u);
    EXPECT_EQ(loop.faults(), std::uint32_t{kFaultEncoderJump});
}

TEST(LinkRecoveryRun, AGoneDeviceThatPacesTheLoopDoesNotSpinIt) {
    // A device that paces the loop blocks in read(); gone, it returns at once. run() must
    // then sleep to the period's deadline itself: one sleep per tick while it is gone, none
    // while it paces the loop again.
    VirtualTime time;
    UnpluggedDevice device{.gone_from = 10, .back_at = 110};
    device.inner.set_position_counts(-2000);
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    ServoConfig config = recovery_config();
    config.device_paces_loop = true;
    ServoLoop<UnpluggedDevice, PlaneWall, FakeClock> loop(device, wall, config, nullptr,
                                                          FakeClock{&time});
    const std::atomic<bool> stop{false};
    EXPECT_EQ(loop.run(stop, 300), RunExit::tick_limit);
    // Ticks 10..109 had no sample: the ticks after each of them (11..110) slept first.
    EXPECT_EQ(time.sleeps, 100);
    EXPECT_EQ(time.now_ns, 100 * 1'000'000);  // one period per tick without a sample
    EXPECT_EQ(loop.stats().link_recoveries, 1u);
    EXPECT_EQ(loop.faults(), 0u);
}

}  // namespace
}  // namespace hapticd::servo
