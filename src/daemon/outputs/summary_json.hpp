// hapticd's --summary (docs/architecture.md §4.6, docs/daemon.md "Summary"): the servo loop's
// Summary as JSON, with its counters (ticks, overruns, rate_hz, wake_latency_us {p50, p99,
// p999, max}, tick_compute_us {p50, p99, max}, max_force_n, faults, telemetry_dropped, ...)
// and the context a lab needs to read it later: what ran, against what, how it ended and what
// real-time was granted.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "hapticd/daemon/startup_check.hpp"
#include "hapticd/servo/environment_port.hpp"
#include "hapticd/servo/realtime.hpp"
#include "hapticd/servo/summary.hpp"
#include "run/run_stamp.hpp"

namespace hapticd::daemon {

/// A file the control socket recorded to (recording.hpp), as it was closed.
struct RecordedFile {
    std::string path;
    std::uint64_t records = 0;  ///< whole lines after the header
    std::uint64_t dropped = 0;  ///< records the disk did not keep up with (0: lossless)
    bool complete = true;       ///< every tick from its first to its stop is in it
    std::string failure{};      ///< why not, when not
};

/// An excitation the control socket's identify played (excitation_session.hpp).
struct PlayedExcitation {
    std::string path;     ///< its log
    std::string outcome;  ///< the journal's line
    bool complete = false;
};

struct RunContext {
    RunStamp stamp;             ///< version, start time, host
    std::string name;           ///< [servo] name, "" when unset
    std::string config_source;  ///< file name or "<embedded default>"
    std::string config_path;    ///< the config's absolute path; empty: the embedded default
    std::string device;         ///< the plugin's name
    std::string scene;          ///< the scene's name
    std::string causality;      ///< "impedance" | "admittance"
    bool lockstep = false;
    std::string exit;  ///< "stopped" | "duration" | "fault" | "error"
    /// The servo's safety state at its last tick (servo_state.hpp): "disabled", "arming",
    /// "running" or "fault".
    std::string final_state;
    /// The last command written after the loop stopped: "zero" when the device accepted the
    /// disabled zero-force command, else "zero, not confirmed: REASON".
    std::string final_command;
    std::string stopped_by;  ///< "SIGTERM", "SIGHUP"..., or "parent lifeline"; empty: n/a
    /// Why the environment in force at the end failed (a plugin's world: fault
    /// `environment`); empty when it did not.
    std::string environment_failure;
    /// An [external] scene's world at the end (its port's report); `external` false: none.
    servo::EnvironmentPortReport external_world{};
    double run_time_s = 0.0;              ///< device time covered (virtual time in lockstep)
    std::string telemetry_log;            ///< the --log path; empty without one
    std::uint64_t telemetry_records = 0;  ///< records the run gave the writer; 0 without --log
    std::uint64_t telemetry_records_written = 0;  ///< of them, whole lines in the --log file
    bool telemetry_complete = true;  ///< every record is in the file (none failed, none dropped)
    /// The flight recorder's files, one per fault (docs/daemon.md, "The flight recorder").
    std::vector<std::string> flight_records{};
    /// Faults whose flight record was not written: past the run's cap, with nowhere to put
    /// it, or a failed write.
    std::uint64_t flight_records_not_written = 0;
    /// No flight record's write failed (the cap and a run with nowhere to put them are the
    /// run's policy, said in the journal; a failure is an output not whole: exit 3).
    bool flight_records_complete = true;
    /// The control socket's recordings (record_start and identify), in order, once closed.
    std::vector<RecordedFile> recordings{};
    /// The control socket's identify excitations, in order, as they ended.
    std::vector<PlayedExcitation> excitations{};
    StartupCheck check;
    servo::RealtimeReport realtime;
    /// Where hapticd's other threads run when [servo] cpu keeps them off the servo's CPU, or
    /// why it could not.
    servo::OtherThreadsCpus other_threads;
};

/// The summary as one JSON object (pretty-printed, two-space indent).
std::string summary_json(const servo::Summary& summary, const RunContext& context);

/// The same, as a few readable lines for the terminal.
std::string summary_text(const servo::Summary& summary, const RunContext& context);

}  // namespace hapticd::daemon
