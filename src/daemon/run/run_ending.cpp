#include "run/run_ending.hpp"

#include <cstring>
#include <ostream>

#include "hapticd/daemon/journal.hpp"
#include "hapticd/servo/faults.hpp"
#include "run/realtime_advice.hpp"
#include "run/run_messages.hpp"

namespace hapticd::daemon {
namespace {

// The exit: an error, a fault (with the faults that ended it), the end of the duration, or a
// stop.
int exit_of(const Config& config, const ServoEnd& end, const servo::Summary& summary,
            RunContext& context, std::ostream& log) {
    int code = kExitOk;
    if (!end.error.empty()) {
        log << priority::err << "hapticd: the servo loop could not run: " << end.error << "\n";
        context.exit = "error";
        // Real time that this host refuses and the config demands (enforce) is refused again
        // at every start, as a bad config is: exit 2, which the unit does not restart.
        const bool realtime_refused = config.servo.realtime == servo::RealtimeMode::enforce &&
                                      !context.realtime.all_granted();
        code = realtime_refused ? kExitBadInput : kExitFault;
    } else if (end.exit == servo::RunExit::fault) {
        context.exit = "fault";
        code = kExitFault;
        if (end.link_gave_up) {
            log << priority::err
                << "hapticd: the device did not come back within [safety] reconnect_timeout = "
                << config.safety.reconnect.timeout_s << " s; stopped on the fault, force zero "
                << "since the tick that saw it:";
        } else {
            log << priority::err << "hapticd: stopped on a fault, force zeroed in the same tick:";
        }
        for (const std::string& fault : summary.faults) log << " " << fault;
        log << "\n";
    } else if (end.faults != 0u) {
        // Stopped (duration or signal) while waiting for the device to come back, or, with
        // a control socket, for a reset.
        context.exit = "fault";
        code = kExitFault;
        log << priority::err << "hapticd: the run ended with "
            << (servo::only_link_faults(end.faults) ? "the link down (" : "faults latched (")
            << fault_names(end.faults) << "), force zero since the tick that saw it\n";
    } else if (end.exit == servo::RunExit::tick_limit || end.duration_ended) {
        context.exit = "duration";
    } else {
        context.exit = "stopped";
    }
    return code;
}

// What stopped the run, when a signal or the parent's lifeline did (not the duration).
void note_stop_cause(const RunOptions& options, const ServoEnd& end, RunContext& context,
                     std::ostream& log) {
    if (const int cause = options.stop_cause != nullptr ? options.stop_cause->load() : 0;
        cause != 0 && !end.duration_ended && end.exit != servo::RunExit::tick_limit) {
        const char* abbrev = cause > 0 ? sigabbrev_np(cause) : nullptr;
        context.stopped_by = cause == kStopByLifeline ? std::string("parent lifeline")
                             : abbrev != nullptr      ? "SIG" + std::string(abbrev)
                                                      : "signal " + std::to_string(cause);
        log << priority::notice << "hapticd: stopped by " << context.stopped_by
            << ": force zeroed, telemetry flushed, summary written\n";
    }
}

// What real time refused, when the watcher never said: the loop never ticked, or enforce
// refused.
void report_realtime_at_end(const servo::RealtimeRequest& realtime, const ServoEnd& end,
                            const RunContext& context, std::ostream& log) {
    if (!end.realtime_reported && end.error.empty()) {  // it never ticked
        report_realtime(realtime, context.realtime, log);
    } else if (!end.error.empty() && !context.realtime.all_granted()) {  // enforce refused
        log << priority::err << "hapticd: " << realtime_advice(realtime, context.realtime) << "\n";
    }
}

}  // namespace

std::string confirm_zero_force(device::Device& device) {
    switch (device.write(servo::Command{})) {
        case servo::IoResult::ok:
            return "zero";
        case servo::IoResult::timeout:
            return "zero, not confirmed: timeout";
        case servo::IoResult::disconnected:
            return "zero, not confirmed: disconnected";
        case servo::IoResult::error:
            return "zero, not confirmed: error";
    }
    return {};
}

int judge_run_end(const RunOptions& options, const Config& config,
                  const servo::RealtimeRequest& realtime, const ServoEnd& end,
                  const servo::Summary& summary, RunContext& context, std::ostream& log) {
    const int code = exit_of(config, end, summary, context, log);
    note_stop_cause(options, end, context, log);
    report_realtime_at_end(realtime, end, context, log);
    return code;
}

int check_outputs_whole(int code, bool summary_written, const servo::Summary& summary,
                        const RunContext& context, std::ostream& log) {
    // An output that is not whole is an exit status of its own, unless a fault (1) says more.
    // A client's recording counts too: it is the run's output as much as --log is.
    std::uint64_t recordings_not_whole = 0;
    for (const RecordedFile& file : context.recordings)
        recordings_not_whole += file.complete ? 0 : 1;
    if (code == kExitOk && recordings_not_whole > 0) {
        log << priority::err << "hapticd: " << recordings_not_whole << " of "
            << context.recordings.size()
            << " recordings of the control socket are incomplete (the summary's recordings say "
               "why); exit "
            << kExitOutput << "\n";
    }
    if (code == kExitOk && !context.flight_records_complete) {
        log << priority::err
            << "hapticd: a flight record could not be written (the journal says which, and "
               "why); exit "
            << kExitOutput << "\n";
    }
    if (code == kExitOk && (!context.telemetry_complete || !summary_written ||
                            recordings_not_whole > 0 || !context.flight_records_complete)) {
        if (!context.telemetry_complete) {
            log << priority::err << "hapticd: the telemetry log " << context.telemetry_log
                << " is incomplete: " << context.telemetry_records_written << " of "
                << context.telemetry_records << " records written"
                << (summary.telemetry_dropped > 0
                        ? ", " + std::to_string(summary.telemetry_dropped) + " dropped"
                        : std::string())
                << "; exit " << kExitOutput << "\n";
        }
        return kExitOutput;
    }
    return code;
}

}  // namespace hapticd::daemon
