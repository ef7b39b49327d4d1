// hapticd's run: config -> start-up stability check -> scene -> device plugin -> the servo
// loop on its own thread, the telemetry writer on another, a status line each second on
// this one, and the summary at the end. With --identify: config -> device plugin -> the
// excitation (env/excitation.hpp) open loop in place of the scene, logged. Glue only
// (docs/architecture.md §2.8): every piece it wires is a library of its own layer.
#pragma once

#include <atomic>
#include <iosfwd>
#include <optional>
#include <string>

#include "hapticd/daemon/exit_code.hpp"

namespace hapticd::daemon {

/// The longest --duration, seconds.
inline constexpr double kMaxDurationS = 1e7;

struct RunOptions {
    std::optional<std::string> config_path;  ///< --config; none: the embedded default; "": error
    std::optional<double> duration_s;        ///< --duration; none: until SIGINT/SIGTERM
    /// --summary FILE, or "-" for standard output; `{start}` in FILE becomes the start time
    /// (run_stamp.hpp), as in log_path.
    std::optional<std::string> summary_path;
    std::optional<std::string> log_path;  ///< --log FILE: telemetry CSV
    /// --socket PATH: the control socket (docs/control.md); none: no socket. With one, a
    /// fault latches at zero force until `reset` instead of ending the run.
    std::optional<std::string> socket_path;
    bool lockstep = false;  ///< --lockstep: virtual time, as fast as it goes
    /// --identify: the excitation run (docs/daemon.md): the [identify] multisine on the
    /// handle, open loop, instead of the scene; needs log_path. Without duration_s it runs
    /// for the excitation (IdentifyPlan::duration_s).
    bool identify = false;
    double status_interval_s = 1.0;  ///< the live status line; 0: none
    /// The run's figures (state, ticks, rate, overruns, faults) on the log, for the journal
    /// of a service that prints no status line; 0: none.
    double figures_interval_s = 60.0;
    /// What set `stop`, for the summary's `stopped_by`: > 0 a signal number, kStopByLifeline
    /// the parent's lifeline (--parent-lifeline); null or 0: not known.
    const std::atomic<int>* stop_cause = nullptr;
};

inline constexpr int kStopByLifeline = -1;

/// Runs the daemon until `stop` is set (the signal watcher's flag: the servo thread reads it
/// at each tick), the duration ends (the run then sets `stop` itself) or a fault is latched.
/// Messages and the status line go to `log`; `--summary -` writes the JSON summary to `out`, and
/// without --summary a readable summary goes to `log`. Never throws: every error becomes a message
/// and an exit code, and the device is left at zero force on every path.
int run_daemon(const RunOptions& options, std::atomic<bool>& stop, std::ostream& out,
               std::ostream& log);

}  // namespace hapticd::daemon
