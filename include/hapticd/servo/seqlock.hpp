// A sequence lock for one writer and any number of readers on other threads. The writer never
// waits. Two directions are in use:
//   - the servo tick writes (its status), other threads read with load(), which retries while
//     a write is in progress;
//   - another thread writes (the control socket's coupling gains), the servo tick reads with
//     try_load(), which never retries: a write in progress may belong to a thread the
//     real-time servo thread has preempted, and waiting for it would never end. The tick
//     takes the value at a later tick instead. The payload lives in relaxed atomic words, so there
//     is no data race
// (Boehm, "Can seqlocks get along with programming language memory models?", 2012).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace hapticd::servo {

template <typename T>
class Seqlock {
    static_assert(std::is_trivially_copyable_v<T>);
    static constexpr std::size_t kWords =
        (sizeof(T) + sizeof(std::uint64_t) - 1) / sizeof(std::uint64_t);

  public:
    /// Writer only (one thread).
    void store(const T& value) noexcept {
        std::array<std::uint64_t, kWords> words{};
        std::memcpy(words.data(), &value, sizeof(T));
        const std::uint64_t sequence = sequence_.load(std::memory_order_relaxed);
        sequence_.store(sequence + 1, std::memory_order_relaxed);  // odd: write in progress
        std::atomic_thread_fence(std::memory_order_release);
        for (std::size_t i = 0; i < kWords; ++i)
            words_[i].store(words[i], std::memory_order_relaxed);
        sequence_.store(sequence + 2, std::memory_order_release);
    }

    /// Any thread. Retries until it gets a consistent copy.
    T load() const noexcept {
        std::array<std::uint64_t, kWords> words{};
        for (;;) {
            const std::uint64_t before = sequence_.load(std::memory_order_acquire);
            if ((before & 1u) != 0u) continue;
            for (std::size_t i = 0; i < kWords; ++i)
                words[i] = words_[i].load(std::memory_order_relaxed);
            std::atomic_thread_fence(std::memory_order_acquire);
            if (sequence_.load(std::memory_order_relaxed) == before) break;
        }
        T value;
        std::memcpy(static_cast<void*>(&value), words.data(),
                    sizeof(T));  // T is trivially copyable
        return value;
    }

    /// One attempt, for a reader that must not wait (the servo tick): false while a write is
    /// in progress or when one raced the copy; else the value and the number of completed
    /// stores it is the last of.
    bool try_load(T& value, std::uint64_t& version) const noexcept {
        const std::uint64_t before = sequence_.load(std::memory_order_acquire);
        if ((before & 1u) != 0u) return false;
        std::array<std::uint64_t, kWords> words{};
        for (std::size_t i = 0; i < kWords; ++i)
            words[i] = words_[i].load(std::memory_order_relaxed);
        std::atomic_thread_fence(std::memory_order_acquire);
        if (sequence_.load(std::memory_order_relaxed) != before) return false;
        std::memcpy(static_cast<void*>(&value), words.data(), sizeof(T));
        version = before / 2;
        return true;
    }

    /// Number of completed stores.
    std::uint64_t version() const noexcept { return sequence_.load(std::memory_order_acquire) / 2; }

  private:
    std::atomic<std::uint64_t> sequence_{0};
    std::array<std::atomic<std::uint64_t>, kWords> words_{};
};

}  // namespace hapticd::servo
