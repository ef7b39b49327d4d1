#include "hapticd/tune/telemetry_log.hpp"

#include <algorithm>
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

/// Parses a finite double the way the daemon writes it (std::to_chars) or a script does
/// ("1e-5", "+0.25", "3."). Returns false for anything else.
bool parse_number(std::string_view text, double& value) {
    if (!text.empty() && text.front() == '+') text.remove_prefix(1);
    if (text.empty()) return false;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    return error == std::errc{} && end == text.data() + text.size() && std::isfinite(value);
}

}  // namespace

const std::vector<double>* TelemetryLog::column(std::string_view name) const {
    for (std::size_t c = 0; c < columns.size(); ++c) {
        if (columns[c] == name) return &values[c];
    }
    return nullptr;
}

std::string TelemetryLog::where(std::size_t row) const {
    return source + ":" + std::to_string(row < lines.size() ? lines[row] : 0);
}

std::string TelemetryLog::where(std::size_t row, std::string_view name) const {
    const auto it = std::find(columns.begin(), columns.end(), name);
    const std::size_t number = it == columns.end() ? 0 : (it - columns.begin()) + 1;
    return where(row) + ":" + std::to_string(number) + " (" + std::string(name) + ")";
}

TelemetryLog parse_telemetry_log(std::istream& in, const std::string& source) {
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
        if (!index.emplace(std::string(name), c).second) {
            throw LogFormatError(source + ":" + std::to_string(header_line) + ":" +
                                 std::to_string(c + 1) + ": column " + std::string(name) +
                                 " appears twice in the header");
        }
        log.columns.emplace_back(name);
    }
    const auto missing = [&](const std::string& what) {
        return fail(header_line, what +
                                     " (DESIGN.md: tick, t_s, then per axis i x{i}_m, "
                                     "v{i}_mps, xe{i}_m, f{i}_n); the header has: " +
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

    // Rows.
    log.values.assign(log.columns.size(), {});
    while (std::getline(in, line)) {
        ++line_number;
        if (is_skipped(line)) continue;
        split_fields(line, fields);
        if (fields.size() != log.columns.size()) {
            throw fail(line_number, std::to_string(fields.size()) +
                                        " fields, but the header (line " +
                                        std::to_string(header_line) + ") has " +
                                        std::to_string(log.columns.size()));
        }
        for (std::size_t c = 0; c < fields.size(); ++c) {
            double value = 0.0;
            if (!parse_number(fields[c], value)) {
                throw LogFormatError(source + ":" + std::to_string(line_number) + ":" +
                                     std::to_string(c + 1) + " (" + log.columns[c] + "): '" +
                                     std::string(fields[c]) + "' is not a finite number");
            }
            log.values[c].push_back(value);
        }
        log.lines.push_back(line_number);
    }
    if (in.bad())
        throw LogFormatError(source + ": read error after line " + std::to_string(line_number));
    return log;
}

TelemetryLog read_telemetry_log(const std::string& path) {
    std::ifstream file(path);
    if (!file) throw LogFormatError(path + ": cannot open the log");
    return parse_telemetry_log(file, path);
}

}  // namespace hapticd::tune
