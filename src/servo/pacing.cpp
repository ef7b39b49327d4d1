#include "hapticd/servo/pacing.hpp"

#include <cerrno>
#include <ctime>

namespace hapticd::servo {

namespace {
constexpr std::int64_t kNanosecondsPerSecond = 1'000'000'000;
}

std::int64_t MonotonicClock::now_ns() noexcept {
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    return static_cast<std::int64_t>(now.tv_sec) * kNanosecondsPerSecond + now.tv_nsec;
}

void MonotonicClock::sleep_until_ns(std::int64_t deadline_ns) noexcept {
    timespec deadline{};
    deadline.tv_sec = static_cast<time_t>(deadline_ns / kNanosecondsPerSecond);
    deadline.tv_nsec = static_cast<long>(deadline_ns % kNanosecondsPerSecond);
    // Absolute: a signal that interrupts the sleep does not shift the deadline.
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) == EINTR) {
    }
}

}  // namespace hapticd::servo
