// The status seqlock (servo_loop.hpp): whole snapshots, never torn, and try_load.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <ostream>
#include <string>
#include <thread>

#include "hapticd/servo/servo_loop.hpp"
#include "servo_fakes.hpp"

namespace hapticd::servo {
namespace {

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
