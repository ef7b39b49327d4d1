// A lock-free single-producer single-consumer ring of fixed, power-of-two capacity, allocated
// once in the constructor. The servo tick is the producer: try_push() never blocks or
// allocates; when the ring is full the record is dropped and counted. The consumer (the
// daemon's telemetry writer thread) drains it with try_pop().
//
// One thread may push and one (other) thread may pop, concurrently; dropped() may be read
// from any thread.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "hapticd/servo/telemetry.hpp"

namespace hapticd::servo {

template <typename T>
class SpscRing {  // NOLINT(clang-analyzer-optin.performance.Padding): cache-line separation
    static_assert(std::is_trivially_copyable_v<T>);

  public:
    /// Throws std::invalid_argument unless capacity is a power of two >= 2.
    explicit SpscRing(std::size_t capacity) : capacity_(capacity), mask_(capacity - 1) {
        if (capacity < 2 || (capacity & (capacity - 1)) != 0) {
            throw std::invalid_argument(
                "telemetry ring: capacity must be a power of two >= 2, got " +
                std::to_string(capacity));
        }
        slots_ = std::make_unique<T[]>(capacity);  // value-initialised: pages touched now
    }

    SpscRing(const SpscRing&) = delete;
    SpscRing& operator=(const SpscRing&) = delete;

    /// Producer only. False (and dropped() + 1) when full.
    bool try_push(const T& value) noexcept {
        const std::uint64_t head = head_.load(std::memory_order_relaxed);
        if (head - cached_tail_ >= capacity_) {
            cached_tail_ = tail_.load(std::memory_order_acquire);
            if (head - cached_tail_ >= capacity_) {
                dropped_.fetch_add(1, std::memory_order_relaxed);
                return false;
            }
        }
        slots_[head & mask_] = value;
        head_.store(head + 1, std::memory_order_release);
        return true;
    }

    /// Consumer only. False when empty.
    bool try_pop(T& value) noexcept {
        const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
        if (tail == cached_head_) {
            cached_head_ = head_.load(std::memory_order_acquire);
            if (tail == cached_head_) return false;
        }
        value = slots_[tail & mask_];
        tail_.store(tail + 1, std::memory_order_release);
        return true;
    }

    std::size_t capacity() const noexcept { return capacity_; }
    std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }
    /// Approximate when called concurrently with push or pop.
    std::size_t size() const noexcept {
        return static_cast<std::size_t>(head_.load(std::memory_order_acquire) -
                                        tail_.load(std::memory_order_acquire));
    }

  private:
    static constexpr std::size_t kLine = 64;  // keep producer and consumer indices apart

    std::size_t capacity_;
    std::size_t mask_;
    std::unique_ptr<T[]> slots_;
    alignas(kLine) std::atomic<std::uint64_t> head_{0};  // written by the producer
    std::uint64_t cached_tail_ = 0;                      // producer's view of tail_
    alignas(kLine) std::atomic<std::uint64_t> tail_{0};  // written by the consumer
    std::uint64_t cached_head_ = 0;                      // consumer's view of head_
    alignas(kLine) std::atomic<std::uint64_t> dropped_{0};
};

using TelemetryRing = SpscRing<TelemetryRecord>;

}  // namespace hapticd::servo
