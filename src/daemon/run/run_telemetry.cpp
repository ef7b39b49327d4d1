#include "run/run_telemetry.hpp"

#include <chrono>
#include <exception>
#include <ostream>

#include "hapticd/daemon/journal.hpp"
#include "run/run_messages.hpp"
#include "run/run_stamp.hpp"

namespace hapticd::daemon {

TelemetryHeader telemetry_header(const Config& config, const RunContext& context,
                                 const device::DeviceInfo& info, const servo::CouplingGains& gains,
                                 std::string verdict, std::string scene) {
    const RunStamp now = stamp_run(std::chrono::system_clock::now());
    return {.version = now.version,
            .name = config.servo.name,
            .started_at = now.started_at,
            .host = now.host,
            .device = device_line(info),
            .config = context.config_path.empty() ? context.config_source : context.config_path,
            .config_sha256 = config.sha256,
            .rate_hz = config.servo.rate_hz,
            .coupling_enabled = config.coupling.enabled,
            .stiffness_n_per_m = gains.stiffness_n_per_m,
            .damping_n_s_per_m = gains.damping_n_s_per_m,
            .stability = std::move(verdict),
            .scene = std::move(scene)};
}

RunTelemetry::RunTelemetry(const RunOptions& options, const device::DeviceInfo& info,
                           Outputs& outputs, std::string_view preamble, const RunNotes* notes) {
    if (!options.log_path) return;
    ring_ = std::make_unique<servo::TelemetryRing>(info.lockstep ? kLockstepRingRecords
                                                                 : kRealtimeRingRecords);
    // Real time: also fdatasync() each second, bounding what a power cut loses; a lockstep
    // run (a test, a simulation) waits for its writer, so it does not sync.
    writer_ = std::make_unique<TelemetryWriter>(
        *ring_, outputs.log.release(), *options.log_path, info.axes,
        info.lockstep ? std::chrono::milliseconds{0} : std::chrono::milliseconds{1000}, preamble,
        notes);
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
