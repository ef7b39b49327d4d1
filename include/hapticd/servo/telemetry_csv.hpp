// Telemetry as CSV (docs/architecture.md §4.5): a header row, then one line per record.
// Columns: tick, t_s, unix_time_s, then per axis i from 0: x{i}_m, v{i}_mps, xe{i}_m, f{i}_n,
// then the status columns status, tick_flags, faults, state, wake_latency_us, compute_us,
// energy_j, mark (docs/daemon.md, "Telemetry"). Numbers are written in the shortest form that
// reads back to the same double.
#pragma once

#include <cstddef>
#include <iosfwd>
#include <span>
#include <string>

#include "hapticd/servo/telemetry.hpp"

namespace hapticd::servo {

/// Longest line format_csv_record() can produce, newline included.
inline constexpr std::size_t kMaxCsvLineChars = 1024;

/// The header row for `axes` (1..kMaxAxes), without a newline. Throws std::invalid_argument.
std::string csv_header(int axes);

/// Formats `record` as one CSV line ending in '\n' into `out`, without allocating. Returns
/// the number of characters written, or 0 if `out` is too small (kMaxCsvLineChars is enough)
/// or `axes` is out of range.
std::size_t format_csv_record(const TelemetryRecord& record, int axes,
                              std::span<char> out) noexcept;

/// Writes the header row and a newline.
void write_csv_header(std::ostream& out, int axes);
/// Writes one record as a line.
void write_csv_record(std::ostream& out, const TelemetryRecord& record, int axes);

}  // namespace hapticd::servo
