// One run of the servo loop, supervised: the loop on its own thread (real time where it may),
// the telemetry writer on another, and on the calling thread the duration, the status line
// and the fault lines; then the zero force, the run's exit and the summary
// (docs/architecture.md §6). A template over the environment, as ServoLoop is, so that the
// tick calls it directly.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <iomanip>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <sstream>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include "control_requests.hpp"
#include "flight_file.hpp"
#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/control_server.hpp"
#include "hapticd/daemon/identify_session.hpp"
#include "hapticd/daemon/journal.hpp"
#include "hapticd/daemon/realtime_advice.hpp"
#include "hapticd/daemon/run.hpp"
#include "hapticd/daemon/scene_switch.hpp"
#include "hapticd/daemon/service_notifier.hpp"
#include "hapticd/daemon/startup_check.hpp"
#include "hapticd/daemon/summary_json.hpp"
#include "hapticd/daemon/telemetry_writer.hpp"
#include "hapticd/device/device.hpp"
#include "hapticd/servo/faults.hpp"
#include "hapticd/servo/flight_recorder.hpp"
#include "hapticd/servo/servo_loop.hpp"
#include "run_messages.hpp"
#include "run_outputs.hpp"

namespace hapticd::daemon {

// Telemetry ring: 65 s of records at 1 kHz in real time, so that a stalled disk loses
// nothing for a minute; a lockstep run waits for the writer instead (backpressure).
inline constexpr std::size_t kRealtimeRingRecords = std::size_t{1} << 16;
inline constexpr std::size_t kLockstepRingRecords = std::size_t{1} << 14;

/// The servo loop as the control socket sees it: lock-free calls only (servo_loop.hpp).
template <typename Loop>
class LoopControl final : public control::ServoControl {
  public:
    LoopControl(Loop& loop, const servo::CouplingGains& gains) : loop_(loop), gains_(gains) {}
    servo::StatusSnapshot status() const noexcept override { return loop_.status(); }
    void arm() noexcept override { loop_.arm(); }
    void disarm() noexcept override { loop_.disarm(); }
    void reset() noexcept override {
        resets_requested_.fetch_add(1, std::memory_order_acq_rel);
        loop_.request_fault_reset();
    }
    std::uint64_t resets_requested() const noexcept override {
        return resets_requested_.load(std::memory_order_acquire);
    }
    void set_coupling(const servo::CouplingGains& gains) noexcept override {
        const std::lock_guard lock(gains_mutex_);  // two non-real-time threads; never the servo's
        gains_ = gains;
        loop_.request_coupling(gains);
    }
    servo::CouplingGains coupling() const noexcept override {
        const std::lock_guard lock(gains_mutex_);
        return gains_;
    }

  private:
    Loop& loop_;
    std::atomic<std::uint64_t> resets_requested_{0};
    mutable std::mutex gains_mutex_;
    servo::CouplingGains gains_;  // the last accepted: the servo may not have taken it yet
};

/// The start-up check of `config` with the coupling `gains` in place of its own, against the
/// scene in force (`scenes`; without, the config's): what a control socket's coupling request
/// must pass ([coupling] check, docs/control.md).
inline control::CouplingVerdict check_new_coupling(const Config& config, const SceneSwitch* scenes,
                                                   const servo::CouplingGains& gains) {
    try {
        if (scenes != nullptr) {
            const StartupCheck check = scenes->check_coupling(gains);
            return {.accepted = check.skipped || check.passed, .verdict = check.describe()};
        }
        Config candidate = config;
        candidate.coupling.stiffness_n_per_m = gains.stiffness_n_per_m;
        candidate.coupling.damping_n_s_per_m = gains.damping_n_s_per_m;
        const StartupCheck check = check_coupling_at_startup(candidate);
        return {.accepted = check.skipped || check.passed, .verdict = check.describe()};
    } catch (const std::exception& e) {
        return {.accepted = false, .verdict = e.what()};
    }
}

/// The scene a run renders (`environment` of run_loop is one of its environments), for the
/// control socket's scene_load; an identification run has none.
struct RunScene {
    const env::Scene* scene = nullptr;
    std::string source;  ///< its file, or "<embedded demo-wall scene>"
};

/// The environment of `scene` that a loop over `Environment` renders; null for the other
/// causality.
template <typename Environment>
Environment* environment_of(env::Scene& scene) noexcept {
    if constexpr (std::is_same_v<Environment, env::ImpedanceEnvironment>) {
        return scene.impedance.get();
    } else if constexpr (std::is_same_v<Environment, env::AdmittanceEnvironment>) {
        return scene.admittance.get();
    } else {
        return nullptr;
    }
}

/// Stops the control socket's thread when it goes out of scope: before the loop that its
/// handler reaches is destroyed, on every path.
struct ControlStopper {
    control::ControlServer* server;
    ~ControlStopper() {
        if (server != nullptr) server->stop();
    }
};

/// Stops and joins the servo thread when it goes out of scope, if nobody has.
struct ServoJoiner {
    std::thread& thread;
    std::atomic<bool>& stop;
    ~ServoJoiner() {
        if (thread.joinable()) {
            stop.store(true, std::memory_order_release);
            thread.join();
        }
    }
};

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
    const device::DeviceInfo info = device.info();

