// Reading a telemetry log (DESIGN.md "Public names", docs/daemon.md "Telemetry"): CSV with a
// header row, `tick`, `t_s`, then per axis i from 0 `x{i}_m`, `v{i}_mps`, `xe{i}_m`,
// `f{i}_n`, then status columns. What haptic-tune identify reads.
//
// The reader takes the daemon's own logs (servo/telemetry_csv.hpp) and logs a user's script
// writes with the same names: only `t_s` and, per axis, `x{i}_m` and `f{i}_n` are required;
// the columns may come in any order; other columns (`tick`, `v{i}_mps`, `xe{i}_m`, the
// status columns, a script's own extras) are kept if present and otherwise ignored. Lines
// starting with '#' and blank lines are skipped; '\r' line ends and spaces around fields are
// accepted; header names may be quoted. Every value must be a finite number.
#pragma once

#include <cstddef>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace hapticd::tune {

/// The log cannot be read. what() names the file, the line and the column, e.g.
/// "run.csv:12:4 (x0_m): 'abc' is not a number".
class LogFormatError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// A telemetry log, column by column.
struct TelemetryLog {
    std::string source;                       ///< the file name, for messages
    std::vector<std::string> columns;         ///< header names in file order
    std::vector<std::vector<double>> values;  ///< values[column][row]
    std::vector<std::size_t> lines;           ///< 1-based file line of each row
    /// Axes with both x{i}_m and f{i}_n, for i = 0 .. axes-1 (at least 1).
    int axes = 0;

    std::size_t rows() const { return lines.size(); }
    /// The column's values, or nullptr when the log has no such column.
    const std::vector<double>* column(std::string_view name) const;
    /// "run.csv:12" for row `row`.
    std::string where(std::size_t row) const;
    /// "run.csv:12:4 (x0_m)" for row `row` of column `name`.
    std::string where(std::size_t row, std::string_view name) const;
};

/// Reads `path`. Throws LogFormatError naming the file (and line and column) when it cannot
/// be opened, a header name repeats, `t_s` or an axis's x{i}_m / f{i}_n is missing (the
/// message lists the columns found), a row has the wrong number of fields, or a value is
/// not a finite number.
TelemetryLog read_telemetry_log(const std::string& path);

/// The same from a stream; `source` names it in messages.
TelemetryLog parse_telemetry_log(std::istream& in, const std::string& source);

}  // namespace hapticd::tune
