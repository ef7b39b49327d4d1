// The telemetry writer: a thread that drains the servo loop's SPSC ring into a CSV file
// (DESIGN.md "Public names": tick, t_s, per axis x{i}_m, v{i}_mps, xe{i}_m, f{i}_n, then
// the status columns; servo/telemetry_csv.hpp formats the lines).
//
// The servo thread only ever try_push()es (never blocks); this thread pops, formats into a
// 1 MiB buffer and writes it out in large blocks. finish() is called after the loop has
// stopped: it drains what is left, flushes and closes, so on a clean stop the file holds
// every record the ring accepted. Records the ring refused are counted by the ring
// (TelemetryRing::dropped) and reported in the summary.
#pragma once

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "hapticd/servo/telemetry_ring.hpp"

namespace hapticd::daemon {

class TelemetryWriter {
  public:
    /// Opens `path` for writing and writes the header row. Throws std::runtime_error naming
    /// the path and the system's reason when the file cannot be created.
    TelemetryWriter(servo::TelemetryRing& ring, const std::string& path, int axes);
    ~TelemetryWriter();
    TelemetryWriter(const TelemetryWriter&) = delete;
    TelemetryWriter& operator=(const TelemetryWriter&) = delete;

    /// Starts the writer thread.
    void start();
    /// After the producer has stopped: drains the ring, flushes and closes the file. Throws
    /// std::runtime_error if any write failed (disk full...), naming the path. Idempotent.
    void finish();

    std::uint64_t records_written() const noexcept {
        return records_written_.load(std::memory_order_relaxed);
    }
    const std::string& path() const noexcept { return path_; }

  private:
    void run() noexcept;
    void drain() noexcept;
    void flush_buffer() noexcept;

    servo::TelemetryRing& ring_;
    std::string path_;
    int axes_;
    std::FILE* file_ = nullptr;
    std::vector<char> buffer_;
    std::size_t used_ = 0;
    int write_errno_ = 0;
    std::atomic<bool> producer_done_{false};
    std::atomic<std::uint64_t> records_written_{0};
    std::thread thread_;
    bool finished_ = false;
};

}  // namespace hapticd::daemon
