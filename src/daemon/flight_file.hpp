// Where the flight recorder's records go and how (docs/daemon.md, "The flight recorder"):
// a telemetry CSV (the --log format) per fault, beside the run's other files.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "hapticd/daemon/run.hpp"
#include "hapticd/servo/telemetry.hpp"

namespace hapticd::daemon {

/// The flight recorder holds this long (the last ticks before a fault).
inline constexpr double kFlightRecordS = 5.0;

/// The directory of the flight files: $LOGS_DIRECTORY (a service's, its first entry), else
/// the directory of --log, else of --summary FILE; none when there is none of these (the run
/// says so when a fault comes).
std::optional<std::string> flight_directory(const RunOptions& options);

/// What writing one flight file came to.
struct FlightFile {
    std::string path;   ///< written, or tried
    std::string error;  ///< empty when written whole
};

/// Writes `records` (oldest first) to DIR/flight-START-tickN.csv, N the last record's tick.
/// Never throws: a failure (disk full, no permission) is in `error`, naming the path.
FlightFile write_flight_file(const std::string& directory, const std::string& start_name,
                             const std::vector<servo::TelemetryRecord>& records, int axes);

}  // namespace hapticd::daemon
