// libFuzzer target for the telemetry log reader that `haptic-tune identify` uses
// (tune::parse_telemetry_log, include/hapticd/tune/telemetry_log.hpp): any bytes are either
// a log whose columns all hold one finite value per row, with at least one axis, or a
// LogFormatError. Anything else is a finding. The seed corpus (fuzz/corpus/telemetry_log) is
// replayed in ctest under GCC (tests/fuzz_replay).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "fuzz_check.hpp"
#include "hapticd/tune/telemetry_log.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
    try {
        const hapticd::tune::TelemetryLog log = hapticd::tune::parse_telemetry_log(in, "fuzz.csv");
        FUZZ_CHECK(log.axes >= 1);
        FUZZ_CHECK(log.values.size() == log.columns.size());
        for (const auto& column : log.values) {
            FUZZ_CHECK(column.size() == log.rows());
            for (const double v : column) FUZZ_CHECK(std::isfinite(v));
        }
        FUZZ_CHECK(log.column("t_s") != nullptr && log.column("x0_m") != nullptr);
        // What identification reads: the same rows, lines and kept columns, nothing else.
        std::istringstream again(std::string(reinterpret_cast<const char*>(data), size));
        const hapticd::tune::TelemetryLog lean = hapticd::tune::parse_telemetry_log(
            again, "fuzz.csv", hapticd::tune::TelemetryLogOptions::identification());
        FUZZ_CHECK(lean.rows() == log.rows() && lean.lines.empty());
        for (std::size_t c = 0; c < log.columns.size(); ++c) {
            const std::vector<double>* kept = lean.column(log.columns[c]);
            FUZZ_CHECK(kept == nullptr ? lean.values[c].empty() : *kept == log.values[c]);
        }
        for (std::size_t row = 0; row < log.rows(); ++row) {
            FUZZ_CHECK(lean.line(row) == log.lines[row] && log.line(row) == log.lines[row]);
        }
    } catch (const hapticd::tune::LogFormatError&) {
        // refused, with a message
    }
    return 0;
}
