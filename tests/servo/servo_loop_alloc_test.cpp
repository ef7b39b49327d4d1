// Real-time rule, checked: thousands of ticks of the servo loop, against a penalty wall (17)
// and an admittance proxy (22), with telemetry, make no allocation on the servo thread.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <string>
#include <vector>

#include "alloc_guard.hpp"
#include "hapticd/env/excitation_source.hpp"
#include "hapticd/servo/servo_loop.hpp"
#include "servo_fakes.hpp"

namespace hapticd::servo {
namespace {

using fakes::FakeClock;
using fakes::FakeDevice;
using fakes::VirtualTime;

// A device that sweeps sinusoidally through the wall at x = 0 (so contact comes and goes).
struct SweepingDevice {
    FakeDevice inner;
    std::int64_t n = 0;
    IoResult read(Sample& sample) noexcept {
        const double x_m = 0.004 * std::sin(2.0 * M_PI * 3.0 * static_cast<double>(n++) * 1e-3);
        inner.set_position_counts(std::llround(x_m * 1e6));
        return inner.read(sample);
    }
    IoResult write(const Command& command) noexcept { return inner.write(command); }
};

/// `velocity_filter_hz` > 0 puts the coupling damper on a filtered velocity.
ServoConfig alloc_config(double velocity_filter_hz = 0.0) {
    ServoConfig config;
    config.axes = 3;
    config.counts_per_meter = 1e6;
    config.coupling = {.stiffness_n_per_m = 2000.0,
                       .damping_n_s_per_m = 2.0,
                       .velocity_filter_hz = velocity_filter_hz};
    config.safety.max_force_n = 5.0;  // the sweep saturates sometimes
    config.safety.soft_start = {.still_speed_mps = 1.0, .still_time_s = 0.01, .ramp_time_s = 0.05};
    config.safety.passivity.mode = PassivityMode::control;
    config.realtime.mode = RealtimeMode::off;
    config.stop_on_fault = false;
    return config;
}

TEST(ServoAllocationGuard, SeesAnAllocation) {
    static std::vector<int>* volatile sink = nullptr;
    hapticd::testing::AllocationGuard guard;
    sink = new std::vector<int>(100);
    delete sink;
    EXPECT_EQ(guard.allocations(), 2u);  // the vector object and its buffer
    EXPECT_EQ(guard.deallocations(), 2u);
    const hapticd::testing::AllocationGuard fresh;
    std::string long_text(1000, 'x');
    EXPECT_GE(fresh.allocations(), 1u);
}

template <typename Environment>
void expect_ticks_do_not_allocate(Environment& environment, int ticks,
                                  double velocity_filter_hz = 0.0) {
    VirtualTime time;
    SweepingDevice device;
    TelemetryRing ring(64);  // small: it overflows, and dropping must not allocate either
    ServoLoop<SweepingDevice, Environment, FakeClock> loop(
        device, environment, alloc_config(velocity_filter_hz), &ring, FakeClock{&time});
    hapticd::testing::AllocationGuard guard;  // from the very first tick (environment reset)
    double max_force = 0.0;
    for (int n = 0; n < ticks; ++n) {
        const TelemetryRecord& record = loop.tick();
        max_force = std::max(max_force, std::abs(record.f_n[0]));
        if (n % 100 == 0) {
            TelemetryRecord popped;
            while (ring.try_pop(popped)) {
            }
            (void)loop.inbox().status();
        }
        if (n == ticks / 2) {
            loop.inbox().disarm();
            loop.tick();
            loop.inbox().arm();
        }
    }
    const std::uint64_t allocations = guard.allocations();
    EXPECT_EQ(allocations, 0u);
    EXPECT_EQ(loop.faults(), 0u);
    EXPECT_GT(max_force, 1.0);  // the ticks really rendered the wall
    EXPECT_GT(ring.dropped(), 0u);
}

TEST(ServoAllocation, ImpedanceWallTicksDoNotAllocate) {
    fakes::PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 8000.0, .damping_n_s_per_m = 5.0};
    expect_ticks_do_not_allocate(wall, 10'000);
}

TEST(ServoAllocation, AdmittanceProxyTicksDoNotAllocate) {
    fakes::ProxyPlane proxy{.wall_m = 0.0};
    expect_ticks_do_not_allocate(proxy, 10'000);
}

// The damper on a filtered velocity: the filter's state, its pole and the equivalent gains
// handed to an admittance environment live in the coupling, nothing on the heap.
TEST(ServoAllocation, FilteredCouplingTicksDoNotAllocate) {
    fakes::PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 8000.0, .damping_n_s_per_m = 5.0};
    expect_ticks_do_not_allocate(wall, 10'000, 100.0);
    fakes::ProxyPlane proxy{.wall_m = 0.0};
    expect_ticks_do_not_allocate(proxy, 10'000, 100.0);
}

// A recording (the control socket's record_start): a second ring attached and detached while
// the loop ticks, which every tick also pushes to, full or not.
TEST(ServoAllocation, ARecordingAttachedAndDetachedDoesNotAllocate) {
    VirtualTime time;
    SweepingDevice device;
    fakes::PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 8000.0, .damping_n_s_per_m = 5.0};
    ServoLoop<SweepingDevice, fakes::PlaneWall, FakeClock> loop(device, wall, alloc_config(),
                                                                nullptr, FakeClock{&time});
    TelemetryRing recording(128);
    hapticd::testing::AllocationGuard guard;
    for (int n = 0; n < 1000; ++n) {
        if (n == 100) loop.inbox().attach_recording(&recording);
        if (n == 900) loop.inbox().attach_recording(nullptr);
        loop.tick();
    }
    EXPECT_EQ(guard.allocations(), 0u);
    EXPECT_EQ(recording.size(), 128u);  // full: 800 ticks pushed into 128 places
    EXPECT_EQ(recording.dropped(), 800u - 128u);
}

// A scene load (the control socket's scene_load): the loop takes the new environment at a
// tick's start, restarts the soft start and resets the environment, all without the heap.
TEST(ServoAllocation, TakingAnOfferedEnvironmentDoesNotAllocate) {
    VirtualTime time;
    SweepingDevice device;
    fakes::PlaneWall first{.wall_m = 0.0, .stiffness_n_per_m = 8000.0, .damping_n_s_per_m = 5.0};
    fakes::PlaneWall second{.wall_m = 0.001, .stiffness_n_per_m = 4000.0};
    ServoLoop<SweepingDevice, fakes::PlaneWall, FakeClock> loop(device, first, alloc_config(),
                                                                nullptr, FakeClock{&time});
    hapticd::testing::AllocationGuard guard;
    for (int n = 0; n < 1000; ++n) {
        if (n % 100 == 50) {
            ASSERT_TRUE(loop.inbox().offer_environment(n % 200 == 50 ? second : first));
        }
        loop.tick();
    }
    EXPECT_EQ(guard.allocations(), 0u);
    EXPECT_TRUE(loop.inbox().offer_taken());
    EXPECT_EQ(second.resets, 5);
    EXPECT_GT(second.commits, 0);
}

// identify on the control socket: the excitation played open loop (play_open_loop), from
// its still wait through the fade-in, two periods and the fade-out to the let-go, then the
// environment armed again, all without the heap.
TEST(ServoAllocation, PlayingTheExcitationOpenLoopDoesNotAllocate) {
    VirtualTime time;
    SweepingDevice device;
    fakes::PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 8000.0, .damping_n_s_per_m = 5.0};
    ServoConfig config = alloc_config();
    config.arm_at_start = false;
    ServoLoop<SweepingDevice, fakes::PlaneWall, FakeClock> loop(device, wall, config, nullptr,
                                                                FakeClock{&time});
    env::ExcitationSettings settings;
    settings.signal = {.sample_rate_hz = 1000.0,
                       .axes = 3,
                       .band_low_hz = 2.0,
                       .band_high_hz = 20.0,
                       .period_s = 0.5,
                       .lines_per_decade = 10.0,
                       .peak_force_n = 0.5};
    settings.periods = 2;
    settings.fade_s = 0.1;
    settings.workspace_half_width_m = 0.05;
    settings.force_limit_n = 5.0;
    settings.still_speed_mps = 1.0;  // the sweep counts as still
    settings.still_time_s = 0.01;
    env::ExcitationSource source(settings);  // its tables are built here, before the guard
    hapticd::testing::AllocationGuard guard;
    for (int n = 0; n < 10; ++n) loop.tick();
    ASSERT_TRUE(loop.inbox().play_open_loop(source));
    for (int n = 0; n < 1500 && !loop.inbox().open_loop_idle(); ++n) loop.tick();
    const bool idle = loop.inbox().open_loop_idle();
    const int wall_commits = wall.commits;
    loop.inbox().arm();
    for (int n = 0; n < 200; ++n) loop.tick();
    EXPECT_EQ(guard.allocations(), 0u);
    EXPECT_TRUE(idle);
    EXPECT_EQ(source.phase(), env::ExcitationSource::Phase::finished);
    EXPECT_EQ(source.samples_played(), source.excitation().samples());
    EXPECT_EQ(source.excitation().samples(), 1200);
    EXPECT_GT(wall.commits, wall_commits) << "the wall renders again once armed";
}

TEST(ServoAllocation, FaultPathDoesNotAllocate) {
    VirtualTime time;
    SweepingDevice device;
    fakes::NanAfter environment{.after_evaluations = 100};
    ServoLoop<SweepingDevice, fakes::NanAfter, FakeClock> loop(device, environment, alloc_config(),
                                                               nullptr, FakeClock{&time});
    FlightRecorder recorder(256);  // the flight recorder records and freezes without allocating
    loop.attach_flight_recorder(&recorder);
    hapticd::testing::AllocationGuard guard;
    for (int n = 0; n < 1000; ++n) loop.tick();
    const bool frozen_by_the_fault = recorder.frozen();
    recorder.thaw();
    loop.inbox().request_fault_reset();
    // New coupling gains (the control socket's coupling request) are taken in a tick too.
    loop.inbox().request_coupling({.stiffness_n_per_m = 1500.0, .damping_n_s_per_m = 1.0});
    for (int n = 0; n < 10; ++n) loop.tick();
    EXPECT_EQ(guard.allocations(), 0u);
    EXPECT_NE(loop.faults_seen(), 0u);
    EXPECT_TRUE(frozen_by_the_fault);
    EXPECT_EQ(loop.coupling().gains().stiffness_n_per_m, 1500.0);
    EXPECT_EQ(loop.inbox().status().stiffness_n_per_m, 1500.0);
}

// The interval-unknown and stale-sample paths (docs/architecture.md §7.6, §7.1): a device
// clock that runs backwards every 50 ticks (zero force, the history and the soft start
// restart), and a stale sample at the end.
TEST(ServoAllocation, UnknownIntervalAndStalePathsDoNotAllocate) {
    VirtualTime time;
    SweepingDevice device;
    fakes::PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 8000.0, .damping_n_s_per_m = 5.0};
    ServoLoop<SweepingDevice, fakes::PlaneWall, FakeClock> loop(device, wall, alloc_config(),
                                                                nullptr, FakeClock{&time});
    hapticd::testing::AllocationGuard guard;
    for (int n = 0; n < 1000; ++n) {
        if (n % 50 == 49) device.inner.next.device_time_s -= 0.01;
        loop.tick();
    }
    device.inner.next.status = kStatusStale;
    loop.tick();
    EXPECT_EQ(guard.allocations(), 0u);
    EXPECT_EQ(loop.stats().intervals_unknown, 20u);
    EXPECT_EQ(loop.faults(), std::uint32_t{kFaultEncoderStale});
}

// The sweep, unplugged for 40 ticks of every 200 (and answering with dropped samples for
// a few more): link faults latch and clear by themselves again and again.
struct FlakyDevice {
    SweepingDevice sweep;
    std::int64_t n = 0;
    IoResult read(Sample& sample) noexcept {
        const std::int64_t phase = n++ % 200;
        const IoResult result = sweep.read(sample);
        if (phase >= 100 && phase < 140) {
            sample.status = kStatusDisconnected;
            return IoResult::disconnected;
        }
        if (phase >= 140 && phase < 145) sample.status = kStatusDropped;
        return result;
    }
    IoResult write(const Command& command) noexcept { return sweep.write(command); }
};

TEST(ServoAllocation, LinkRecoveryDoesNotAllocate) {
    VirtualTime time;
    FlakyDevice device;
    fakes::PlaneWall wall{.wall_m = 0.0, .stiffness_n_per_m = 8000.0, .damping_n_s_per_m = 5.0};
    ServoConfig config = alloc_config();
    config.stop_on_fault = true;
    config.link_recovery = {.enabled = true, .settle_s = 0.02, .timeout_s = 1.0};
    TelemetryRing ring(64);
    ServoLoop<FlakyDevice, fakes::PlaneWall, FakeClock> loop(device, wall, config, &ring,
                                                             FakeClock{&time});
    const std::atomic<bool> stop{false};
    hapticd::testing::AllocationGuard guard;
    const RunExit exit = loop.run(stop, 10'000);
    const std::uint64_t allocations = guard.allocations();
    EXPECT_EQ(allocations, 0u);
    EXPECT_EQ(exit, RunExit::tick_limit);
    EXPECT_EQ(loop.stats().link_recoveries, 50u);
    EXPECT_EQ(loop.faults_seen(), kFaultDeviceLost | kFaultReadTimeout);
}

}  // namespace
}  // namespace hapticd::servo
