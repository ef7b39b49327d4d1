// The sim's real-time contract and its realtime clock: read()/write() never allocate, and on
// the realtime clock the physics follows CLOCK_MONOTONIC exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>

#include "alloc_guard.hpp"
#include "hapticd/device/sim/sim_device.hpp"
#include "hapticd/servo/monotonic_clock.hpp"

namespace hapticd::device::sim {
namespace {

using hapticd::testing::AllocationGuard;

SimConfig busy_config(SimClock clock) {
    SimConfig c;
    c.axes = 3;
    c.clock = clock;
    c.coulomb_n = 0.05;
    c.human[0].family = HumanFamily::stiff_grasp;
    c.human[0].hand_mass_kg = 0.3;
    c.human[0].hand_stiffness_n_per_m = 500.0;
    c.human[0].push = PushProfile{0.0, 0.01, 0.01, 0.05, 0.05};
    c.human[1].family = HumanFamily::two_mass_grasp;
    c.human[1].hand_mass_kg = 0.3;
    c.human[1].skin_stiffness_n_per_m = 3000.0;
    c.human[1].arm_stiffness_n_per_m = 100.0;
    c.human[2].family = HumanFamily::heavy_hand;
    c.human[2].hand_mass_kg = 0.5;
    c.faults.drop_at_s = {0.1, 0.2};
    c.faults.drop_probability = 0.01;
    c.faults.late_probability = 0.01;
    c.faults.stale_at_s = 0.3;
    c.faults.stale_for_s = 0.01;
    c.faults.jump_at_s = 0.4;
    c.faults.jump_counts = 10;
    c.faults.disconnect_at_s = 0.45;
    return c;
}

TEST(SimRealtime, ReadAndWriteNeverAllocateInLockstep) {
    SimDevice dev;
    dev.open(busy_config(SimClock::lockstep));
    Sample s;
    Command cmd;
    cmd.enable = true;
    std::uint64_t allocations = 0;
    {
        AllocationGuard guard;
        for (int n = 0; n < 500; ++n) {
            dev.read(s);
            cmd.force_n = {std::sin(0.01 * n), -1.0, 0.5};
            dev.write(cmd);
        }
        allocations = guard.allocations();
    }
    EXPECT_EQ(allocations, 0u);
    EXPECT_EQ(dev.read(s), IoResult::disconnected);  // it did get through every fault
    {                                                // the guard itself sees an allocation
        AllocationGuard guard;
        int* volatile p = new int(3);  // volatile: the allocation cannot be elided
        delete p;
        EXPECT_EQ(guard.allocations(), 1u);
    }
}

TEST(SimRealtime, ReadAndWriteNeverAllocateOnTheRealtimeClock) {
    SimConfig c = busy_config(SimClock::realtime);
    c.faults = FaultConfig{};
    c.faults.drop_probability = 0.1;
    SimDevice dev;
    dev.open(c);
    Sample s;
    Command cmd;
    cmd.enable = true;
    cmd.force_n = {0.1, 0.1, 0.1};
    std::uint64_t allocations = 0;
    {
        AllocationGuard guard;
        for (int n = 0; n < 2000; ++n) {
            dev.read(s);
            dev.write(cmd);
        }
        allocations = guard.allocations();
    }
    EXPECT_EQ(allocations, 0u);
}

void sleep_s(double s) {
    servo::sleep_until_monotonic_ns(servo::monotonic_now_ns() + std::llround(s * 1e9));
}

// The force written at t_w is held from t_w; a later read() reports the state at its own
// device time, which is (10) under that force exactly, whatever the time is.
TEST(SimRealtime, PhysicsFollowsTheMonotonicClockExactly) {
    SimConfig c;
    c.clock = SimClock::realtime;
    c.counts_per_meter = 1e9;
    SimDevice dev;
    dev.open(c);
    Command cmd;
    cmd.enable = true;
    cmd.force_n[0] = 2.0;
    ASSERT_EQ(dev.write(cmd), IoResult::ok);
    const double t_w = dev.time_s();  // the force is held from here
    EXPECT_EQ(dev.plant(0).state().position_m, 0.0);
    const double m = 0.1, b = 2.0, F = 2.0, tau = m / b;
    Sample s;
    double previous_s = t_w;
    for (double wait_s : {0.0173, 0.0021, 0.0456}) {
        sleep_s(wait_s);
        ASSERT_EQ(dev.read(s), IoResult::ok);
        EXPECT_GE(s.device_time_s - previous_s, wait_s);
        EXPECT_LT(s.device_time_s - previous_s, wait_s + 0.05);
        previous_s = s.device_time_s;
        const double t = s.device_time_s - t_w, decay = -std::expm1(-t / tau);
        const double x = F / b * (t - tau * decay);
        EXPECT_NEAR(dev.plant(0).state().position_m, x, 1e-12 * x);
        EXPECT_EQ(s.encoder_counts[0],
                  static_cast<std::int64_t>(std::floor(dev.plant(0).state().position_m * 1e9)));
    }
    EXPECT_EQ(s.sequence, 2u);  // one per read on this clock
    dev.close();
    EXPECT_EQ(dev.held_force_n()[0], 0.0);
}

// With a loop delay D the command computed from the sample taken at t_s lands at t_s + D
// (or at once, if the write came later than that): the closed form of (10) from then on,
// and nothing before.
TEST(SimRealtime, ACommandLandsTheLoopDelayAfterItsSample) {
    SimConfig c;
    c.clock = SimClock::realtime;
    c.counts_per_meter = 1e9;
    c.delay_s = 0.0043;  // 4.3 periods at 1 kHz
    SimDevice dev;
    dev.open(c);
    Sample s;
    ASSERT_EQ(dev.read(s), IoResult::ok);
    const double t_sample = s.device_time_s;
    Command cmd;
    cmd.enable = true;
    cmd.force_n[0] = 2.0;
    ASSERT_EQ(dev.write(cmd), IoResult::ok);
    const double t_write = dev.time_s();
    // The delay on this clock is whole units of T 2^-20.
    const double delay_s =
        std::ldexp(static_cast<double>(dev.loop_delay().units), -kFractionBits) / c.rate_hz;
    EXPECT_NEAR(delay_s, 0.0043, 1e-9);
    const double t_land = std::max(t_sample + delay_s, t_write);
    if (t_write < t_land) {  // (a machine that stalled 4 ms between the two calls lands it now)
        EXPECT_EQ(dev.held_force_n()[0], 0.0);
        EXPECT_EQ(dev.commands_in_flight(), 1u);
    }
    const double m = 0.1, b = 2.0, F = 2.0, tau = m / b;
    bool saw_before = false, saw_after = false;
    for (double wait_s : {0.0011, 0.0012, 0.0173, 0.0456}) {
        sleep_s(wait_s);
        ASSERT_EQ(dev.read(s), IoResult::ok);
        const double t = s.device_time_s - t_land;
        if (t <= 0.0) {
            saw_before = true;
            EXPECT_EQ(dev.plant(0).state().position_m, 0.0);
            EXPECT_EQ(dev.held_force_n()[0], 0.0);
            continue;
        }
        saw_after = true;
        const double decay = -std::expm1(-t / tau);
        const double x = F / b * (t - tau * decay);
        EXPECT_NEAR(dev.plant(0).state().position_m, x, 1e-12 * x + 1e-18);
        EXPECT_EQ(dev.held_force_n()[0], F);
        EXPECT_EQ(dev.commands_in_flight(), 0u);
    }
    EXPECT_TRUE(saw_after);
    std::cout << "[sim] realtime delay: a read before the command landed: "
              << (saw_before ? "yes" : "no (the machine was slow)") << "\n";
    dev.close();
    EXPECT_EQ(dev.held_force_n()[0], 0.0);
}

}  // namespace
}  // namespace hapticd::device::sim
