// The flight recorder (docs/architecture.md §7.12): the last few seconds of ticks, always,
// whether or not a telemetry log was asked for, so that every fault can be read afterwards.
//
// A ring of TelemetryRecords allocated up front. The servo thread copies each tick's record
// into it (no allocation, no lock, no system call) and freezes it in the tick that latches a
// new fault, after recording that tick. Another thread, seeing it frozen, reads the records
// (the servo thread no longer writes them), writes them out and thaws it; the servo thread
// records again from its next tick. A fault latched while the recorder is still frozen
// freezes it at the first tick it keeps after the thaw (ServoLoop's record step).
//
// Ordering: the servo thread's stores to the ring happen before its release store of
// `frozen_`; the reader's acquire load of it sees them. Only the servo thread sets it, and
// only the reader clears it, so the two never touch the ring at once.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "hapticd/servo/telemetry.hpp"

namespace hapticd::servo {

class FlightRecorder {
  public:
    /// Holds the last `capacity` ticks (>= 1; std::invalid_argument otherwise).
    explicit FlightRecorder(std::size_t capacity);

    FlightRecorder(const FlightRecorder&) = delete;
    FlightRecorder& operator=(const FlightRecorder&) = delete;

    // --- the servo thread -------------------------------------------------------------
    /// Keeps `record`, dropping the oldest once full; nothing while frozen. Returns whether
    /// it kept it: only a kept record may freeze the ring (else a reader's thaw between this
    /// and freeze() would freeze the previous fault's ticks again).
    bool record(const TelemetryRecord& record) noexcept {
        if (frozen_.load(std::memory_order_acquire)) return false;
        ring_[static_cast<std::size_t>(recorded_ % ring_.size())] = record;
        ++recorded_;
        return true;
    }
    /// Keeps what it holds for a reader (the tick that latched a fault, after record()).
    void freeze() noexcept {
        if (!frozen_.load(std::memory_order_relaxed)) {
            frozen_.store(true, std::memory_order_release);
        }
    }

    // --- the reader -------------------------------------------------------------------
    bool frozen() const noexcept { return frozen_.load(std::memory_order_acquire); }
    /// The records held, oldest first; only while frozen() (empty otherwise).
    std::vector<TelemetryRecord> frozen_records() const;
    /// Records again from the servo's next tick.
    void thaw() noexcept { frozen_.store(false, std::memory_order_release); }

    std::size_t capacity() const noexcept { return ring_.size(); }

  private:
    std::vector<TelemetryRecord> ring_;
    std::uint64_t recorded_ = 0;  // the servo thread's; read by the reader only while frozen
    std::atomic<bool> frozen_{false};
};

}  // namespace hapticd::servo
