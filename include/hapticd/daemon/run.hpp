// hapticd's run: config -> start-up stability check -> scene -> device plugin -> the servo
// loop on its own thread, the telemetry writer on another, a status line each second on
// this one, and the summary at the end. With --identify: config -> device plugin -> the
// excitation (env/excitation.hpp) open loop in place of the scene, logged. Glue only (DESIGN.md):
// every piece it wires is a library of its own layer.
#pragma once

#include <atomic>
#include <iosfwd>
#include <optional>
#include <string>

namespace hapticd::daemon {

/// Exit codes of hapticd.
enum ExitCode : int {
    kExitOk = 0,        ///< stopped by a signal or at the end of --duration, no fault
    kExitFault = 1,     ///< the run ended on a latched fault, or the loop could not run;
                        ///< --identify: also when the handle left the workspace
    kExitBadInput = 2,  ///< usage, config, scene or device-table errors; gains refused
};

struct RunOptions {
    std::optional<std::string> config_path;   ///< --config; none: the embedded default
    std::optional<double> duration_s;         ///< --duration; none: until SIGINT/SIGTERM
    std::optional<std::string> summary_path;  ///< --summary FILE, or "-" for standard output
    std::optional<std::string> log_path;      ///< --log FILE: telemetry CSV
    bool lockstep = false;                    ///< --lockstep: virtual time, as fast as it goes
    /// --identify: the excitation run (docs/daemon.md): the [identify] multisine on the
    /// handle, open loop, instead of the scene; needs log_path. Without duration_s it runs
    /// for the excitation (IdentifyPlan::duration_s).
    bool identify = false;
    double status_interval_s = 1.0;  ///< the live status line; 0: none
};

/// Runs the daemon until `stop` is set (the signal handler's flag), the duration ends or a
/// fault is latched. Messages and the status line go to `log`; `--summary -` writes the
/// JSON summary to `out`, and without --summary a readable summary goes to `log`.
/// Never throws: every error becomes a message and an exit code, and the device is left at
/// zero force on every path.
int run_daemon(const RunOptions& options, const std::atomic<bool>& stop, std::ostream& out,
               std::ostream& log);

}  // namespace hapticd::daemon
