// One run of the servo loop, supervised (docs/architecture.md §6, §7.2): run_loop sets up the
// run's outputs, the loop, its flight recorder and the control socket; runs the loop on its
// own thread (real time where it may), watched from this one until it ends; then zeroes the
// force and writes the run's exit and summary. Each step is a file of its own:
// run_telemetry (--log), flight_writer (the flight recorder, §7.12), socket/loop_ports.hpp and
// run_control (the control socket), servo_thread, run_watcher (the watching thread, §6.1)
// and run_ending (the exit). A template over the environment, as ServoLoop is, so that the
// tick calls it directly.
#pragma once

#include <atomic>
#include <memory>
#include <ostream>
#include <string>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/journal.hpp"
#include "hapticd/daemon/run.hpp"
#include "hapticd/device/device.hpp"
#include "hapticd/input/printable.hpp"
#include "hapticd/servo/servo_loop.hpp"
#include "hapticd/servo/servo_state.hpp"
#include "outputs/flight_writer.hpp"
#include "outputs/summary_json.hpp"
#include "run/run_control.hpp"
#include "run/run_ending.hpp"
#include "run/run_outputs.hpp"
#include "run/run_telemetry.hpp"
#include "run/run_watcher.hpp"
#include "run/servo_thread.hpp"
#include "socket/loop_ports.hpp"

namespace hapticd::daemon {

/// Nothing to add after the run.
struct NoAfterRun {
    void operator()(int& /*code*/, RunContext& /*context*/) const {}
};

/// The servo loop for one environment, on its own thread, watched from this one.
/// `after_run(code, context)` may amend the exit code and the context once the loop has
/// stopped, before the summary is written.
template <typename Environment, typename AfterRun = NoAfterRun>
int run_loop(const RunOptions& options, const Config& config,
             const servo::ServoConfig& servo_config, device::Device& device,
             Environment& environment, const RunScene& scene, RunContext& context, Outputs& outputs,
             std::atomic<bool>& stop, std::ostream& out, std::ostream& log,
             AfterRun after_run = {}) {
    using Loop = servo::ServoLoop<device::Device, Environment>;
    const device::DeviceInfo info = device.info();

    // Set up. From here on the outputs are this run's: emptied now (an old summary must not
    // outlive a run that is killed), kept whatever happens.
    outputs.log.begin();  // throws OutputError
    outputs.summary.begin();
    // The run's notes (marks, changes of gains and scene): the servo stamps their numbers on
    // its records, the writers put their text in the files (run_notes.hpp).
    RunNotes notes;
    RunTelemetry telemetry(
        options, info, outputs,
        telemetry_preamble(telemetry_header(config, context, info, servo_config.coupling,
                                            context.check.describe(), scene_in_force(scene))),
        &notes);
    Loop loop(device, environment, servo_config, telemetry.ring());
    // The directory of the flight records and a client's recordings, opened once.
    const std::unique_ptr<OutputsDirectory> outputs_directory =
        open_outputs_directory(options, log);
    FlightWriter flight(outputs_directory.get(), config.servo.rate_hz, info.axes);
    loop.attach_flight_recorder(&flight.recorder());
    // The control socket, on its own thread from here to the servo thread's end.
    InboxServoControl control_port(loop.inbox(), servo_config.coupling);
    RunControl control(config, info, scene, context,
                       socket_loop_ports<Environment>(loop.inbox(), control_port),
                       outputs.control.get(), outputs_directory.get(), log, &device, notes);

    // Run. The servo thread reads `stop` itself, so a signal (or the parent's death) ends the
    // run at the next tick; the watcher sets it too when the duration ends.
    ServoThread<Loop> servo(loop, stop, lockstep_tick_limit(options, info, config.servo.rate_hz));
    RunWatcher watcher(watched_loop(loop, servo), options, config, servo_config.realtime, info,
                       stop, control.measured_rate_hz(), log);
    watcher.watch([&] {
        control.poll(log);
        flight.write_frozen(context, log);
    });

    // Finish: the servo thread joined, the control socket's work in, the fault that ended the
    // run written, zero force and once more to know that it landed, the log drained.
    servo.join();
    if constexpr (requires { loop.environment().failure(); }) {
        context.environment_failure = std::string(loop.environment().failure());
        if (!context.environment_failure.empty()) {
            log << priority::err << "hapticd: the environment failed: "
                << input::printable(context.environment_failure) << "\n";
        }
    }
    if constexpr (requires { loop.environment().port_report(); }) {
        context.external_world = loop.environment().port_report();
        const servo::EnvironmentPortReport& w = context.external_world;
        if (w.external) {
            log << "hapticd: the external world: " << w.update << " updates, stale "
                << w.stale_episodes << " times, " << w.rejected_updates
                << " refused; the passivity controller on its port removed " << w.energy_removed_j
                << " J\n";
        }
    }
    control.finish(context, log);
    flight.write_frozen(context, log);
    loop.write_zero_force();
    context.final_command = confirm_zero_force(device);
    telemetry.finish(options, context, log);

    // The run's exit, then its summary.
    const servo::Summary summary = loop.summary();
    context.final_state = std::string(servo::servo_state_name(loop.inbox().status().state));
    context.realtime = loop.realtime_report();
    context.run_time_s = info.lockstep ? static_cast<double>(summary.ticks) / config.servo.rate_hz
                                       : watcher.seconds_since_start();
    const ServoEnd end{.exit = servo.run_exit(),
                       .error = servo.error(),
                       .faults = loop.faults(),
                       .link_gave_up = loop.link_recovery().gave_up(),
                       .duration_ended = watcher.duration_ended(),
                       .realtime_reported = watcher.realtime_reported()};
    int code = judge_run_end(options, config, servo_config.realtime, end, summary, context, log);
    after_run(code, context);
    watcher.stopping(context);
    const bool summary_written = write_summary(options, outputs, summary, context, out, log);
    return check_outputs_whole(code, summary_written, summary, context, log);
}

}  // namespace hapticd::daemon
