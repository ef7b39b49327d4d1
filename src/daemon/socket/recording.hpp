// A control socket's `record start PATH` / `record stop` (docs/control.md, "record_start"): a
// full-rate telemetry file in the --log format, lossless while the disk keeps up.
//
// One ring, allocated with the run and kept for all of it, is attached to the servo loop for
// each recording (ServoLoop::attach_recording) and drained by a TelemetryWriter of its own.
// Because the ring outlives every recording, a tick that read the ring just before a stop may
// still push to it safely; stop() waits two ticks for that, so that the file ends with the
// last tick before the stop. Everything here runs off the servo thread: on the control
// server's worker, and at the end of the run on the supervising thread.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "hapticd/daemon/telemetry_writer.hpp"
#include "hapticd/servo/telemetry_ring.hpp"

namespace hapticd::daemon {

class OutputsDirectory;  // src/daemon/outputs_directory.hpp

/// What a start or a stop came to.
struct RecordingResult {
    bool ok = false;
    std::string message{};  ///< why not, or what was done (for the journal)
    std::string path{};
    std::uint64_t first_tick = 0;  ///< start: the file's first tick; none before it
    std::uint64_t records = 0;     ///< stop: whole lines in the file after its header
    std::uint64_t dropped = 0;     ///< stop: records the ring refused (0: lossless)
    /// stop: every tick from the first to the stop is in the file (none dropped, no write
    /// failed); `failure` says why not. A stop that closed a file that is not whole is still
    /// ok: it stopped.
    bool complete = true;
    std::string failure{};
};

class Recording {
  public:
    /// `attach` hands the ring (or null) to the servo loop; `tick` is the servo's last
    /// published tick. `lockstep`: the loop waits for the writer (no fdatasync either). The
    /// files go in `directory` (the run's outputs directory; null: none, and start refuses).
    /// Each file begins with what `preamble` returns as it starts (telemetry_preamble(): the
    /// gains, verdict and scene in force then; unset: nothing), and carries the run's
    /// `notes` as "# mark" lines (null: none).
    Recording(std::function<void(servo::TelemetryRing*)> attach,
              std::function<std::uint64_t()> tick, int axes, bool lockstep,
              const OutputsDirectory* directory, std::function<std::string()> preamble = {},
              const RunNotes* notes = nullptr);
    ~Recording();
    Recording(const Recording&) = delete;
    Recording& operator=(const Recording&) = delete;

    /// Creates the file a client's `path` names in the directory (OutputsDirectory::
    /// client_file(): never elsewhere, never over an existing file, never through a link) and
    /// records from the next tick on.
    RecordingResult start(const std::string& path);
    /// Ends the recording: the file holds every tick from its start to the stop.
    RecordingResult stop();
    /// After the servo has stopped: ends a recording still running; nullopt when none was.
    std::optional<RecordingResult> finish_at_exit();
    /// The file being recorded to, if any (cheap: for `status`).
    std::optional<std::string> active_path() const;
    /// Whether the file being recorded to holds every record so far (no write failed); none
    /// when not recording (for `status`).
    std::optional<bool> active_whole() const;
    /// Every recording closed so far, in order (the summary's `recordings`).
    std::vector<RecordingResult> closed() const;

  private:
    RecordingResult end(bool servo_stopped);

    servo::TelemetryRing ring_;
    std::function<void(servo::TelemetryRing*)> attach_;
    std::function<std::uint64_t()> tick_;
    std::mutex mutex_;  // one start or stop at a time
    // Never held while waiting: status reads it. It guards active_path_, closed_, and the
    // writer_ pointer while active_path_ is set (status reads the writer's complete()).
    mutable std::mutex path_mutex_;
    std::unique_ptr<TelemetryWriter> writer_;
    std::optional<std::string> active_path_;
    std::vector<RecordingResult> closed_;  // under path_mutex_
    std::uint64_t dropped_before_ = 0;
    int axes_;
    bool lockstep_;
    const OutputsDirectory* directory_;
    std::function<std::string()> preamble_;  ///< each file's first lines (telemetry_preamble())
    const RunNotes* notes_;
};

}  // namespace hapticd::daemon
