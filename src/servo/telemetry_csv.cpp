#include "hapticd/servo/telemetry_csv.hpp"

#include <charconv>
#include <ostream>
#include <stdexcept>

namespace hapticd::servo {

namespace {

// Per axis i: x{i}_m, v{i}_mps, xe{i}_m, f{i}_n, in the order of format_csv_record().
struct AxisColumn {
    const char* prefix;
    const char* unit;
};
constexpr AxisColumn kAxisColumns[] = {{"x", "_m"}, {"v", "_mps"}, {"xe", "_m"}, {"f", "_n"}};

// `tick_flags`, not `flags`: a pandas DataFrame's attribute of that name hides the column.
constexpr const char* kStatusColumns[] = {"status",          "tick_flags", "faults",   "state",
                                          "wake_latency_us", "compute_us", "energy_j", "mark"};

bool axes_in_range(int axes) noexcept { return axes >= 1 && axes <= kMaxAxes; }

// Appends to [cursor, end); on overflow sets cursor to nullptr.
class LineBuilder {
  public:
    LineBuilder(char* begin, char* end) : cursor_(begin), end_(end) {}

    template <typename Number>
    void number(Number value) noexcept {
        if (cursor_ == nullptr) return;
        const auto [ptr, ec] = std::to_chars(cursor_, end_, value);
        cursor_ = ec == std::errc{} ? ptr : nullptr;
    }

    void character(char c) noexcept {
        if (cursor_ == nullptr) return;
        if (cursor_ == end_) {
            cursor_ = nullptr;
            return;
        }
        *cursor_++ = c;
    }

    char* cursor() const noexcept { return cursor_; }

  private:
    char* cursor_;
    char* end_;
};

}  // namespace

std::string csv_header(int axes) {
    if (!axes_in_range(axes)) {
        throw std::invalid_argument("telemetry csv: axes must be in 1.." +
                                    std::to_string(kMaxAxes) + ", got " + std::to_string(axes));
    }
    std::string header = "tick,t_s,unix_time_s";
    for (int i = 0; i < axes; ++i) {
        const std::string axis = std::to_string(i);
        for (const auto& [prefix, unit] : kAxisColumns) {
            header += ',';
            header += prefix;
            header += axis;
            header += unit;
        }
    }
    for (const char* column : kStatusColumns) {
        header += ',';
        header += column;
    }
    return header;
}

std::size_t format_csv_record(const TelemetryRecord& record, int axes,
                              std::span<char> out) noexcept {
    if (!axes_in_range(axes)) return 0;
    LineBuilder line(out.data(), out.data() + out.size());
    line.number(record.tick);
    line.character(',');
    line.number(record.t_s);
    line.character(',');
    line.number(record.unix_time_s);
    for (int i = 0; i < axes; ++i) {
        for (double value : {record.x_m[i], record.v_mps[i], record.xe_m[i], record.f_n[i]}) {
            line.character(',');
            line.number(value);
        }
    }
    for (std::uint32_t value : {record.status, record.flags, record.faults, record.state}) {
        line.character(',');
        line.number(value);
    }
    for (double value : {record.wake_latency_us, record.compute_us, record.energy_j}) {
        line.character(',');
        line.number(value);
    }
    line.character(',');
    line.number(record.mark);
    line.character('\n');
    return line.cursor() == nullptr ? 0 : static_cast<std::size_t>(line.cursor() - out.data());
}

void write_csv_header(std::ostream& out, int axes) { out << csv_header(axes) << '\n'; }

void write_csv_record(std::ostream& out, const TelemetryRecord& record, int axes) {
    char buffer[kMaxCsvLineChars];
    const std::size_t length = format_csv_record(record, axes, buffer);
    if (length == 0) {
        throw std::invalid_argument("telemetry csv: axes must be in 1.." +
                                    std::to_string(kMaxAxes) + ", got " + std::to_string(axes));
    }
    out.write(buffer, static_cast<std::streamsize>(length));
}

}  // namespace hapticd::servo
