#include "hapticd/tune/telemetry_log.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <istream>
#include <map>
#include <sstream>

namespace hapticd::tune {
namespace {

std::string_view trim(std::string_view text) {
    const auto first = text.find_first_not_of(" \t\r");
    if (first == std::string_view::npos) return {};
    const auto last = text.find_last_not_of(" \t\r");
    return text.substr(first, last - first + 1);
}

/// Splits a line at commas (no quoting inside values: they are numbers).
void split_fields(std::string_view line, std::vector<std::string_view>& fields) {
    fields.clear();
    std::size_t start = 0;
    while (true) {
        const std::size_t comma = line.find(',', start);
        if (comma == std::string_view::npos) {
            fields.push_back(trim(line.substr(start)));
            return;
        }
        fields.push_back(trim(line.substr(start, comma - start)));
        start = comma + 1;
    }
}

std::string column_list(const std::vector<std::string>& columns) {
    std::string list;
    for (const std::string& name : columns) list += (list.empty() ? "" : ", ") + name;
    return list;
}

bool is_skipped(std::string_view line) {
    const std::string_view text = trim(line);
    return text.empty() || text.front() == '#';
}

/// The lines left in `in` (an upper bound of its rows), read ahead and rewound; 0 when the
/// stream cannot seek back (then the columns grow as they are read).
std::size_t lines_left(std::istream& in) {
    const std::istream::pos_type start = in.tellg();
    if (start == std::istream::pos_type(-1)) return 0;
    std::array<char, 1 << 16> buffer;
    std::size_t lines = 0;
    char last = '\n';
    while (in.read(buffer.data(), buffer.size()) || in.gcount() > 0) {
        const auto count = static_cast<std::size_t>(in.gcount());
        lines += static_cast<std::size_t>(std::count(buffer.data(), buffer.data() + count, '\n'));
        last = buffer[count - 1];
    }
    if (last != '\n') ++lines;  // a last line without its newline
    in.clear();
    in.seekg(start);
    return in ? lines : 0;
}

/// "# key: value" -> (key, value); false for any other comment.
bool preamble_entry(std::string_view line, std::pair<std::string, std::string>& entry) {
    std::string_view text = trim(line);
    if (!text.starts_with('#')) return false;
    text = trim(text.substr(1));
    const std::size_t colon = text.find(": ");
    if (colon == std::string_view::npos || colon == 0) return false;
    const std::string_view key = text.substr(0, colon);
    if (key.find_first_of(" \t") != std::string_view::npos) return false;
    entry = {std::string(key), std::string(trim(text.substr(colon + 2)))};
    return true;
}

/// "# mark N: text" -> (N, text); false for any other comment.
bool mark_line(std::string_view line, TelemetryMark& mark) {
    std::string_view text = trim(line);
    if (!text.starts_with("# mark ")) return false;
    text.remove_prefix(7);
    const char* const last = text.data() + text.size();
    const auto [end, error] = std::from_chars(text.data(), last, mark.number);
    const std::string_view rest(end, static_cast<std::size_t>(last - end));
    if (error != std::errc{} || end == text.data() || !rest.starts_with(':')) return false;
    mark.text = std::string(trim(rest.substr(1)));
    return true;
}

bool is_required(std::string_view name, int axes) {
    if (name == "t_s") return true;
    for (int axis = 0; axis < axes; ++axis) {
        const std::string i = std::to_string(axis);
        if (name == "x" + i + "_m" || name == "f" + i + "_n") return true;
    }
    return false;
}

}  // namespace

bool parse_log_number(std::string_view text, double& value) {
    if (!text.empty() && text.front() == '+') text.remove_prefix(1);
    if (text.empty()) return false;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    return error == std::errc{} && end == text.data() + text.size() && std::isfinite(value);
}

TelemetryLogOptions TelemetryLogOptions::identification() {
    TelemetryLogOptions options;
    // t_s, x{i}_m and f{i}_n are kept as required columns; these are the masks
    // identification_data.cpp reads.
    options.keep_column = [](std::string_view name) {
        return name == "status" || name == "tick_flags" || name == "faults";
    };
    options.row_lines = false;
    return options;
}

const std::vector<double>* TelemetryLog::column(std::string_view name) const {
    for (std::size_t c = 0; c < columns.size(); ++c) {
        if (columns[c] == name) return c < kept.size() && kept[c] ? &values[c] : nullptr;
    }
    return nullptr;
}

const std::string* TelemetryLog::preamble_value(std::string_view key) const {
    for (const auto& [name, value] : preamble) {
        if (name == key) return &value;
    }
    return nullptr;
}

std::size_t TelemetryLog::line(std::size_t row) const {
    if (row >= row_count) return 0;
    if (row < lines.size()) return lines[row];
    const auto run =
        std::upper_bound(line_runs.begin(), line_runs.end(), row,
                         [](std::size_t r, const auto& entry) { return r < entry.first; });
    if (run == line_runs.begin()) return 0;
    const auto& [first_row, first_line] = *std::prev(run);
    return first_line + (row - first_row);
}

std::string TelemetryLog::where(std::size_t row) const {
    return source + ":" + std::to_string(line(row));
}

std::string TelemetryLog::where(std::size_t row, std::string_view name) const {
    const auto it = std::find(columns.begin(), columns.end(), name);
    const std::size_t number = it == columns.end() ? 0 : (it - columns.begin()) + 1;
    return where(row) + ":" + std::to_string(number) + " (" + std::string(name) + ")";
}

std::size_t TelemetryLog::memory_bytes() const {
    std::size_t bytes = values.capacity() * sizeof(std::vector<double>);
    for (const std::vector<double>& column : values) bytes += column.capacity() * sizeof(double);
    bytes += lines.capacity() * sizeof(std::size_t);
    bytes += line_runs.capacity() * sizeof(line_runs[0]);
    return bytes;
}

TelemetryLog parse_telemetry_log(std::istream& in, const std::string& source,
                                 const TelemetryLogOptions& options) {
    TelemetryLog log;
    log.source = source;
    std::string line;
    std::size_t line_number = 0;
    std::vector<std::string_view> fields;
    const auto fail = [&](std::size_t at, const std::string& what) -> LogFormatError {
        return LogFormatError(source + ":" + std::to_string(at) + ": " + what);
    };

    // Header.
    std::size_t header_line = 0;
    while (std::getline(in, line)) {
        ++line_number;
        if (std::pair<std::string, std::string> entry; preamble_entry(line, entry)) {
            log.preamble.push_back(std::move(entry));
        }
        if (is_skipped(line)) continue;
        header_line = line_number;
        break;
    }
    if (header_line == 0) {
        throw LogFormatError(source + ": empty log: no header row (expected tick,t_s,x0_m,...)");
    }
    if (line.starts_with("\xEF\xBB\xBF")) line.erase(0, 3);  // a UTF-8 byte-order mark
    split_fields(line, fields);
    std::map<std::string, std::size_t> index;
    for (std::size_t c = 0; c < fields.size(); ++c) {
        std::string_view name = fields[c];
        if (name.size() >= 2 && name.front() == '"' && name.back() == '"') {
            name = trim(name.substr(1, name.size() - 2));
        }
        if (name.empty()) {
            throw LogFormatError(source + ":" + std::to_string(header_line) + ":" +
                                 std::to_string(c + 1) + ": empty column name in the header");
        }
        if (name == "flags") name = "tick_flags";  // its name before 0.1.0's preamble
        if (!index.emplace(std::string(name), c).second) {
            throw LogFormatError(source + ":" + std::to_string(header_line) + ":" +
                                 std::to_string(c + 1) + ": column " + std::string(name) +
                                 " appears twice in the header");
        }
        log.columns.emplace_back(name);
    }
    const auto missing = [&](const std::string& what) {
        return fail(header_line, what +
                                     " (docs/daemon.md, \"Telemetry\": tick, t_s, then per axis "
                                     "i x{i}_m, v{i}_mps, xe{i}_m, f{i}_n); the header has: " +
                                     column_list(log.columns));
    };
    if (!index.contains("t_s")) throw missing("no column t_s (time, s)");
    while (log.axes < 64) {
        const std::string axis = std::to_string(log.axes);
        const bool has_x = index.contains("x" + axis + "_m");
        const bool has_f = index.contains("f" + axis + "_n");
        if (!has_x && !has_f) break;
        if (!has_x) throw missing("column f" + axis + "_n has no matching x" + axis + "_m");
        if (!has_f) throw missing("column x" + axis + "_m has no matching f" + axis + "_n");
        ++log.axes;
    }
    if (log.axes == 0) throw missing("no axis columns: need at least x0_m and f0_n");

    // Rows: the kept columns reserved once for every line left (comments and blank lines
    // make it a slight overestimate), not grown by doubling.
    const std::size_t columns = log.columns.size();
    log.values.assign(columns, {});
    log.kept.assign(columns, false);
    std::vector<std::vector<double>*> kept(columns, nullptr);
    for (std::size_t c = 0; c < columns; ++c) {
        const std::string& name = log.columns[c];
        log.kept[c] =
            !options.keep_column || options.keep_column(name) || is_required(name, log.axes);
        if (log.kept[c]) kept[c] = &log.values[c];
    }
    const std::size_t expected_rows = lines_left(in);
    for (std::vector<double>* column : kept) {
        if (column != nullptr) column->reserve(expected_rows);
    }
    if (options.row_lines) log.lines.reserve(expected_rows);
    std::size_t previous_line = 0;
    while (std::getline(in, line)) {
        ++line_number;
        if (TelemetryMark mark; mark_line(line, mark)) {
            mark.row = log.row_count;
            log.marks.push_back(std::move(mark));
        }
        if (is_skipped(line)) continue;
        split_fields(line, fields);
        if (fields.size() != columns) {
            throw fail(line_number,
                       std::to_string(fields.size()) + " fields, but the header (line " +
                           std::to_string(header_line) + ") has " + std::to_string(columns));
        }
        for (std::size_t c = 0; c < columns; ++c) {
            double value = 0.0;
            if (!parse_log_number(fields[c], value)) {
                throw LogFormatError(source + ":" + std::to_string(line_number) + ":" +
                                     std::to_string(c + 1) + " (" + log.columns[c] + "): '" +
                                     std::string(fields[c]) + "' is not a finite number");
            }
            if (kept[c] != nullptr) kept[c]->push_back(value);
        }
        if (options.row_lines) log.lines.push_back(line_number);
        if (line_number != previous_line + 1)
            log.line_runs.emplace_back(log.row_count, line_number);
        previous_line = line_number;
        ++log.row_count;
    }
    if (in.bad())
        throw LogFormatError(source + ": read error after line " + std::to_string(line_number));
    log.line_runs.shrink_to_fit();
    return log;
}

TelemetryLog read_telemetry_log(const std::string& path, const TelemetryLogOptions& options) {
    std::ifstream file(path);
    if (!file) throw LogFormatError(path + ": cannot open the log");
    return parse_telemetry_log(file, path, options);
}

}  // namespace hapticd::tune
