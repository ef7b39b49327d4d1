// The servo loop against a fake device, on virtual time: arm and disarm, offered
// environments, open-loop sources, the causalities, backpressure, saturation, the
// passivity controller, the config check, and a real clock through an abstract device.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <ostream>
#include <string>
#include <thread>

#include "hapticd/servo/servo_loop.hpp"
#include "servo_fakes.hpp"
#include "servo_loop_fixture.hpp"

namespace hapticd::servo {
namespace {

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

// A mark is stamped on every record from the next tick on, and changes nothing else: the
// force, the soft start and the state go on as without it. The record's time is the double
// nearest tick / rate, its wall clock the host's.
TEST(ServoLoop, AMarkIsStampedOnEveryRecordFromTheNextTickOn) {
    VirtualTime time;
    FakeDevice device;
    device.set_position_counts(-2000);
    PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 6000.0};
    TestLoop<PlaneWall> loop(device, wall, test_config(), nullptr, FakeClock{&time});
    const auto unix_before_s = static_cast<double>(unix_now_us()) / 1e6;
    for (int n = 0; n < 3; ++n) EXPECT_EQ(loop.tick().mark, 0u);
    loop.inbox().mark(1);
    loop.inbox().mark(2);  // two before a tick: the tick takes the latest
    EXPECT_EQ(loop.last_record().mark, 0u);
    for (int n = 0; n < 3; ++n) {
        const TelemetryRecord& record = loop.tick();
        EXPECT_EQ(record.mark, 2u);
        EXPECT_NEAR(device.last_command.force_n[0], 3.0, 1e-12);
        EXPECT_EQ(record.t_s, static_cast<double>(record.tick) / test_config().rate_hz);
        EXPECT_GE(record.unix_time_s, unix_before_s);
    }
    loop.inbox().mark(3);
    EXPECT_EQ(loop.tick().mark, 3u);
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

}  // namespace
}  // namespace hapticd::servo
