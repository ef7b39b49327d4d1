// Loop pacing on an absolute deadline (docs/architecture.md §3.1): sleep to
// deadline = start + n T with clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME), so that
// errors never accumulate. When the previous tick ran past the deadline (an overrun), the
// pacer counts the periods that were missed and moves to the latest deadline that has
// passed: the loop runs once, now, and never bursts to catch up.
//
// The clock is a template parameter (a `PacingClock`) so that tests drive the pacer with a
// virtual clock and never sleep, as libfranka's tests do.
#pragma once

#include <concepts>
#include <cstdint>

#include "hapticd/servo/monotonic_clock.hpp"

namespace hapticd::servo {

template <typename C>
concept PacingClock = requires(C& clock, std::int64_t deadline_ns) {
    { clock.now_ns() }
    noexcept->std::same_as<std::int64_t>;
    { clock.sleep_until_ns(deadline_ns) }
    noexcept;
};

static_assert(PacingClock<MonotonicClock>);

/// What one wait() found.
struct Wake {
    std::int64_t deadline_ns = 0;     ///< the deadline this tick belongs to
    std::int64_t wake_ns = 0;         ///< when the tick started
    std::int64_t latency_ns = 0;      ///< wake_ns - deadline_ns, >= 0
    std::int64_t missed_periods = 0;  ///< deadlines skipped because of an overrun
    bool overrun = false;             ///< the deadline had passed before wait() was called
};

template <PacingClock Clock>
class LoopPacer {
  public:
    LoopPacer(Clock& clock, std::int64_t period_ns) : clock_(&clock), period_ns_(period_ns) {}

    /// The first deadline is one period after now.
    void start() noexcept { next_deadline_ns_ = clock_->now_ns() + period_ns_; }
    void start_at(std::int64_t first_deadline_ns) noexcept {
        next_deadline_ns_ = first_deadline_ns;
    }

    /// Sleeps to the next deadline (or, after an overrun, returns at once for the latest
    /// deadline that has passed) and schedules the one after it.
    Wake wait() noexcept {
        Wake wake;
        const std::int64_t now = clock_->now_ns();
        if (now > next_deadline_ns_) {
            // Overrun: skip to the latest deadline <= now; the ones before it are missed.
            wake.overrun = true;
            wake.missed_periods = (now - next_deadline_ns_) / period_ns_;
            next_deadline_ns_ += wake.missed_periods * period_ns_;
            wake.wake_ns = now;
        } else {
            clock_->sleep_until_ns(next_deadline_ns_);
            wake.wake_ns = clock_->now_ns();
        }
        wake.deadline_ns = next_deadline_ns_;
        wake.latency_ns = wake.wake_ns > wake.deadline_ns ? wake.wake_ns - wake.deadline_ns : 0;
        next_deadline_ns_ += period_ns_;
        return wake;
    }

    std::int64_t period_ns() const noexcept { return period_ns_; }
    std::int64_t next_deadline_ns() const noexcept { return next_deadline_ns_; }

  private:
    Clock* clock_;
    std::int64_t period_ns_;
    std::int64_t next_deadline_ns_ = 0;
};

}  // namespace hapticd::servo
