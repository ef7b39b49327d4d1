// The safety stage: saturation, velocity limit, fault latch, soft start, passivity.
#include "hapticd/servo/safety.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

namespace hapticd::servo {
namespace {

constexpr double kPeriod = 1e-3;

// Limits with the soft start and passivity out of the way unless a test wants them.
SafetyLimits plain_limits() {
    SafetyLimits limits;
    limits.max_force_n = 4.0;
    limits.max_speed_mps = 0.5;
    limits.soft_start = {.still_speed_mps = 1.0, .still_time_s = 0.0, .ramp_time_s = 0.0};
    limits.passivity.mode = PassivityMode::off;
    return limits;
}

TEST(ServoSafety, VectorNormSaturationKeepsDirection) {
    SafetySupervisor safety(plain_limits(), 3);
    const SafeForce out = safety.filter(Vec3(6.0, 8.0, 0.0), Vec3(0.0), kPeriod);
    EXPECT_TRUE(out.enable);
    EXPECT_TRUE(out.saturated);
    EXPECT_NEAR(out.handle_force_n.x, 2.4, 1e-12);
    EXPECT_NEAR(out.handle_force_n.y, 3.2, 1e-12);
    EXPECT_NEAR(glm::length(out.handle_force_n), 4.0, 1e-12);
}

TEST(ServoSafety, PerAxisSaturationClampsEachAxis) {
    SafetyLimits limits = plain_limits();
    limits.saturation = ForceSaturation::per_axis;
    SafetySupervisor safety(limits, 3);
    const SafeForce out = safety.filter(Vec3(6.0, -8.0, 1.0), Vec3(0.0), kPeriod);
    EXPECT_TRUE(out.saturated);
    EXPECT_EQ(out.handle_force_n, Vec3(4.0, -4.0, 1.0));
}

TEST(ServoSafety, ForceBelowTheLimitPassesUnchangedOnUsedAxesOnly) {
    SafetySupervisor safety(plain_limits(), 2);
    const SafeForce out = safety.filter(Vec3(1.0, -2.0, 3.0), Vec3(0.0), kPeriod);
    EXPECT_FALSE(out.saturated);
    EXPECT_EQ(out.handle_force_n, Vec3(1.0, -2.0, 0.0));  // axis 2 does not exist
}

TEST(ServoSafety, NonFiniteForceLatchesAndZeroesInTheSameTick) {
    SafetySupervisor safety(plain_limits(), 1);
    const SafeForce out =
        safety.filter(Vec3(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0), Vec3(0.0), kPeriod);
    EXPECT_FALSE(out.enable);
    EXPECT_EQ(out.handle_force_n, Vec3(0.0));
    EXPECT_EQ(safety.faults(), kFaultNonFinite);
    // Latched: a good force next tick is still zeroed.
    const SafeForce next = safety.filter(Vec3(1.0, 0.0, 0.0), Vec3(0.0), kPeriod);
    EXPECT_FALSE(next.enable);
    EXPECT_EQ(next.handle_force_n, Vec3(0.0));
    safety.reset();
    EXPECT_EQ(safety.faults(), 0u);
    EXPECT_TRUE(safety.filter(Vec3(1.0, 0.0, 0.0), Vec3(0.0), kPeriod).enable);
}

TEST(ServoSafety, OverspeedFaultLatches) {
    SafetyLimits limits = plain_limits();
    limits.speed_action = SpeedAction::fault;
    SafetySupervisor safety(limits, 1);
    const SafeForce out = safety.filter(Vec3(1.0, 0.0, 0.0), Vec3(0.6, 0.0, 0.0), kPeriod);
    EXPECT_FALSE(out.enable);
    EXPECT_EQ(out.handle_force_n, Vec3(0.0));
    EXPECT_EQ(safety.faults(), kFaultOverspeed);
    EXPECT_EQ(fault_name(kFaultOverspeed), "overspeed");
}

TEST(ServoSafety, OverspeedDampingActsOnTheExcessSpeed) {
    SafetyLimits limits = plain_limits();
    limits.max_force_n = 100.0;
    limits.overspeed_damping_n_s_per_m = 20.0;
    SafetySupervisor safety(limits, 1);
    const SafeForce out = safety.filter(Vec3(1.0, 0.0, 0.0), Vec3(0.8, 0.0, 0.0), kPeriod);
    EXPECT_TRUE(out.overspeed);
    EXPECT_NEAR(out.handle_force_n.x, 1.0 - 20.0 * (0.8 - 0.5), 1e-12);
    EXPECT_EQ(safety.faults(), 0u);
}

TEST(ServoSafety, RaisedFaultZeroesForceUntilReset) {
    SafetySupervisor safety(plain_limits(), 1);
    safety.raise(kFaultDeviceLost | kFaultEncoderJump);
    const SafeForce out = safety.filter(Vec3(1.0, 0.0, 0.0), Vec3(0.0), kPeriod);
    EXPECT_FALSE(out.enable);
    EXPECT_EQ(out.handle_force_n, Vec3(0.0));
    int names = 0;
    for_each_fault(safety.faults(), [&](std::string_view name) {
        EXPECT_TRUE(name == "device_lost" || name == "encoder_jump") << name;
        ++names;
    });
    EXPECT_EQ(names, 2);
}

TEST(ServoSafety, RejectsBadLimitsNamingTheValue) {
    SafetyLimits limits = plain_limits();
    limits.max_force_n = -1.0;
    try {
        SafetySupervisor safety(limits, 1);
        FAIL() << "no exception";
    } catch (const std::invalid_argument& error) {
        EXPECT_NE(std::string(error.what()).find("max_force_n"), std::string::npos);
        EXPECT_NE(std::string(error.what()).find("-1"), std::string::npos);
    }
    EXPECT_THROW(SafetySupervisor(plain_limits(), 4), std::invalid_argument);
}

TEST(ServoSoftStart, WaitsForStillnessThenRampsLinearly) {
    // 1 kHz: 50 ms still, then a 100 ms ramp.
    SoftStart soft_start({.still_speed_mps = 0.01, .still_time_s = 0.05, .ramp_time_s = 0.1});
    // Moving: nothing, however long.
    for (int n = 0; n < 500; ++n) EXPECT_EQ(soft_start.update(0.02, kPeriod), 0.0);
    EXPECT_EQ(soft_start.phase(), SoftStart::Phase::waiting_for_still);
    // Still for 50 ticks: the timer completes on the 50th, still at zero force.
    for (int n = 0; n < 50; ++n) EXPECT_EQ(soft_start.update(0.0, kPeriod), 0.0) << n;
    EXPECT_EQ(soft_start.phase(), SoftStart::Phase::ramping);
    // Ramp: tick k of the ramp gives k T / ramp_time, whatever the handle does meanwhile.
    for (int k = 1; k <= 100; ++k) {
        EXPECT_NEAR(soft_start.update(0.5, kPeriod), k * kPeriod / 0.1, 1e-9) << k;
    }
    EXPECT_EQ(soft_start.phase(), SoftStart::Phase::active);
    EXPECT_EQ(soft_start.update(3.0, kPeriod), 1.0);
    soft_start.restart();
    EXPECT_EQ(soft_start.update(0.0, kPeriod), 0.0);
}

TEST(ServoSoftStart, MotionRestartsTheStillnessTimer) {
    SoftStart soft_start({.still_speed_mps = 0.01, .still_time_s = 0.01, .ramp_time_s = 0.01});
    for (int n = 0; n < 9; ++n) soft_start.update(0.0, kPeriod);
    soft_start.update(0.05, kPeriod);  // a twitch
    for (int n = 0; n < 9; ++n) soft_start.update(0.0, kPeriod);
    EXPECT_EQ(soft_start.phase(), SoftStart::Phase::waiting_for_still);
    soft_start.update(0.0, kPeriod);
    EXPECT_EQ(soft_start.phase(), SoftStart::Phase::ramping);
}

TEST(ServoSafety, SoftStartScalesTheForce) {
    SafetyLimits limits = plain_limits();
    limits.soft_start = {.still_speed_mps = 0.01, .still_time_s = 0.002, .ramp_time_s = 0.004};
    SafetySupervisor safety(limits, 1);
    const Vec3 force(2.0, 0.0, 0.0);
    EXPECT_EQ(safety.filter(force, Vec3(0.0), kPeriod).handle_force_n.x, 0.0);
    EXPECT_EQ(safety.filter(force, Vec3(0.0), kPeriod).handle_force_n.x, 0.0);
    EXPECT_NEAR(safety.filter(force, Vec3(0.0), kPeriod).handle_force_n.x, 0.5, 1e-12);
    EXPECT_NEAR(safety.filter(force, Vec3(0.0), kPeriod).handle_force_n.x, 1.0, 1e-12);
    EXPECT_NEAR(safety.filter(force, Vec3(0.0), kPeriod).handle_force_n.x, 1.5, 1e-12);
    EXPECT_NEAR(safety.filter(force, Vec3(0.0), kPeriod).handle_force_n.x, 2.0, 1e-12);
}

// docs/architecture.md §7.3: a handle that starts deep in a wall asks for far more than
// max_force. The ramp must bound the force commanded (scale x max_force), not the raw force
// before saturation (a ramp on that one reached the limit 3 ms into a 0.5 s ramp).
TEST(ServoSafety, SoftStartBoundsTheForceCommandedNotTheRawForce) {
    SafetyLimits limits = plain_limits();
    limits.max_force_n = 20.0;
    limits.soft_start = {.still_speed_mps = 0.01, .still_time_s = 0.0, .ramp_time_s = 0.5};
    SafetySupervisor safety(limits, 1);
    const Vec3 raw(1000.0, 0.0, 0.0);  // 1 m into a 1000 N/m wall
    for (int n = 1; n <= 500; ++n) {
        const SafeForce out = safety.filter(raw, Vec3(0.0), kPeriod);
        const double ramp = n * kPeriod / 0.5;
        ASSERT_NEAR(out.handle_force_n.x, ramp * 20.0, 1e-9) << "tick " << n;
        ASSERT_TRUE(out.saturated);
    }
    EXPECT_NEAR(safety.filter(raw, Vec3(0.0), kPeriod).handle_force_n.x, 20.0, 1e-12);
}

// A deliberately active environment: the rendered handle force pushes along the motion,
// F_h = +c v (negative damping), while the handle oscillates.
struct ActiveRun {
    double min_energy_j = 0.0;
    double final_energy_j = 0.0;
    int control_ticks = 0;
};

ActiveRun run_active(PassivityMode mode) {
    SafetyLimits limits = plain_limits();
    limits.max_force_n = 100.0;
    limits.max_speed_mps = 10.0;
    limits.passivity = {.mode = mode, .max_damping_n_s_per_m = 1000.0};
    SafetySupervisor safety(limits, 1);
    const double negative_damping = 3.0;
    ActiveRun run;
    for (int n = 0; n < 2000; ++n) {
        const Vec3 v(0.1 * std::cos(2.0 * M_PI * 1.5 * n * kPeriod), 0.0, 0.0);
        const SafeForce out = safety.filter(negative_damping * v, v, kPeriod);
        if (out.passivity_damping_n_s_per_m > 0.0) {
            ++run.control_ticks;
            // The added force opposes the motion.
            EXPECT_LT(out.handle_force_n.x * v.x, negative_damping * v.x * v.x);
        }
        run.min_energy_j = std::min(run.min_energy_j, safety.passivity().energy_j());
    }
    run.final_energy_j = safety.passivity().energy_j();
    return run;
}

TEST(ServoPassivity, ObserverSeesTheActiveEnvironment) {
    const ActiveRun run = run_active(PassivityMode::observe);
    // E = -sum F.v T = -c sum v^2 T: about -c * 0.1^2/2 * 2 s = -0.03 J.
    EXPECT_LT(run.final_energy_j, -0.025);
    EXPECT_EQ(run.control_ticks, 0);
}

TEST(ServoPassivity, ControllerRestoresNonNegativeEnergy) {
    const ActiveRun run = run_active(PassivityMode::control);
    EXPECT_GT(run.control_ticks, 1000);
    EXPECT_GE(run.min_energy_j, -1e-12);
    EXPECT_GE(run.final_energy_j, -1e-12);
}

TEST(ServoPassivity, PassiveDamperIsLeftAlone) {
    SafetyLimits limits = plain_limits();
    limits.max_force_n = 100.0;
    limits.passivity = {.mode = PassivityMode::control};
    SafetySupervisor safety(limits, 1);
    for (int n = 0; n < 1000; ++n) {
        const Vec3 v(0.1 * std::sin(2.0 * M_PI * 2.0 * n * kPeriod), 0.0, 0.0);
        const SafeForce out = safety.filter(-2.0 * v, v, kPeriod);
        EXPECT_EQ(out.passivity_damping_n_s_per_m, 0.0);
        EXPECT_DOUBLE_EQ(out.handle_force_n.x, -2.0 * v.x);
    }
    EXPECT_GT(safety.passivity().energy_j(), 0.0);
}

TEST(ReadVerdict, EachResultAndStatusBitGivesItsFaultAndOnlyAGoodReadIsASample) {
    EXPECT_TRUE(judge_read(IoResult::ok, 0u).have_sample);
    EXPECT_EQ(judge_read(IoResult::ok, 0u).faults, 0u);
    EXPECT_FALSE(judge_read(IoResult::ok, kStatusDropped).have_sample);
    EXPECT_EQ(judge_read(IoResult::ok, kStatusDropped).faults, 0u);  // a read_timeout's to count
    EXPECT_FALSE(judge_read(IoResult::timeout, 0u).have_sample);
    EXPECT_EQ(judge_read(IoResult::timeout, 0u).faults, 0u);
    EXPECT_EQ(judge_read(IoResult::disconnected, 0u).faults, kFaultDeviceLost);
    EXPECT_EQ(judge_read(IoResult::error, 0u).faults, kFaultDeviceIo);
    const ReadVerdict gone = judge_read(IoResult::ok, kStatusDisconnected);
    EXPECT_FALSE(gone.have_sample);
    EXPECT_EQ(gone.faults, kFaultDeviceLost);
    EXPECT_EQ(judge_read(IoResult::ok, kStatusDeviceFault).faults, kFaultDeviceFault);
    EXPECT_EQ(judge_read(IoResult::ok, kStatusJump).faults, kFaultEncoderJump);
    EXPECT_EQ(judge_read(IoResult::ok, kStatusStale).faults, kFaultEncoderStale);
    // Stale counts in a reply that is no sample are no sensor fault: nothing is used.
    EXPECT_EQ(judge_read(IoResult::ok, kStatusStale | kStatusDropped).faults, 0u);
    EXPECT_TRUE(judge_read(IoResult::ok, kStatusLate).have_sample);  // late, but a sample
}

}  // namespace
}  // namespace hapticd::servo
