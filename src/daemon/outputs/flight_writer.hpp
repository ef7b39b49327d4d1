// Writing the flight recorder out (docs/architecture.md §7.12): the last kFlightRecordS of
// ticks, in a ring the servo loop fills and freezes on a new fault; the watching thread writes
// it beside the run's files (flight_file.hpp) and thaws it, log or no log, and each file goes
// in the summary (docs/daemon.md, "The flight recorder").
#pragma once

#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>

#include "hapticd/daemon/run.hpp"
#include "hapticd/servo/flight_recorder.hpp"
#include "outputs/outputs_directory.hpp"
#include "outputs/summary_json.hpp"

namespace hapticd::daemon {

class FlightWriter {
  public:
    /// A recorder of the last kFlightRecordS at `rate_hz` (for the loop to attach), its files
    /// in `directory` (the run's outputs directory; null: nowhere, and the fault's line says so).
    FlightWriter(const OutputsDirectory* directory, double rate_hz, int axes);

    servo::FlightRecorder& recorder() noexcept { return recorder_; }
    /// When the loop has frozen the recorder: thaws it, writes its records to a file, says so
    /// on `log` and adds the file to `context.flight_records`; past the run's cap
    /// (kMaxFlightFilesPerRun, kMaxFlightBytesPerRun), or when the write fails, counts it in
    /// `context.flight_records_not_written` instead. Nothing when it is not frozen.
    void write_frozen(RunContext& context, std::ostream& log);

  private:
    servo::FlightRecorder recorder_;
    const OutputsDirectory* directory_;
    int axes_;
    int files_ = 0;            // files tried this run (kMaxFlightFilesPerRun)
    std::uint64_t bytes_ = 0;  // bytes written to them (kMaxFlightBytesPerRun)
    bool told_cap_ = false;
};

}  // namespace hapticd::daemon
