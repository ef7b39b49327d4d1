// The daemon's telemetry CSV as the tests read it: through the product's own reader
// (tune::read_telemetry_log, the reader haptic-tune identify uses), so that a test reads a
// log exactly as the tools do and a format the reader refuses fails the test. column()
// throws for a missing column instead of returning null, so that a test names it.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "hapticd/tune/telemetry_log.hpp"

namespace hapticd::testing {

class TelemetryLog {
  public:
    TelemetryLog() = default;  ///< no log: zero rows
    explicit TelemetryLog(tune::TelemetryLog log) : log_(std::move(log)) {}

    const std::vector<double>& column(std::string_view name) const {
        const std::vector<double>* values = log_.column(name);
        if (values == nullptr) {
            throw std::runtime_error(log_.source + " has no column " + std::string(name));
        }
        return *values;
    }
    std::size_t rows() const { return log_.rows(); }
    /// The header's names, in file order.
    const std::vector<std::string>& columns() const { return log_.columns; }
    /// The preamble's value for `key` ("# key: value"); throws naming it when absent.
    const std::string& preamble(std::string_view key) const {
        const std::string* value = log_.preamble_value(key);
        if (value == nullptr) {
            throw std::runtime_error(log_.source + " has no preamble line " + std::string(key));
        }
        return *value;
    }
    /// The "# mark N: text" lines, in order.
    const std::vector<tune::TelemetryMark>& marks() const { return log_.marks; }

  private:
    tune::TelemetryLog log_;
};

/// Throws tune::LogFormatError naming the file and line when it is not a telemetry log.
inline TelemetryLog read_telemetry(const std::string& path) {
    return TelemetryLog(tune::read_telemetry_log(path));
}

}  // namespace hapticd::testing
