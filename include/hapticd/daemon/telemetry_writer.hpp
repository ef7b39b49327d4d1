// The telemetry writer: a thread that drains the servo loop's SPSC ring into a CSV file
// (docs/architecture.md §4.5: tick, t_s, per axis x{i}_m, v{i}_mps, xe{i}_m, f{i}_n, then
// the status columns; servo/telemetry_csv.hpp formats the lines).
//
// The servo thread only ever try_push()es (never blocks); this thread pops, formats whole
// lines into a buffer and write(2)s them out: when the buffer is nearly full, and at the
// latest kFlushInterval after the oldest line still in it (a timer on this thread, never on
// the tick). So a SIGKILL of the daemon loses at most the last kFlushInterval of records
// (plus what the ring still held, which the writer drains every kIdlePoll); with a
// sync interval the writer also fdatasync()s, bounding what a power cut loses.
//
// Only whole lines are written: every write(2) ends on a newline, and a write that fails
// part way (disk full, EFBIG) keeps the whole lines it wrote and is cut back with
// ftruncate() to the last of them; from then on nothing more is written (the records are still
// drained and counted), and the file holds records_written() whole lines after the header. finish()
// is called after the loop has stopped: it drains what is left, writes and closes, so on a clean
// stop the file holds every record the ring accepted. Records the ring refused are counted by the
// ring (TelemetryRing::dropped) and reported in the summary.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "hapticd/daemon/run_notes.hpp"
#include "hapticd/servo/telemetry_ring.hpp"

namespace hapticd::daemon {

/// What a log's or a recording's preamble says of the run it comes from, as the file starts.
struct TelemetryHeader {
    std::string version;     ///< hapticd's
    std::string name;        ///< [servo] name; "" for none
    std::string started_at;  ///< ISO 8601, UTC (RunStamp::started_at)
    std::string host;
    std::string device;         ///< the device line
    std::string config;         ///< the config's path, or "<embedded default>"
    std::string config_sha256;  ///< of the config's text as read (Config::sha256)
    double rate_hz = 0.0;
    bool coupling_enabled = true;    ///< [coupling] enabled
    double stiffness_n_per_m = 0.0;  ///< k_c of (16) in force
    double damping_n_s_per_m = 0.0;  ///< b_c of (16) in force
    std::string stability;  ///< the stability check's verdict on them (StartupCheck::describe())
    std::string scene;      ///< "NAME (CAUSALITY, SOURCE)"
};

/// The comment lines a log or a recording begins with, before its header row: "# key:
/// value" lines (docs/daemon.md, "Telemetry"): version, name (when set), started, host,
/// device, config, config_sha256, rate_hz, coupling_stiffness_n_per_m and
/// coupling_damping_n_s_per_m (or coupling: off), stability and scene. Values are one line
/// each, control characters written out (input::printable). Readers skip lines that begin
/// with '#' (tune/telemetry_log.hpp reads these; pandas: comment="#").
std::string telemetry_preamble(const TelemetryHeader& header);

class TelemetryWriter {
  public:
    /// The longest a formatted record waits in the writer's buffer before write(2).
    static constexpr std::chrono::milliseconds kFlushInterval{100};

    /// Creates (truncates) `path` and writes the header row. Throws std::runtime_error
    /// naming the path and the system's reason when the file cannot be created.
    TelemetryWriter(servo::TelemetryRing& ring, const std::string& path, int axes);
    /// Writes to `fd` (an open, empty file; the writer owns and closes it); `path` is for
    /// messages. `sync_interval` > 0: fdatasync() at most that often (0: never). `preamble`:
    /// whole comment lines ("# ...\n", telemetry_preamble()) written before the header row.
    /// `notes`: the run's (may be null: then no "# mark" lines), read on the writer's thread.
    TelemetryWriter(servo::TelemetryRing& ring, int fd, std::string path, int axes,
                    std::chrono::milliseconds sync_interval = std::chrono::milliseconds{0},
                    std::string_view preamble = {}, const RunNotes* notes = nullptr);
    ~TelemetryWriter();
    TelemetryWriter(const TelemetryWriter&) = delete;
    TelemetryWriter& operator=(const TelemetryWriter&) = delete;

    /// Before start(): records of earlier ticks are taken from the ring and not written (a
    /// recording's, whose file begins at a tick: src/daemon/socket/recording.hpp).
    void skip_ticks_before(std::uint64_t tick) noexcept { first_tick_ = tick; }
    /// Starts the writer thread.
    void start();
    /// After the producer has stopped: drains the ring, writes and closes the file. Throws
    /// std::runtime_error if any write failed (disk full...), naming the path and saying how
    /// many records are in the file. Idempotent.
    void finish();

    /// Records whole on disk (lines after the header that write(2) accepted).
    std::uint64_t records_written() const noexcept {
        return records_written_.load(std::memory_order_relaxed);
    }
    /// Records taken from the ring (written or not).
    std::uint64_t records_taken() const noexcept {
        return records_taken_.load(std::memory_order_relaxed);
    }
    /// No write failed: every record taken is in the file (after finish()). Any thread, at
    /// any time: while the writer runs, whether any write failed so far.
    bool complete() const noexcept { return write_errno_.load(std::memory_order_relaxed) == 0; }
    /// After finish(): why the file is not whole ("writing telemetry failed: REASON; the
    /// file holds the first N of M records, each line whole"); empty when it is.
    std::string failure() const;
    const std::string& path() const noexcept { return path_; }

  private:
    void run() noexcept;
    void drain() noexcept;
    void flush_buffer() noexcept;
    void write_marks(std::uint32_t mark) noexcept;

    servo::TelemetryRing& ring_;
    std::string path_;
    int axes_;
    int fd_ = -1;
    std::chrono::milliseconds sync_interval_{0};
    std::vector<char> buffer_;
    std::size_t used_ = 0;
    std::uint64_t buffered_records_ = 0;  ///< record lines in buffer_ (no comment, no header)
    std::uint64_t file_bytes_ = 0;        ///< bytes on disk: whole lines only
    const RunNotes* notes_ = nullptr;
    std::uint32_t last_mark_ = 0;  ///< the mark of the last record taken
    bool first_record_ = true;
    std::atomic<int> write_errno_{0};  // the writer thread's; read by complete() from any
    std::uint64_t first_tick_ = 0;
    std::chrono::steady_clock::time_point oldest_buffered_{};
    std::chrono::steady_clock::time_point last_sync_{};
    std::atomic<bool> producer_done_{false};
    std::atomic<std::uint64_t> records_written_{0};
    std::atomic<std::uint64_t> records_taken_{0};
    std::thread thread_;
    bool finished_ = false;
};

}  // namespace hapticd::daemon
