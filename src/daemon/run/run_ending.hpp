// The end of a run, once the servo thread has joined (docs/architecture.md §4.7, §7.2): the
// zero force confirmed for the summary's final_command, the run's exit and exit code with
// the lines that say why, and exit 3 for an output that is not whole.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/run.hpp"
#include "hapticd/device/device.hpp"
#include "hapticd/servo/realtime.hpp"
#include "hapticd/servo/servo_loop.hpp"
#include "hapticd/servo/summary.hpp"
#include "outputs/summary_json.hpp"

namespace hapticd::daemon {

/// How the servo thread's run ended, read once it has joined.
struct ServoEnd {
    servo::RunExit exit = servo::RunExit::stopped;  ///< what ServoLoop::run returned
    std::string error;                              ///< what it threw instead; empty: it returned
    std::uint32_t faults = 0;                       ///< latched at the end (ServoLoop::faults)
    bool link_gave_up = false;       ///< the device did not come back in time (LinkRecovery)
    bool duration_ended = false;     ///< the watcher ended a real-time --duration
    bool realtime_reported = false;  ///< the watcher reported real time (the loop ticked)
};

/// A disabled zero command once more, after the loop's own, to learn whether it landed:
/// "zero", or "zero, not confirmed: REASON".
std::string confirm_zero_force(device::Device& device);

/// The run's exit code, its exit and what stopped it in `context`, and the lines that say so
/// on `log`: why the loop could not run or stopped on a fault (exit 1), the stop signal, and
/// what real time refused when the watcher never said.
int judge_run_end(const RunOptions& options, const Config& config,
                  const servo::RealtimeRequest& realtime, const ServoEnd& end,
                  const servo::Summary& summary, RunContext& context, std::ostream& log);

/// `code`, or exit 3 when it is 0 and an output is not whole (the telemetry log, or the
/// summary when `summary_written` is false), saying which records the log is missing.
int check_outputs_whole(int code, bool summary_written, const servo::Summary& summary,
                        const RunContext& context, std::ostream& log);

}  // namespace hapticd::daemon
