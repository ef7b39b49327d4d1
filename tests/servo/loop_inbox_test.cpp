// The loop's inbox on its own: what a take returns for each request, in the order a tick
// carries it out, and (under ThreadSanitizer in CI: label threads) a requesting thread racing
// the servo thread's takes.
#include "hapticd/servo/loop_inbox.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

namespace hapticd::servo {
namespace {

struct Scene {
    int id = 0;
};
using Inbox = LoopInbox<Scene>;

// A source with `remaining` ticks to play.
class CountdownSource final : public OpenLoopSource {
  public:
    explicit CountdownSource(int remaining) : remaining_(remaining) {}
    PenaltyForce evaluate(const Vec3& /*x*/, const Vec3& /*v*/) const noexcept override {
        return {};
    }
    void commit(const Vec3& /*x*/, const Vec3& /*v*/) noexcept override { --remaining_; }
    void reset(const Vec3& /*x*/) noexcept override {}
    bool done() const noexcept override { return remaining_ <= 0; }

  private:
    int remaining_;
};

TEST(LoopInbox, ATakeWithNothingAskedChangesNothing) {
    Inbox inbox(/*arm_at_start=*/true);
    const auto requests = inbox.take(/*faulted=*/false);
    EXPECT_TRUE(requests.armed);
    EXPECT_FALSE(requests.armed_now);  // armed from the start: no edge
    EXPECT_FALSE(requests.fault_reset);
    EXPECT_FALSE(requests.gains.has_value());
    EXPECT_EQ(requests.environment, nullptr);
    EXPECT_EQ(requests.open_loop, nullptr);
    EXPECT_EQ(requests.open_loop_change, OpenLoopChange::none);
    EXPECT_EQ(requests.recording, nullptr);
    EXPECT_EQ(requests.mark, 0u);
    inbox.mark(7);
    EXPECT_EQ(inbox.take(false).mark, 7u);
    EXPECT_EQ(inbox.take(false).mark, 7u);  // a mark holds until the next
}

TEST(LoopInbox, ArmingIsAnEdgeOnceAndDisarmingIsSeenAtTheNextTake) {
    Inbox inbox(/*arm_at_start=*/false);
    EXPECT_FALSE(inbox.take(false).armed);
    inbox.arm();
    const auto first = inbox.take(false);
    EXPECT_TRUE(first.armed);
    EXPECT_TRUE(first.armed_now);
    const auto second = inbox.take(false);
    EXPECT_TRUE(second.armed);
    EXPECT_FALSE(second.armed_now);
    inbox.disarm();
    EXPECT_FALSE(inbox.take(false).armed);
    inbox.arm();
    EXPECT_TRUE(inbox.take(false).armed_now);  // an edge again after a disarm
}

TEST(LoopInbox, AFaultResetAndNewGainsAreEachTakenOnce) {
    Inbox inbox(true);
    inbox.request_fault_reset();
    inbox.request_coupling({.stiffness_n_per_m = 1200.0, .damping_n_s_per_m = 3.0});
    const auto first = inbox.take(false);
    EXPECT_TRUE(first.fault_reset);
    ASSERT_TRUE(first.gains.has_value());
    EXPECT_EQ(first.gains->stiffness_n_per_m, 1200.0);
    EXPECT_EQ(first.gains->damping_n_s_per_m, 3.0);
    const auto second = inbox.take(false);
    EXPECT_FALSE(second.fault_reset);
    EXPECT_FALSE(second.gains.has_value());
    // Two requests before a take: the last one counts.
    inbox.request_coupling({.stiffness_n_per_m = 10.0});
    inbox.request_coupling({.stiffness_n_per_m = 20.0});
    const auto third = inbox.take(false);
    ASSERT_TRUE(third.gains.has_value());
    EXPECT_EQ(third.gains->stiffness_n_per_m, 20.0);
}

TEST(LoopInbox, AnOfferIsTakenOnceOrWithdrawnAndOneWaitsAtATime) {
    Inbox inbox(true);
    Scene a{1};
    Scene b{2};
    ASSERT_TRUE(inbox.offer_environment(a));
    EXPECT_FALSE(inbox.offer_environment(b));  // one waits already
    EXPECT_FALSE(inbox.offer_taken());
    EXPECT_EQ(inbox.take(false).environment, &a);
    EXPECT_TRUE(inbox.offer_taken());
    EXPECT_FALSE(inbox.withdraw_environment(a));  // taken: too late
    EXPECT_EQ(inbox.take(false).environment, nullptr);
    ASSERT_TRUE(inbox.offer_environment(b));
    EXPECT_FALSE(inbox.withdraw_environment(a));  // not the one offered
    EXPECT_TRUE(inbox.withdraw_environment(b));
    EXPECT_EQ(inbox.take(false).environment, nullptr);
}

TEST(LoopInbox, AnOpenLoopSourceStartsPlaysAndEndsDisarmedWhileOffersAndGainsWait) {
    Inbox inbox(false);
    CountdownSource source(2);
    Scene scene{1};
    ASSERT_TRUE(inbox.play_open_loop(source));
    EXPECT_FALSE(inbox.play_open_loop(source));  // one at a time
    inbox.request_coupling({.stiffness_n_per_m = 500.0});
    ASSERT_TRUE(inbox.offer_environment(scene));
    const auto start = inbox.take(false);
    EXPECT_EQ(start.open_loop_change, OpenLoopChange::start);
    EXPECT_EQ(start.open_loop, &source);
    EXPECT_TRUE(start.armed);  // play_open_loop armed the loop
    EXPECT_FALSE(start.gains.has_value());
    EXPECT_EQ(start.environment, nullptr);
    EXPECT_FALSE(inbox.offer_taken());
    source.commit({}, {});
    const auto plays = inbox.take(false);
    EXPECT_EQ(plays.open_loop_change, OpenLoopChange::plays);
    EXPECT_EQ(plays.open_loop, &source);
    EXPECT_FALSE(inbox.open_loop_idle());
    source.commit({}, {});  // done
    const auto end = inbox.take(false);
    EXPECT_EQ(end.open_loop_change, OpenLoopChange::end);
    EXPECT_EQ(end.open_loop, nullptr);
    EXPECT_FALSE(end.armed);
    EXPECT_TRUE(inbox.open_loop_idle());
    // What waited is taken in the tick that let the source go.
    ASSERT_TRUE(end.gains.has_value());
    EXPECT_EQ(end.gains->stiffness_n_per_m, 500.0);
    EXPECT_EQ(end.environment, &scene);
    EXPECT_FALSE(inbox.take(false).armed);  // it stays disarmed
}

TEST(LoopInbox, AFaultEndsAnOpenLoopSourceUnlessTheSameTakeResetsIt) {
    Inbox inbox(false);
    CountdownSource source(100);
    ASSERT_TRUE(inbox.play_open_loop(source));
    ASSERT_EQ(inbox.take(false).open_loop_change, OpenLoopChange::start);
    inbox.request_fault_reset();
    const auto reset = inbox.take(/*faulted=*/true);
    EXPECT_TRUE(reset.fault_reset);
    EXPECT_EQ(reset.open_loop_change, OpenLoopChange::plays);
    const auto faulted = inbox.take(/*faulted=*/true);
    EXPECT_EQ(faulted.open_loop_change, OpenLoopChange::end);
    EXPECT_FALSE(faulted.armed);
    EXPECT_TRUE(inbox.open_loop_idle());
}

TEST(LoopInbox, ADisarmBeforeAnyTakeWithdrawsTheSourceUnplayedEvenIfArmedAgain) {
    Inbox inbox(false);
    CountdownSource source(100);
    ASSERT_TRUE(inbox.play_open_loop(source));
    inbox.disarm();
    inbox.arm();
    const auto requests = inbox.take(false);
    EXPECT_EQ(requests.open_loop, nullptr);
    EXPECT_EQ(requests.open_loop_change, OpenLoopChange::none);
    EXPECT_TRUE(requests.armed);  // the arm after the disarm still holds
    EXPECT_TRUE(inbox.open_loop_idle());
    // A new offer after that plays.
    ASSERT_TRUE(inbox.play_open_loop(source));
    EXPECT_EQ(inbox.take(false).open_loop_change, OpenLoopChange::start);
}

TEST(LoopInbox, TheStatusAndTheRecordingRingCrossWhole) {
    Inbox inbox(true);
    StatusSnapshot snapshot;
    snapshot.tick = 42;
    snapshot.stiffness_n_per_m = 900.0;
    inbox.publish_status(snapshot);
    EXPECT_EQ(inbox.status().tick, 42u);
    EXPECT_EQ(inbox.status().stiffness_n_per_m, 900.0);
    TelemetryRing ring(8);
    inbox.attach_recording(&ring);
    EXPECT_EQ(inbox.take(false).recording, &ring);
    inbox.attach_recording(nullptr);
    EXPECT_EQ(inbox.take(false).recording, nullptr);
}

// Another thread asks for everything as fast as it can while the servo thread takes: every
// gain taken is one that was asked for, whole; every environment offered is taken or
// withdrawn, never both; a source is never taken after the disarm that withdrew it.
TEST(LoopInbox, RequestsRacingTakesArriveWholeAndExactlyOnce) {
    constexpr int kRounds = 20000;
    Inbox inbox(false);
    std::vector<Scene> scenes(kRounds);
    std::atomic<bool> done{false};
    std::atomic<int> withdrawn{0};
    std::atomic<int> offered{0};
    CountdownSource source(1 << 30);
    std::thread requester([&] {
        for (int i = 0; i < kRounds; ++i) {
            const double k = 1.0 + i;
            inbox.request_coupling({.stiffness_n_per_m = k, .damping_n_s_per_m = 2.0 * k});
            if (inbox.offer_environment(scenes[static_cast<std::size_t>(i)])) {
                offered.fetch_add(1);
                if (i % 3 == 0 && inbox.withdraw_environment(scenes[static_cast<std::size_t>(i)])) {
                    withdrawn.fetch_add(1);
                }
            }
            if (i % 5 == 0) inbox.request_fault_reset();
            if (i % 7 == 0) (void)inbox.play_open_loop(source);
            if (i % 11 == 0) inbox.disarm();
            if (i % 13 == 0) inbox.arm();
        }
        done.store(true);
    });
    int taken = 0;
    double last_k = 0.0;
    std::vector<const Scene*> seen;
    const auto take_one = [&] {
        const auto requests = inbox.take(false);
        if (requests.gains) {
            EXPECT_EQ(requests.gains->damping_n_s_per_m, 2.0 * requests.gains->stiffness_n_per_m);
            EXPECT_GT(requests.gains->stiffness_n_per_m, last_k);  // newer than the last taken
            last_k = requests.gains->stiffness_n_per_m;
        }
        if (requests.environment != nullptr) {
            ++taken;
            seen.push_back(requests.environment);
        }
        if (requests.open_loop != nullptr) {
            EXPECT_TRUE(requests.armed);
        }
    };
    while (!done.load()) take_one();
    inbox.disarm();  // lets a playing source go, so that what waits behind it is taken
    for (int i = 0; i < 3; ++i) take_one();
    EXPECT_TRUE(inbox.offer_taken());
    EXPECT_EQ(taken + withdrawn.load(), offered.load());
    std::sort(seen.begin(), seen.end());
    EXPECT_EQ(std::adjacent_find(seen.begin(), seen.end()), seen.end());  // none taken twice
    requester.join();
    EXPECT_TRUE(inbox.open_loop_idle());
}

}  // namespace
}  // namespace hapticd::servo