    // From here on the outputs are this run's: emptied now (an old summary must not outlive
    // a run that is killed), kept whatever happens.
    outputs.log.begin();  // throws OutputError
    outputs.summary.begin();
    std::unique_ptr<servo::TelemetryRing> ring;
    std::unique_ptr<TelemetryWriter> writer;
    if (options.log_path) {
        ring = std::make_unique<servo::TelemetryRing>(info.lockstep ? kLockstepRingRecords
                                                                    : kRealtimeRingRecords);
        // Real time: also fdatasync() each second, bounding what a power cut loses; a lockstep
        // run (a test, a simulation) waits for its writer, so it does not sync.
        writer = std::make_unique<TelemetryWriter>(
            *ring, outputs.log.release(), *options.log_path, info.axes,
            info.lockstep ? std::chrono::milliseconds{0} : std::chrono::milliseconds{1000});
        writer->start();
    }

    std::uint64_t max_ticks = 0;
    if (options.duration_s && info.lockstep) {
        max_ticks =
            static_cast<std::uint64_t>(std::llround(*options.duration_s * config.servo.rate_hz));
    }

    servo::ServoLoop<device::Device, Environment> loop(device, environment, servo_config,
                                                       ring.get());
    // The flight recorder: the last kFlightRecordS of ticks, written beside the run's files
    // on every new fault (flight_file.hpp), log or no log.
    servo::FlightRecorder recorder(static_cast<std::size_t>(
        std::clamp(std::ceil(kFlightRecordS * config.servo.rate_hz), 1.0, 1e6)));
    loop.attach_flight_recorder(&recorder);
    const std::optional<std::string> flight_dir = flight_directory(options);
    const auto write_flight_record = [&] {
        if (!recorder.frozen()) return;
        const std::vector<servo::TelemetryRecord> records = recorder.frozen_records();
        recorder.thaw();
        if (records.empty()) return;
        const servo::TelemetryRecord& last = records.back();
        std::ostringstream what;
        what << std::fixed << std::setprecision(3) << "hapticd: flight recorder: the last "
             << records.size() << " ticks to fault " << fault_names(last.faults) << " at t "
             << last.t_s << " s";
        if (!flight_dir) {
            log << priority::notice << what.str()
                << " not written: no --log, --summary FILE or LOGS_DIRECTORY to put them beside\n";
            return;
        }
        const FlightFile file =
            write_flight_file(*flight_dir, context.stamp.start_name, records, info.axes);
        if (file.error.empty()) {
            context.flight_records.push_back(file.path);
            log << priority::notice << what.str() << ": " << file.path << "\n" << std::flush;
        } else {
            log << priority::err << what.str() << " not written: " << file.error << "\n";
        }
    };
    // The control socket (docs/control.md), on its own thread from here to the servo
    // thread's end; the rate it reports is the watcher's, over the last second.
    std::atomic<double> measured_rate_hz{0.0};
    LoopControl control_port(loop, servo_config.coupling);
    // scene_load (scene_switch.hpp): a scene of the run's causality, only with a control socket.
    std::optional<SceneSwitch> scenes;
    if (outputs.control && scene.scene != nullptr) {
        scenes.emplace(
            config, *scene.scene, scene.source,
            SceneLoopPort{.offer =
                              [&loop](env::Scene& next) {
                                  Environment* const e = environment_of<Environment>(next);
                                  return e != nullptr && loop.offer_environment(*e);
                              },
                          .taken = [&loop] { return loop.offer_taken(); },
                          .withdraw =
                              [&loop](env::Scene& next) {
                                  Environment* const e = environment_of<Environment>(next);
                                  return e != nullptr && loop.withdraw_environment(*e);
                              }});
    }
    control::RunFacts facts{
        .axes = info.axes,
        .rate_hz = config.servo.rate_hz,
        .device = device_line(info),
        .config_path =
            context.config_path.empty() ? std::string("(embedded default)") : context.config_path,
        .measured_rate_hz = &measured_rate_hz,
        .velocity_filter_hz = config.coupling.velocity_filter_hz,
        .coupling_enabled = config.coupling.enabled,
        .check_coupling =
            [&config, &scenes](const servo::CouplingGains& gains) {
                return check_new_coupling(config, scenes ? &*scenes : nullptr, gains);
            },
        .scenes = scenes ? &*scenes : nullptr};
    // record start/stop (recording.hpp): a ring for the run, only with a control socket.
    std::optional<Recording> recording;
    if (outputs.control) {
        recording.emplace(
            [&loop](servo::TelemetryRing* recording_ring) {
                loop.attach_recording(recording_ring);
            },
            [&loop] { return loop.status().tick; }, info.axes, info.lockstep);
        facts.recording = &*recording;
    }
    // identify (identify_session.hpp): the excitation played open loop on a disarmed run that
    // renders a scene, only with a control socket.
    std::optional<IdentifySession> identify;
    if (recording && scene.scene != nullptr) {
        identify.emplace(config, info, *recording,
                         IdentifyLoopPort{.play =
                                              [&loop](servo::OpenLoopSource& source) {
                                                  return loop.play_open_loop(source);
                                              },
                                          .idle = [&loop] { return loop.open_loop_idle(); },
                                          .disarm = [&loop] { loop.disarm(); },
                                          .status = [&loop] { return loop.status(); }},
                         flight_dir, context.stamp.start_name);
        facts.identify = &*identify;
    }
    const ControlStopper control_stopper{outputs.control.get()};
    if (outputs.control) {
        outputs.control->start(
            [&](const control::Request& request, const control::Peer& peer) {
                return control::answer(request, peer, control_port, facts);
            },
            [&] { return control::telemetry_event(control_port.status(), facts); });
        log << priority::info << "hapticd: control socket " << outputs.control->path() << "\n";
    }
    const auto drain_control_messages = [&] {
        if (!outputs.control) return;
        for (const std::string& line : outputs.control->take_messages()) {
            log << priority::info << "hapticd: " << line << "\n" << std::flush;
        }
    };
    auto rate_since = std::chrono::steady_clock::now();
    std::uint64_t rate_ticks_before = 0;

