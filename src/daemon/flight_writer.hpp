// Writing the flight recorder out (docs/architecture.md §7.12): the last kFlightRecordS of
// ticks, in a ring the servo loop fills and freezes on a new fault; the watching thread writes
// it beside the run's files (flight_file.hpp) and thaws it, log or no log, and each file goes
// in the summary (docs/daemon.md, "The flight recorder").
#pragma once

#include <iosfwd>
#include <optional>
#include <string>

#include "hapticd/daemon/run.hpp"
#include "hapticd/daemon/summary_json.hpp"
#include "hapticd/servo/flight_recorder.hpp"

namespace hapticd::daemon {

class FlightWriter {
  public:
    /// A recorder of the last kFlightRecordS at `rate_hz` (for the loop to attach), its files
    /// in flight_directory(options).
    FlightWriter(const RunOptions& options, double rate_hz, int axes);

    servo::FlightRecorder& recorder() noexcept { return recorder_; }
    /// Where the files go; none: nowhere (the fault's line says so).
    const std::optional<std::string>& directory() const noexcept { return directory_; }

    /// When the loop has frozen the recorder: thaws it, writes its records to a file, says so
    /// on `log` and adds the file to `context.flight_records`. Nothing when it is not frozen.
    void write_frozen(RunContext& context, std::ostream& log);

  private:
    servo::FlightRecorder recorder_;
    std::optional<std::string> directory_;
    int axes_;
};

}  // namespace hapticd::daemon
