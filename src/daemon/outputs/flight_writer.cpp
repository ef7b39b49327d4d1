#include "outputs/flight_writer.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <vector>

#include "hapticd/daemon/journal.hpp"
#include "hapticd/servo/telemetry.hpp"
#include "outputs/flight_file.hpp"
#include "run/run_messages.hpp"

namespace hapticd::daemon {

FlightWriter::FlightWriter(const OutputsDirectory* directory, double rate_hz, int axes)
    : recorder_(
          static_cast<std::size_t>(std::clamp(std::ceil(kFlightRecordS * rate_hz), 1.0, 1e6))),
      directory_(directory),
      axes_(axes) {}

void FlightWriter::write_frozen(RunContext& context, std::ostream& log) {
    if (!recorder_.frozen()) return;
    const std::vector<servo::TelemetryRecord> records = recorder_.frozen_records();
    recorder_.thaw();
    if (records.empty()) return;
    const servo::TelemetryRecord& last = records.back();
    std::ostringstream what;
    what << std::fixed << std::setprecision(3) << "hapticd: flight recorder: the last "
         << records.size() << " ticks to fault " << fault_names(last.faults) << " at t " << last.t_s
         << " s";
    if (directory_ == nullptr) {
        ++context.flight_records_not_written;
        log << priority::notice << what.str()
            << " not written: no --log, --summary FILE or LOGS_DIRECTORY to put them beside\n";
        return;
    }
    if (files_ >= kMaxFlightFilesPerRun || bytes_ >= kMaxFlightBytesPerRun) {
        ++context.flight_records_not_written;
        if (!told_cap_) {  // once: a fault loop must not flood the journal either
            told_cap_ = true;
            log << priority::warning << what.str() << " not written: the run's flight records "
                << "are capped at " << kMaxFlightFilesPerRun << " files and "
                << (kMaxFlightBytesPerRun >> 20U)
                << " MiB, and this run has written them (a fault that keeps returning?); "
                   "the summary counts the records not written (flight_records_not_written)\n";
        }
        return;
    }
    const FlightFile file =
        write_flight_file(*directory_, context.stamp.start_name, records, axes_);
    ++files_;
    bytes_ += file.bytes;
    if (file.error.empty()) {
        context.flight_records.push_back(file.path);
        log << priority::notice << what.str() << ": " << file.path << "\n" << std::flush;
    } else {
        ++context.flight_records_not_written;
        context.flight_records_complete = false;
        log << priority::err << what.str() << " not written: " << file.error << "\n";
    }
}

}  // namespace hapticd::daemon
