// Fault injection of the simulated device: each fault shows the right status bit and
// IoResult at the right sample, deterministically.
#include <gtest/gtest.h>

#include <vector>

#include "hapticd/device/sim/sim_device.hpp"
#include "hapticd/servo/monotonic_clock.hpp"

namespace hapticd::device::sim {
namespace {

using servo::kStatusDisconnected;
using servo::kStatusDropped;
using servo::kStatusJump;
using servo::kStatusLate;
using servo::kStatusStale;

SimConfig faulty(const FaultConfig& faults) {
    SimConfig c;
    c.axes = 2;
    c.rate_hz = 1000.0;
    c.clock = SimClock::lockstep;
    c.faults = faults;
    return c;
}

Command push(double f) {
    Command c;
    c.enable = true;
    c.force_n = {f, -f, 0.0};
    return c;
}

struct Tick {
    IoResult read;
    IoResult write;
    Sample sample;
    double position_m;
};

/// n lockstep ticks (read, then write 2 N), as the servo loop does them.
std::vector<Tick> run(SimDevice& dev, int n) {
    std::vector<Tick> ticks;
    for (int i = 0; i < n; ++i) {
        Tick t{};
        t.read = dev.read(t.sample);
        t.position_m = dev.plant(0).state().position_m;
        t.write = dev.write(push(2.0));
        ticks.push_back(t);
    }
    return ticks;
}

TEST(SimFaults, NoFaultsMeansEveryTickIsClean) {
    SimDevice dev;
    dev.open(faulty({}));
    for (const Tick& t : run(dev, 100)) {
        EXPECT_EQ(t.read, IoResult::ok);
        EXPECT_EQ(t.write, IoResult::ok);
        EXPECT_EQ(t.sample.status, 0u);
    }
}

TEST(SimFaults, DisconnectAtATimeIsPermanentAndZeroesTheForce) {
    FaultConfig f;
    f.disconnect_at_s = 0.010;
    SimDevice dev;
    dev.open(faulty(f));
    const auto ticks = run(dev, 20);
    for (int n = 0; n < 10; ++n) {
        EXPECT_EQ(ticks[n].read, IoResult::ok) << n;
        EXPECT_EQ(ticks[n].write, IoResult::ok) << n;
        EXPECT_EQ(ticks[n].sample.status, 0u) << n;
    }
    for (int n = 10; n < 20; ++n) {
        EXPECT_EQ(ticks[n].read, IoResult::disconnected) << n;
        EXPECT_EQ(ticks[n].write, IoResult::disconnected) << n;
        EXPECT_EQ(ticks[n].sample.status, kStatusDisconnected) << n;
        EXPECT_EQ(ticks[n].sample.sequence, static_cast<std::uint64_t>(n));
    }
    EXPECT_EQ(dev.held_force_n()[0], 0.0);
    EXPECT_EQ(dev.held_force_n()[1], 0.0);
}

TEST(SimFaults, StaleEncoderFreezesTheCountsForItsDuration) {
    FaultConfig f;
    f.stale_at_s = 0.005;
    f.stale_for_s = 0.003;
    SimDevice dev;
    dev.open(faulty(f));
    const auto ticks = run(dev, 12);
    for (int n = 5; n < 8; ++n) {
        EXPECT_EQ(ticks[n].read, IoResult::ok) << n;
        EXPECT_EQ(ticks[n].sample.status, kStatusStale) << n;
        EXPECT_EQ(ticks[n].sample.encoder_counts, ticks[4].sample.encoder_counts) << n;
        EXPECT_EQ(ticks[n].sample.sequence, static_cast<std::uint64_t>(n));
    }
    EXPECT_EQ(ticks[4].sample.status, 0u);
    EXPECT_EQ(ticks[8].sample.status, 0u);
    // The handle kept moving underneath, and the fresh count shows it.
    EXPECT_GT(ticks[8].sample.encoder_counts[0], ticks[4].sample.encoder_counts[0] + 5);
    EXPECT_EQ(ticks[8].sample.encoder_counts[0],
              static_cast<std::int64_t>(std::floor(ticks[8].position_m * 1e5)));
}

TEST(SimFaults, StaleForEverWhenNoDurationIsGiven) {
    FaultConfig f;
    f.stale_at_s = 0.002;
    SimDevice dev;
    dev.open(faulty(f));
    const auto ticks = run(dev, 50);
    EXPECT_EQ(ticks[49].sample.status, kStatusStale);
    EXPECT_EQ(ticks[49].sample.encoder_counts, ticks[1].sample.encoder_counts);
}

TEST(SimFaults, JumpingEncoderFlagsTheJumpOnceAndKeepsTheOffset) {
    FaultConfig f;
    f.jump_at_s = 0.004;
    f.jump_counts = 1000;
    f.jump_axis = 1;
    SimDevice dev;
    dev.open(faulty(f));
    const auto ticks = run(dev, 8);
    for (int n = 0; n < 8; ++n) {
        EXPECT_EQ(ticks[n].read, IoResult::ok);
        EXPECT_EQ(ticks[n].sample.status, n == 4 ? kStatusJump : 0u) << n;
        EXPECT_EQ(ticks[n].sample.encoder_counts[0],
                  static_cast<std::int64_t>(std::floor(ticks[n].position_m * 1e5)));
    }
    const auto true_counts_axis1 = [&](int n) {
        // axis 1 is pushed with -2 N, the mirror image of axis 0.
        return ticks[n].sample.encoder_counts[1] - (n >= 4 ? 1000 : 0);
    };
    for (int n = 0; n < 8; ++n) {
        EXPECT_EQ(true_counts_axis1(n),
                  static_cast<std::int64_t>(std::floor(-ticks[n].position_m * 1e5)))
            << n;
    }
}

TEST(SimFaults, ScheduledDropsTimeOutAtTheirSamples) {
    FaultConfig f;
    f.drop_at_s = {0.0075, 0.003};  // unsorted on purpose; 0.0075 hits sample 8
    SimDevice dev;
    dev.open(faulty(f));
    const auto ticks = run(dev, 12);
    for (int n = 0; n < 12; ++n) {
        const bool dropped = n == 3 || n == 8;
        EXPECT_EQ(ticks[n].read, dropped ? IoResult::timeout : IoResult::ok) << n;
        EXPECT_EQ(ticks[n].sample.status, dropped ? kStatusDropped : 0u) << n;
        EXPECT_EQ(ticks[n].write, IoResult::ok) << n;
        EXPECT_EQ(ticks[n].sample.sequence, static_cast<std::uint64_t>(n));
    }
    // A dropped reply carries the last delivered counts, not new data.
    EXPECT_EQ(ticks[8].sample.encoder_counts, ticks[7].sample.encoder_counts);
}

TEST(SimFaults, RandomDropsFollowTheProbabilityAndTheSeed) {
    auto pattern = [](std::uint64_t seed) {
        FaultConfig f;
        f.drop_probability = 0.1;
        f.seed = seed;
        SimDevice dev;
        dev.open(faulty(f));
        std::vector<bool> dropped;
        for (const Tick& t : run(dev, 20000)) {
            EXPECT_EQ(t.read == IoResult::timeout, (t.sample.status & kStatusDropped) != 0);
            dropped.push_back(t.read == IoResult::timeout);
        }
        return dropped;
    };
    const auto a = pattern(7), b = pattern(7), c = pattern(8);
    EXPECT_EQ(a, b);
    EXPECT_NE(a, c);
    const auto count = std::count(a.begin(), a.end(), true);
    EXPECT_NEAR(static_cast<double>(count) / 20000.0, 0.1, 0.01);
}

TEST(SimFaults, LateRepliesAreFlaggedInLockstep) {
    FaultConfig f;
    f.late_at_s = {0.002};
    SimDevice dev;
    dev.open(faulty(f));
    const auto ticks = run(dev, 5);
    for (int n = 0; n < 5; ++n) {
        EXPECT_EQ(ticks[n].read, IoResult::ok);
        EXPECT_EQ(ticks[n].sample.status, n == 2 ? kStatusLate : 0u) << n;
    }
}

TEST(SimFaults, ReadingTheSameLockstepSampleTwiceGivesTheSameVerdict) {
    FaultConfig f;
    f.drop_at_s = {0.001};
    f.jump_at_s = 0.001;
    f.jump_counts = 5;
    SimDevice dev;
    dev.open(faulty(f));
    Sample s;
    dev.read(s);
    dev.write(push(0.0));
    EXPECT_EQ(dev.read(s), IoResult::timeout);
    EXPECT_EQ(s.status, kStatusDropped | kStatusJump);
    EXPECT_EQ(dev.read(s), IoResult::timeout);
    EXPECT_EQ(s.status, kStatusDropped | kStatusJump);
}

double monotonic_s() { return 1e-9 * static_cast<double>(servo::monotonic_now_ns()); }

TEST(SimFaults, LateRepliesAreReallyLateOnTheRealtimeClock) {
    FaultConfig f;
    f.late_at_s = {0.0};
    f.late_by_s = 0.02;
    SimConfig c = faulty(f);
    c.clock = SimClock::realtime;
    SimDevice dev;
    dev.open(c);
    Sample s;
    const double t0 = monotonic_s();
    EXPECT_EQ(dev.read(s), IoResult::ok);
    const double late_s = monotonic_s() - t0;
    EXPECT_EQ(s.status, kStatusLate);
    EXPECT_GE(late_s, 0.02);
    EXPECT_LT(late_s, 0.5);
    const double t1 = monotonic_s();
    EXPECT_EQ(dev.read(s), IoResult::ok);
    EXPECT_EQ(s.status, 0u);
    EXPECT_LT(monotonic_s() - t1, 0.01);
}

// The sim's injected faults are status bits of the samples, not a link's counts: it reports
// no link quality (the control socket's status shows counted = false).
TEST(SimFaults, KeepsNoLinkCounts) {
    FaultConfig faults;
    faults.drop_probability = 0.5;
    SimDevice dev;
    dev.open(faulty(faults));
    (void)run(dev, 100);
    const LinkQuality q = dev.link_quality();
    EXPECT_FALSE(q.counted);
    EXPECT_EQ(q.frames_sent, 0u);
    EXPECT_EQ(q.bad_frames, 0u);
    EXPECT_EQ(q.reply_timeouts, 0u);
    EXPECT_EQ(q.disconnects, 0u);
}

}  // namespace
}  // namespace hapticd::device::sim
