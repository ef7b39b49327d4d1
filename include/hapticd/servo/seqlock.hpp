// A sequence lock for one writer and any number of readers on other threads (or processes).
// The writer never waits. Two directions are in use:
//   - the servo tick writes (its status), other threads read with load(), which retries while
//     a write is in progress;
//   - another thread writes (the control socket's coupling gains), the servo tick reads with
//     try_load(), which never retries: a write in progress may belong to a thread the
//     real-time servo thread has preempted, and waiting for it would never end. The tick
//     takes the value at a later tick instead.
// The payload lives in words accessed as relaxed atomics, so there is no data race (Boehm,
// "Can seqlocks get along with programming language memory models?", 2012).
//
// seqlock_store() and seqlock_try_load() are the algorithm, over words wherever they are:
// Seqlock's own std::atomic words, or a block of memory shared with another process through
// std::atomic_ref (env/external_channel.hpp).
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace hapticd::servo {

/// Writer only (one thread): the sequence odd, the kWords payload words from the `bytes` of
/// `value` (<= 8 kWords), the sequence even, one higher. `sequence` and `word(i)` are atomic
/// words (std::atomic<std::uint64_t> or std::atomic_ref<std::uint64_t>).
template <std::size_t kWords, typename Sequence, typename Word>
void seqlock_store(Sequence&& sequence, Word&& word, const void* value,
                   std::size_t bytes) noexcept {
    std::array<std::uint64_t, kWords> copy{};
    std::memcpy(copy.data(), value, bytes);
    const std::uint64_t before = sequence.load(std::memory_order_relaxed);
    sequence.store(before + 1, std::memory_order_relaxed);  // odd: a write in progress
    std::atomic_thread_fence(std::memory_order_release);
    for (std::size_t i = 0; i < kWords; ++i) word(i).store(copy[i], std::memory_order_relaxed);
    sequence.store(before + 2, std::memory_order_release);
}

/// One attempt at a consistent copy of the payload into the `bytes` of `value`: false while a
/// write is in progress or when one raced the copy; else true, with the (even) sequence it was
/// taken at in `sequence_seen`.
template <std::size_t kWords, typename Sequence, typename Word>
bool seqlock_try_load(const Sequence& sequence, Word&& word, void* value, std::size_t bytes,
                      std::uint64_t& sequence_seen) noexcept {
    const std::uint64_t before = sequence.load(std::memory_order_acquire);
    if ((before & 1u) != 0u) return false;
    std::array<std::uint64_t, kWords> copy{};
    for (std::size_t i = 0; i < kWords; ++i) copy[i] = word(i).load(std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_acquire);
    if (sequence.load(std::memory_order_relaxed) != before) return false;
    std::memcpy(value, copy.data(), bytes);
    sequence_seen = before;
    return true;
}

template <typename T>
class Seqlock {
    static_assert(std::is_trivially_copyable_v<T>);
    static constexpr std::size_t kWords =
        (sizeof(T) + sizeof(std::uint64_t) - 1) / sizeof(std::uint64_t);

  public:
    /// Writer only (one thread).
    void store(const T& value) noexcept {
        seqlock_store<kWords>(sequence_, word_at(), &value, sizeof(T));
    }

    /// Any thread. Retries until it gets a consistent copy.
    T load() const noexcept {
        T value;
        std::uint64_t sequence = 0;
        while (!seqlock_try_load<kWords>(sequence_, word_at(), static_cast<void*>(&value),
                                         sizeof(T), sequence)) {
        }
        return value;
    }

    /// One attempt, for a reader that must not wait (the servo tick): false while a write is
    /// in progress or when one raced the copy; else the value and the number of completed
    /// stores it is the last of.
    bool try_load(T& value, std::uint64_t& version) const noexcept {
        std::uint64_t sequence = 0;
        if (!seqlock_try_load<kWords>(sequence_, word_at(), static_cast<void*>(&value), sizeof(T),
                                      sequence)) {
            return false;
        }
        version = sequence / 2;
        return true;
    }

    /// Number of completed stores.
    std::uint64_t version() const noexcept { return sequence_.load(std::memory_order_acquire) / 2; }

  private:
    auto word_at() noexcept {
        return [this](std::size_t i) -> std::atomic<std::uint64_t>& { return words_[i]; };
    }
    auto word_at() const noexcept {
        return [this](std::size_t i) -> const std::atomic<std::uint64_t>& { return words_[i]; };
    }

    std::atomic<std::uint64_t> sequence_{0};
    std::array<std::atomic<std::uint64_t>, kWords> words_{};
};

}  // namespace hapticd::servo
