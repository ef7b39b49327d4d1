// The absolute-deadline pacer on an injected clock: no test here sleeps except the last,
// which only checks that the real clock moves forward.
#include "hapticd/servo/pacing.hpp"

#include <gtest/gtest.h>

#include "servo_fakes.hpp"

namespace hapticd::servo {
namespace {

constexpr std::int64_t kPeriodNs = 1'000'000;

TEST(ServoPacing, SleepsToAbsoluteDeadlinesWithoutDrift) {
    fakes::VirtualTime time{.now_ns = 5'000, .wake_latency_ns = 7'000};
    fakes::FakeClock clock{&time};
    LoopPacer pacer(clock, kPeriodNs);
    pacer.start();
    for (int n = 1; n <= 100; ++n) {
        time.now_ns += 300'000;  // compute time of the tick
        const Wake wake = pacer.wait();
        EXPECT_FALSE(wake.overrun);
        EXPECT_EQ(wake.missed_periods, 0);
        // Deadlines stay on the grid start + n T even though every wake is 7 us late.
        EXPECT_EQ(wake.deadline_ns, 5'000 + n * kPeriodNs);
        EXPECT_EQ(wake.latency_ns, 7'000);
    }
    EXPECT_EQ(time.sleeps, 100);
}

TEST(ServoPacing, OverrunCountsMissedPeriodsAndSkipsAhead) {
    fakes::VirtualTime time{};
    fakes::FakeClock clock{&time};
    LoopPacer pacer(clock, kPeriodNs);
    pacer.start();  // first deadline at 1 ms
    Wake wake = pacer.wait();
    EXPECT_EQ(wake.deadline_ns, 1'000'000);

    // The tick takes 3.4 ms: deadlines at 2, 3 and 4 ms have passed. The pacer runs once
    // now for the 4 ms deadline, counts 2 and 3 as missed, and does not sleep.
    time.now_ns += 3'400'000;
    const std::int64_t sleeps_before = time.sleeps;
    wake = pacer.wait();
    EXPECT_TRUE(wake.overrun);
    EXPECT_EQ(wake.missed_periods, 2);
    EXPECT_EQ(wake.deadline_ns, 4'000'000);
    EXPECT_EQ(wake.latency_ns, 400'000);
    EXPECT_EQ(time.sleeps, sleeps_before);

    // Never bursts: the next tick sleeps to 5 ms, not to 2 or 3.
    wake = pacer.wait();
    EXPECT_FALSE(wake.overrun);
    EXPECT_EQ(wake.deadline_ns, 5'000'000);
    EXPECT_EQ(time.now_ns, 5'000'000);
}

TEST(ServoPacing, SmallOverrunMissesNoPeriod) {
    fakes::VirtualTime time{};
    fakes::FakeClock clock{&time};
    LoopPacer pacer(clock, kPeriodNs);
    pacer.start();
    pacer.wait();              // at 1 ms
    time.now_ns += 1'000'001;  // 1 ns past the 2 ms deadline
    const Wake wake = pacer.wait();
    EXPECT_TRUE(wake.overrun);
    EXPECT_EQ(wake.missed_periods, 0);
    EXPECT_EQ(wake.deadline_ns, 2'000'000);
    EXPECT_EQ(pacer.next_deadline_ns(), 3'000'000);
}

TEST(ServoPacing, RealClockSleepsForward) {
    MonotonicClock clock;
    LoopPacer pacer(clock, 200'000);  // 0.2 ms
    pacer.start();
    const std::int64_t start = clock.now_ns();
    for (int n = 0; n < 5; ++n) {
        const Wake wake = pacer.wait();
        EXPECT_GE(wake.wake_ns, wake.deadline_ns);  // clock_nanosleep never wakes early
    }
    EXPECT_GE(clock.now_ns() - start, 5 * 200'000 - 200'000);
}

}  // namespace
}  // namespace hapticd::servo
