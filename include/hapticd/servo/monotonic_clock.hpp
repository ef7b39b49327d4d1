// CLOCK_MONOTONIC, the one clock of the loop's deadlines, the links' receive() deadlines and
// the simulated device's physics (docs/architecture.md §3.1). Header-only, so that the device
// layer and its plugins use it without linking the servo library. now goes through the vDSO
// (no system call); every sleep is clock_nanosleep(TIMER_ABSTIME), retried on EINTR, so that
// a signal never shifts a deadline. Nothing here allocates, locks or throws.
#pragma once

#include <time.h>

#include <cerrno>
#include <cstdint>

namespace hapticd::servo {

inline constexpr std::int64_t kNanosecondsPerSecond = 1'000'000'000;

/// CLOCK_MONOTONIC now, ns.
inline std::int64_t monotonic_now_ns() noexcept {
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    return static_cast<std::int64_t>(now.tv_sec) * kNanosecondsPerSecond + now.tv_nsec;
}

/// CLOCK_REALTIME now, in whole microseconds since the Unix epoch: the telemetry's
/// unix_time_s (µs / 1e6 is then the double nearest the decimal, and prints as one).
inline std::int64_t unix_now_us() noexcept {
    timespec now{};
    clock_gettime(CLOCK_REALTIME, &now);
    return static_cast<std::int64_t>(now.tv_sec) * 1'000'000 + now.tv_nsec / 1000;
}

/// Sleeps until CLOCK_MONOTONIC reaches deadline_ns (at once if it has).
inline void sleep_until_monotonic_ns(std::int64_t deadline_ns) noexcept {
    timespec deadline{};
    deadline.tv_sec = static_cast<time_t>(deadline_ns / kNanosecondsPerSecond);
    deadline.tv_nsec = static_cast<long>(deadline_ns % kNanosecondsPerSecond);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) == EINTR) {
    }
}

/// The loop's clock (a PacingClock, pacing.hpp); tests inject a virtual one.
struct MonotonicClock {
    std::int64_t now_ns() noexcept { return monotonic_now_ns(); }
    void sleep_until_ns(std::int64_t deadline_ns) noexcept {
        sleep_until_monotonic_ns(deadline_ns);
    }
};

}  // namespace hapticd::servo
