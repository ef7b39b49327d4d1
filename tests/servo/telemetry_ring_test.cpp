// The lock-free SPSC telemetry ring.
#include "hapticd/servo/telemetry_ring.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <thread>

namespace hapticd::servo {
namespace {

TEST(ServoTelemetryRing, RejectsCapacityThatIsNotAPowerOfTwo) {
    EXPECT_THROW(SpscRing<int>(0), std::invalid_argument);
    EXPECT_THROW(SpscRing<int>(1), std::invalid_argument);
    EXPECT_THROW(SpscRing<int>(1000), std::invalid_argument);
    EXPECT_NO_THROW(SpscRing<int>(1024));
}

TEST(ServoTelemetryRing, FullRingDropsAndCounts) {
    SpscRing<int> ring(4);
    for (int i = 0; i < 4; ++i) EXPECT_TRUE(ring.try_push(i));
    EXPECT_FALSE(ring.try_push(99));
    EXPECT_FALSE(ring.try_push(100));
    EXPECT_EQ(ring.dropped(), 2u);
    int value = -1;
    for (int i = 0; i < 4; ++i) {
        ASSERT_TRUE(ring.try_pop(value));
        EXPECT_EQ(value, i);  // the dropped ones never appear
    }
    EXPECT_FALSE(ring.try_pop(value));
    EXPECT_TRUE(ring.try_push(5));
    ASSERT_TRUE(ring.try_pop(value));
    EXPECT_EQ(value, 5);
}

TEST(ServoTelemetryRing, ProducerAndConsumerThreadsKeepOrderAndCount) {
    // The producer never waits; every record it pushed arrives once, in order; the ones it
    // could not push are counted. Records carry their sequence number in `tick`.
    constexpr std::uint64_t kRecords = 200'000;
    TelemetryRing ring(256);
    std::atomic<bool> producer_done{false};
    std::uint64_t pushed = 0;
    std::thread producer([&] {
        TelemetryRecord record;
        for (std::uint64_t i = 0; i < kRecords; ++i) {
            record.tick = i;
            record.x_m[0] = static_cast<double>(i);
            if (ring.try_push(record)) ++pushed;
        }
        producer_done.store(true, std::memory_order_release);
    });
    std::uint64_t received = 0;
    std::uint64_t last_tick = 0;
    bool in_order = true;
    bool consistent = true;
    std::thread consumer([&] {
        TelemetryRecord record;
        for (;;) {
            if (ring.try_pop(record)) {
                if (received > 0 && record.tick <= last_tick) in_order = false;
                if (record.x_m[0] != static_cast<double>(record.tick)) consistent = false;
                last_tick = record.tick;
                ++received;
            } else if (producer_done.load(std::memory_order_acquire) && ring.size() == 0) {
                break;
            }
        }
    });
    producer.join();
    consumer.join();
    EXPECT_TRUE(in_order);
    EXPECT_TRUE(consistent);
    EXPECT_EQ(received, pushed);
    EXPECT_EQ(pushed + ring.dropped(), kRecords);
}

TEST(ServoTelemetryRing, StalledConsumerMakesDrops) {
    TelemetryRing ring(64);
    std::atomic<bool> consumer_may_run{false};
    std::uint64_t received = 0;
    std::thread consumer([&] {
        while (!consumer_may_run.load(std::memory_order_acquire)) std::this_thread::yield();
        TelemetryRecord record;
        while (ring.try_pop(record)) ++received;
    });
    TelemetryRecord record;
    for (std::uint64_t i = 0; i < 1000; ++i) {
        record.tick = i;
        ring.try_push(record);  // consumer stalled: only the first 64 fit
    }
    consumer_may_run.store(true, std::memory_order_release);
    consumer.join();
    EXPECT_EQ(received, 64u);
    EXPECT_EQ(ring.dropped(), 1000u - 64u);
}

}  // namespace
}  // namespace hapticd::servo
