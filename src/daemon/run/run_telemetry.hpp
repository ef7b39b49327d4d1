// The run's telemetry log, --log (docs/architecture.md §4.5, §6.1): the ring the servo loop
// fills and the writer thread that drains it into the file, started before the loop exists
// and finished after its thread has joined, with what the log came to for the summary (§4.6).
#pragma once

#include <cstddef>
#include <iosfwd>
#include <memory>
#include <string_view>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/run.hpp"
#include "hapticd/daemon/run_notes.hpp"
#include "hapticd/daemon/telemetry_writer.hpp"
#include "hapticd/device/device.hpp"
#include "hapticd/servo/coupling.hpp"
#include "hapticd/servo/telemetry_ring.hpp"
#include "outputs/summary_json.hpp"
#include "run/run_outputs.hpp"

namespace hapticd::daemon {

// Telemetry ring: 65 s of records at 1 kHz in real time, so that a stalled disk loses
// nothing for a minute; a lockstep run waits for the writer instead (backpressure).
inline constexpr std::size_t kRealtimeRingRecords = std::size_t{1} << 16;
inline constexpr std::size_t kLockstepRingRecords = std::size_t{1} << 14;

/// The preamble's facts of this run as a file starts now, with the `gains` in force, the
/// stability check's `verdict` on them and the `scene` ("NAME (CAUSALITY, SOURCE)").
TelemetryHeader telemetry_header(const Config& config, const RunContext& context,
                                 const device::DeviceInfo& info, const servo::CouplingGains& gains,
                                 std::string verdict, std::string scene);

class RunTelemetry {
  public:
    /// With --log: the ring, and the writer on `outputs.log` (begun) started, its file begun
    /// with `preamble` and carrying the run's `notes` as "# mark" lines; without, nothing.
    RunTelemetry(const RunOptions& options, const device::DeviceInfo& info, Outputs& outputs,
                 std::string_view preamble, const RunNotes* notes);
    RunTelemetry(const RunTelemetry&) = delete;
    RunTelemetry& operator=(const RunTelemetry&) = delete;

    /// The ring the loop pushes to; null without --log.
    servo::TelemetryRing* ring() const noexcept { return ring_.get(); }

    /// After the servo thread has joined: drains the ring into the file and closes it (a
    /// failed write is a line on `log`), and puts what the log came to in `context`.
    void finish(const RunOptions& options, RunContext& context, std::ostream& log);

  private:
    std::unique_ptr<servo::TelemetryRing> ring_;
    std::unique_ptr<TelemetryWriter> writer_;  // after ring_: stopped before it goes
};

}  // namespace hapticd::daemon
