#include "run/run_telemetry.hpp"

#include <chrono>
#include <exception>
#include <ostream>

#include "hapticd/daemon/journal.hpp"

namespace hapticd::daemon {

RunTelemetry::RunTelemetry(const RunOptions& options, const device::DeviceInfo& info,
                           Outputs& outputs, std::string_view instance_name) {
    if (!options.log_path) return;
    ring_ = std::make_unique<servo::TelemetryRing>(info.lockstep ? kLockstepRingRecords
                                                                 : kRealtimeRingRecords);
    // Real time: also fdatasync() each second, bounding what a power cut loses; a lockstep
    // run (a test, a simulation) waits for its writer, so it does not sync.
    writer_ = std::make_unique<TelemetryWriter>(
        *ring_, outputs.log.release(), *options.log_path, info.axes,
        info.lockstep ? std::chrono::milliseconds{0} : std::chrono::milliseconds{1000},
        telemetry_preamble(instance_name));
    writer_->start();
}

void RunTelemetry::finish(const RunOptions& options, RunContext& context, std::ostream& log) {
    if (!writer_) return;
    try {
        writer_->finish();
    } catch (const std::exception& e) {
        log << priority::err << "hapticd: " << e.what() << "\n";
    }
    context.telemetry_log = *options.log_path;
    context.telemetry_records = writer_->records_taken();
    context.telemetry_records_written = writer_->records_written();
    context.telemetry_complete = writer_->complete() && ring_->dropped() == 0 &&
                                 writer_->records_written() == writer_->records_taken();
}

}  // namespace hapticd::daemon