    // The servo thread reads `stop` itself, so a signal (or the parent's death) ends the run
    // at the next tick; this thread sets it too when the duration ends.
    std::atomic<bool>& stop_servo = stop;
    std::atomic<bool> servo_done{false};
    servo::RunExit run_exit = servo::RunExit::stopped;
    std::string servo_error;
    std::thread servo_thread([&] {
        try {
            run_exit = loop.run(stop_servo, max_ticks);
        } catch (const std::exception& e) {
            servo_error = e.what();
        }
        servo_done.store(true, std::memory_order_release);
    });
    // Should anything on this thread throw before the join below, the servo thread is stopped
    // and joined (a joinable std::thread's destructor would end the process with the force
    // held); the loop's destructor then writes zero force.
    const ServoJoiner servo_joiner{servo_thread, stop_servo};

    // This thread: signals, the duration and the status line.
    // --duration counts servo time: from the first tick, not from before the real-time set-up
    // (locking and prefaulting memory can take a tenth of a second).
    auto started = std::chrono::steady_clock::now();
    bool ticking = false;
    const auto status_every = std::chrono::duration<double>(options.status_interval_s);
    auto next_status =
        started + std::chrono::duration_cast<std::chrono::steady_clock::duration>(status_every);
    bool duration_ended = false;
    std::uint32_t logged_faults = 0;
    // systemd (service_notifier.hpp): READY=1 after the first good tick, STATUS= once a second
    // and on a change of faults, WATCHDOG=1 while the tick counter advances.
    ServiceNotifier notifier;
    const auto service_status_every = std::chrono::seconds(1);
    auto next_service_status = started;
    // What real time refused, reported once the servo thread has asked (before its first
    // tick, whose status this thread then sees): a warning with the remedy, and in STATUS=.
    std::optional<std::string> realtime_note;
    // The run's figures once a minute, for the journal (the status line is per second).
    const auto figures_every = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(options.figures_interval_s));
    auto next_figures = started + figures_every;
    servo::StatusSnapshot figures_before;
    while (!servo_done.load(std::memory_order_acquire)) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        const auto now = std::chrono::steady_clock::now();
        if (const servo::StatusSnapshot status = loop.status(); status.tick >= 1) {
            if (!realtime_note) {
                realtime_note = report_realtime(servo_config.realtime, loop.realtime_report(), log);
            }
            const std::string service_line =
                service_status(status, config.servo.rate_hz, *realtime_note);
            if (status.faults == 0u) notifier.ready(service_line);
            notifier.watch(status.tick, now);
            if (now >= next_service_status || status.faults != logged_faults) {
                notifier.status(service_line);
                next_service_status = now + service_status_every;
            }
        }
        drain_control_messages();
        if (identify) identify->poll(log);
        write_flight_record();
        if (ticking && now - rate_since >= std::chrono::seconds(1)) {
            const std::uint64_t ticks = loop.status().tick;
            measured_rate_hz.store(static_cast<double>(ticks - rate_ticks_before) /
                                   std::chrono::duration<double>(now - rate_since).count());
            rate_ticks_before = ticks;
            rate_since = now;
        }
        if (!ticking && loop.status().tick >= 1) {
            ticking = true;
            started =
                now - std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                          std::chrono::duration<double>(static_cast<double>(loop.status().tick) /
                                                        config.servo.rate_hz));
            next_status = started + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                        status_every);
            next_figures = started + figures_every;
            // The rate's first second starts here, not before the real-time set-up.
            rate_since = now;
            rate_ticks_before = loop.status().tick;
        }
        if (const servo::StatusSnapshot status = loop.status(); status.faults != logged_faults) {
            if ((status.faults & ~logged_faults) != 0u || status.faults == 0u) {
                log << ((status.faults & ~logged_faults) != 0u ? priority::warning
                                                               : priority::notice)
                    << fault_change_line(logged_faults, status, config) << "\n"
                    << std::flush;
            }
            logged_faults = status.faults;
        }
        if (options.duration_s && !info.lockstep &&
            now - started >= std::chrono::duration<double>(*options.duration_s)) {
            duration_ended = true;
            stop_servo.store(true, std::memory_order_release);
        }
        if (options.figures_interval_s > 0.0 && now >= next_figures) {
            const servo::StatusSnapshot status = loop.status();
            log << priority::info
                << figures_line(status, figures_before,
                                std::chrono::duration<double>(figures_every).count())
                << "\n"
                << std::flush;
            figures_before = status;
            next_figures += figures_every;
        }
        if (options.status_interval_s > 0.0 && now >= next_status) {
            log << status_line(loop.status(), info.axes) << "\n" << std::flush;
            next_status +=
                std::chrono::duration_cast<std::chrono::steady_clock::duration>(status_every);
        }
    }
    servo_thread.join();
    if (outputs.control) outputs.control->stop();
    drain_control_messages();
    if (identify) identify->finish_at_exit(log);
    if (recording) {  // a recording still running ends with the run, whole
        if (const std::optional<RecordingResult> ended = recording->finish_at_exit()) {
            log << (ended->ok ? priority::notice : priority::err) << "hapticd: "
                << (ended->ok ? ended->message + ", at the end of the run"
                              : "recording " + ended->path + ": " + ended->message)
                << "\n";
        }
        for (const RecordingResult& closed : recording->closed()) {
            context.recordings.push_back(
                {.path = closed.path, .records = closed.records, .dropped = closed.dropped});
        }
    }
    if (identify) {
        for (const IdentifyProgress& ended : identify->ended()) {
            context.identify_runs.push_back(
                {.path = ended.path, .outcome = ended.outcome, .complete = ended.complete});
        }
    }
    write_flight_record();  // the fault that ended the run
    loop.write_zero_force();
    // Once more, to know that it landed: the summary's final_command.
    switch (device.write(servo::Command{})) {
        case servo::IoResult::ok:
            context.final_command = "zero";
            break;
        case servo::IoResult::timeout:
            context.final_command = "zero, not confirmed: timeout";
            break;
        case servo::IoResult::disconnected:
            context.final_command = "zero, not confirmed: disconnected";
            break;
        case servo::IoResult::error:
            context.final_command = "zero, not confirmed: error";
            break;
    }

    if (writer) {
        try {
            writer->finish();
        } catch (const std::exception& e) {
            log << priority::err << "hapticd: " << e.what() << "\n";
        }
        context.telemetry_log = *options.log_path;
        context.telemetry_records = writer->records_taken();
        context.telemetry_records_written = writer->records_written();
        context.telemetry_complete = writer->complete() && ring->dropped() == 0 &&
                                     writer->records_written() == writer->records_taken();
    }

    const servo::Summary summary = loop.summary();
    if (scenes) context.scene = scenes->in_force().name;  // the last loaded, if any was
    context.final_state = std::string(servo::servo_state_name(loop.status().state));
    context.realtime = loop.realtime_report();
    context.run_time_s =
        info.lockstep
            ? static_cast<double>(summary.ticks) / config.servo.rate_hz
            : std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    int code = kExitOk;
    if (!servo_error.empty()) {
        log << priority::err << "hapticd: the servo loop could not run: " << servo_error << "\n";
        context.exit = "error";
        code = kExitFault;
    } else if (run_exit == servo::RunExit::fault) {
        context.exit = "fault";
        code = kExitFault;
        if (loop.link_recovery().gave_up()) {
            log << priority::err
                << "hapticd: the device did not come back within [safety] reconnect_timeout = "
                << config.safety.reconnect_timeout_s << " s; stopped on the fault, force zero "
                << "since the tick that saw it:";
        } else {
            log << priority::err << "hapticd: stopped on a fault, force zeroed in the same tick:";
        }
        for (const std::string& fault : summary.faults) log << " " << fault;
        log << "\n";
    } else if (loop.faults() != 0u) {
        // Stopped (duration or signal) while waiting for the device to come back, or, with
        // a control socket, for a reset.
        context.exit = "fault";
        code = kExitFault;
        log << priority::err << "hapticd: the run ended with "
            << (servo::only_link_faults(loop.faults()) ? "the link down (" : "faults latched (")
            << fault_names(loop.faults()) << "), force zero since the tick that saw it\n";
    } else if (run_exit == servo::RunExit::tick_limit || duration_ended) {
        context.exit = "duration";
    } else {
        context.exit = "stopped";
    }
    if (const int cause = options.stop_cause != nullptr ? options.stop_cause->load() : 0;
        cause != 0 && !duration_ended && run_exit != servo::RunExit::tick_limit) {
        const char* abbrev = cause > 0 ? sigabbrev_np(cause) : nullptr;
        context.stopped_by = cause == kStopByLifeline ? std::string("parent lifeline")
                             : abbrev != nullptr      ? "SIG" + std::string(abbrev)
                                                      : "signal " + std::to_string(cause);
        log << priority::notice << "hapticd: stopped by " << context.stopped_by
            << ": force zeroed, telemetry flushed, summary written\n";
    }
    if (!realtime_note && servo_error.empty()) {  // it never ticked
        report_realtime(servo_config.realtime, context.realtime, log);
    } else if (!servo_error.empty() && !context.realtime.all_granted()) {  // enforce refused
        log << priority::err
            << "hapticd: " << realtime_advice(servo_config.realtime, context.realtime) << "\n";
    }
    after_run(code, context);
    notifier.stopping("stopping: " + context.exit +
                      (context.stopped_by.empty() ? "" : " (" + context.stopped_by + ")"));
    const bool summary_written = write_summary(options, outputs, summary, context, out, log);
    // An output that is not whole is an exit status of its own, unless a fault (1) says more.
    if (code == kExitOk && (!context.telemetry_complete || !summary_written)) {
        if (!context.telemetry_complete) {
            log << priority::err << "hapticd: the telemetry log " << context.telemetry_log
                << " is incomplete: " << context.telemetry_records_written << " of "
                << context.telemetry_records << " records written"
                << (summary.telemetry_dropped > 0
                        ? ", " + std::to_string(summary.telemetry_dropped) + " dropped"
                        : std::string())
                << "; exit " << kExitOutput << "\n";
        }
        code = kExitOutput;
    }
    return code;
}

}  // namespace hapticd::daemon
