// Reading a telemetry log (docs/architecture.md §4.5, docs/daemon.md "Telemetry"): CSV with a
// header row, `tick`, `t_s`, then per axis i from 0 `x{i}_m`, `v{i}_mps`, `xe{i}_m`,
// `f{i}_n`, then status columns. What haptic-tune identify reads.
//
// The reader takes the daemon's own logs (servo/telemetry_csv.hpp) and logs a user's script
// writes with the same names: only `t_s` and, per axis, `x{i}_m` and `f{i}_n` are required;
// the columns may come in any order; other columns (`tick`, `v{i}_mps`, `xe{i}_m`, the
// status columns, a script's own extras) are kept if present and otherwise ignored. Lines
// starting with '#' and blank lines are skipped as rows; the daemon's own are read: the
// preamble's "# key: value" lines before the header (TelemetryLog::preamble) and the
// "# mark N: text" lines among the rows (TelemetryLog::marks). '\r' line ends and spaces
// around fields are accepted; header names may be quoted. A column `flags` (the name of
// `tick_flags` in logs before the recordings' header, 0.1.0) reads as `tick_flags`. Every
// value must be a finite number.
//
// Memory: a kept column costs 8 bytes a row, reserved once from the number of lines left in
// the stream (when it can seek; otherwise it grows by doubling), and the per-row line
// numbers another 8. TelemetryLogOptions::identification() keeps only what identification
// reads (t_s, x{i}_m, f{i}_n, status, tick_flags, faults) and no per-row line vector: 48
// bytes a row for one axis, against about 83 bytes a row of the daemon's 15-column text and
// 128 for the default read (docs/identification.md "Memory").
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "hapticd/input/input_error.hpp"

namespace hapticd::tune {

/// The log cannot be read. what() names the file, the line and the column, e.g.
/// "run.csv:12:4 (x0_m): 'abc' is not a number".
class LogFormatError : public input::InputError {
  public:
    explicit LogFormatError(const std::string& message) : InputError(message) {}
};

/// What the reader keeps. The default keeps every column and every row's line number.
struct TelemetryLogOptions {
    /// Whether the values of column `name` are kept (unset: every column). The required
    /// columns (t_s, x{i}_m, f{i}_n) are always kept. A column that is not kept is still
    /// checked, a finite number on every row, but not stored: column() returns nullptr.
    std::function<bool(std::string_view name)> keep_column;
    /// Fill TelemetryLog::lines (8 bytes a row). where() names the line either way.
    bool row_lines = true;

    /// What identification reads (identification_data.cpp): t_s, x{i}_m, f{i}_n and the
    /// status, tick_flags and faults columns, without TelemetryLog::lines.
    static TelemetryLogOptions identification();
};

/// A "# mark N: text" line of the log (docs/daemon.md, "Telemetry": hapticctl mark, or a
/// change of the gains or the scene): the rows from `row` on carry N in their `mark` column.
struct TelemetryMark {
    std::uint32_t number = 0;
    std::size_t row = 0;  ///< the first row after the line
    std::string text;
};

/// A telemetry log, column by column.
struct TelemetryLog {
    std::string source;  ///< the file name, for messages
    /// The "# key: value" lines before the header, in order (the daemon's preamble: name,
    /// started, device, config, coupling, stability, scene; docs/daemon.md).
    std::vector<std::pair<std::string, std::string>> preamble;
    std::vector<TelemetryMark> marks;         ///< the "# mark N: text" lines, in order
    std::vector<std::string> columns;         ///< header names in file order
    std::vector<std::vector<double>> values;  ///< values[column][row]; empty if not kept
    std::vector<bool> kept;                   ///< kept[column]: values[column] holds it
    /// 1-based file line of each row; empty unless TelemetryLogOptions::row_lines.
    std::vector<std::size_t> lines;
    /// (first row, its file line) of each run of rows on consecutive lines: the line of
    /// every row in a few entries (a new run after each comment or blank line).
    std::vector<std::pair<std::size_t, std::size_t>> line_runs;
    std::size_t row_count = 0;
    /// Axes with both x{i}_m and f{i}_n, for i = 0 .. axes-1 (at least 1).
    int axes = 0;

    std::size_t rows() const { return row_count; }
    /// The preamble's value for `key`, or nullptr.
    const std::string* preamble_value(std::string_view key) const;
    /// The column's values, or nullptr when the log has no such column (or did not keep it).
    const std::vector<double>* column(std::string_view name) const;
    /// The 1-based file line of row `row` (0 past the last row).
    std::size_t line(std::size_t row) const;
    /// "run.csv:12" for row `row`.
    std::string where(std::size_t row) const;
    /// "run.csv:12:4 (x0_m)" for row `row` of column `name`.
    std::string where(std::size_t row, std::string_view name) const;
    /// Bytes held by the columns' values and the line bookkeeping (by capacity).
    std::size_t memory_bytes() const;
};

/// Parses a finite double the way the daemon writes it (std::to_chars) or a script does
/// ("1e-5", "+0.25", "3."): a field, or a number in the preamble or a mark. False for
/// anything else.
bool parse_log_number(std::string_view text, double& value);

/// Reads `path`. Throws LogFormatError naming the file (and line and column) when it cannot
/// be opened, a header name repeats, `t_s` or an axis's x{i}_m / f{i}_n is missing (the
/// message lists the columns found), a row has the wrong number of fields, or a value is
/// not a finite number.
TelemetryLog read_telemetry_log(const std::string& path, const TelemetryLogOptions& options = {});

/// The same from a stream; `source` names it in messages.
TelemetryLog parse_telemetry_log(std::istream& in, const std::string& source,
                                 const TelemetryLogOptions& options = {});

}  // namespace hapticd::tune
