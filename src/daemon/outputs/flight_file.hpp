// Where the flight recorder's records go and how (docs/daemon.md, "The flight recorder"):
// a telemetry CSV (the --log format) per fault, beside the run's other files.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "hapticd/servo/telemetry.hpp"
#include "outputs/outputs_directory.hpp"

namespace hapticd::daemon {

/// The flight recorder holds this long (the last ticks before a fault).
inline constexpr double kFlightRecordS = 5.0;
/// At most this many flight files a run, and this many bytes in them (a link that keeps
/// dropping, or a reset loop, latches a fault every few ticks; each file is ~160 kB at 1 kHz).
inline constexpr int kMaxFlightFilesPerRun = 16;
inline constexpr std::uint64_t kMaxFlightBytesPerRun = std::uint64_t{32} << 20;

/// What writing one flight file came to.
struct FlightFile {
    std::string path;         ///< written, or tried
    std::string error;        ///< empty when written whole
    std::uint64_t bytes = 0;  ///< what was to be written (the run's cap counts it)
};

/// Writes `records` (oldest first) to a new DIR/flight-START-tickN.csv, N the last record's
/// tick, in the run's outputs directory (outputs_directory.hpp: never over a file, never
/// through a link). Never throws: a failure (disk full, no permission, a file planted under
/// that name) is in `error`, naming the path.
FlightFile write_flight_file(const OutputsDirectory& directory, const std::string& start_name,
                             const std::vector<servo::TelemetryRecord>& records, int axes);

}  // namespace hapticd::daemon
