#include "hapticd/daemon/run.hpp"

#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <exception>
#include <fstream>
#include <iomanip>
#include <memory>
#include <ostream>
#include <sstream>
#include <thread>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/output_files.hpp"
#include "hapticd/daemon/servo_settings.hpp"
#include "hapticd/daemon/startup_check.hpp"
#include "hapticd/daemon/summary_json.hpp"
#include "hapticd/daemon/telemetry_writer.hpp"
#include "hapticd/device/plugin_loader.hpp"
#include "hapticd/env/excitation.hpp"
#include "hapticd/env/scene.hpp"
#include "hapticd/servo/faults.hpp"
#include "hapticd/servo/servo_loop.hpp"

namespace hapticd::daemon {
namespace {

using Clock = std::chrono::steady_clock;

// Telemetry ring: 65 s of records at 1 kHz in real time, so that a stalled disk loses
// nothing for a minute; a lockstep run waits for the writer instead (backpressure).
constexpr std::size_t kRealtimeRingRecords = std::size_t{1} << 16;
constexpr std::size_t kLockstepRingRecords = std::size_t{1} << 14;

/// Thrown by the set-up steps: the message is final, the code is the exit code.
struct StartError : std::runtime_error {
    StartError(int exit_code, const std::string& message)
        : std::runtime_error(message), code(exit_code) {}
    int code;
};

/// Leaves the device at zero force and closes it, whatever path leaves the run.
struct DeviceCloser {
    device::Device* device;
    ~DeviceCloser() {
        if (device != nullptr) device->close();
    }
};

std::string format_vector_mm(const std::array<double, servo::kMaxAxes>& v, int axes, double scale) {
    std::ostringstream out;
    out << std::fixed << std::setprecision(2) << "[";
    for (int i = 0; i < axes; ++i)
        out << (i == 0 ? "" : " ") << v[static_cast<std::size_t>(i)] * scale;
    out << "]";
    return out.str();
}

std::string status_line(const servo::StatusSnapshot& s, int axes) {
    std::ostringstream out;
    out << std::fixed << std::setprecision(2) << "hapticd: t " << s.t_s << " s  x "
        << format_vector_mm(s.x_m, axes, 1e3) << " mm  xe " << format_vector_mm(s.xe_m, axes, 1e3)
        << " mm  f " << format_vector_mm(s.f_n, axes, 1.0) << " N  ";
    if (!s.armed) {
        out << "disarmed";
    } else if (s.soft_start_scale < 1.0) {
        out << "soft start " << std::setprecision(0) << 100.0 * s.soft_start_scale << "%";
    } else {
        out << "armed";
    }
    out << "  overruns " << s.overruns;
    if (s.solver_not_converged > 0) out << "  solver failed " << s.solver_not_converged << " ticks";
    out << "  faults ";
    if (s.faults == 0u) out << "none";
    bool first = true;
    servo::for_each_fault(s.faults, [&](std::string_view name) {
        out << (first ? "" : ",") << name;
        first = false;
    });
    return out.str();
}

std::string fault_names(std::uint32_t faults) {
    std::string names;
    servo::for_each_fault(faults, [&](std::string_view name) {
        names += (names.empty() ? "" : ",") + std::string(name);
    });
    return names;
}

/// One line when the latched faults change (seen from the watcher: a change shorter than
/// its poll may go unlogged; the summary counts every one).
std::string fault_change_line(std::uint32_t before, const servo::StatusSnapshot& now,
                              const Config& config) {
    std::ostringstream out;
    out << std::fixed << std::setprecision(3) << "hapticd: t " << now.t_s
        << " s: " << std::defaultfloat;
    if (now.faults == 0u && !servo::only_link_faults(before)) {
        out << "fault latch cleared, force returns through the soft start";
        return out.str();
    }
    if (now.faults == 0u) {
        out << "link recovered (the device sent good samples for "
            << config.safety.reconnect_settle_s
            << " s): fault latch cleared, force returns through the soft start";
        return out.str();
    }
    out << "fault " << fault_names(now.faults & ~before) << ", force zeroed";
    if (config.safety.reconnect && servo::only_link_faults(now.faults)) {
        out << "; waiting for the device to come back";
        if (config.safety.reconnect_timeout_s > 0.0) {
            out << " (at most " << config.safety.reconnect_timeout_s
                << " s, [safety] reconnect_timeout)";
        }
    }
    return out.str();
}

Config load_any_config(const RunOptions& options) {
    try {
        return options.config_path ? load_config(*options.config_path) : default_config();
    } catch (const ConfigError& e) {
        throw StartError(kExitBadInput, e.what());
    }
}

env::Scene load_any_scene(const Config& config) {
    try {
        if (config.scene_file.empty()) {
            return env::parse_scene(default_scene_text(), "<embedded demo-wall scene>",
                                    config.device.axes);
        }
        return env::load_scene(config.scene_file, config.device.axes);
    } catch (const env::SceneError& e) {
        throw StartError(kExitBadInput, e.what());
    }
}

/// A scene the coupling cannot render is refused before the device opens: an object whose
/// stiffness is more negative than -k_c (a detent with a short period or a large peak force)
/// leaves the massless tool of (17) no stable balance, and the solve failed on every tick.
void check_scene_renderable(const env::Scene& scene, const Config& config,
                            const std::string& scene_source) {
    if (!config.coupling.enabled || !scene.most_negative_stiffness) return;
    const env::LinearObject& o = *scene.most_negative_stiffness;
    const double k_c = config.coupling.stiffness_n_per_m;
    if (k_c > -o.stiffness_n_per_m) return;
    std::ostringstream m;
    m << scene_source << ": " << o.source << " has a stiffness down to " << o.stiffness_n_per_m
      << " N/m between its notches (-2π peak_force/period), out of range for this coupling: "
      << "allowed > -k_c = " << -k_c << " N/m ([coupling] stiffness in " << config.source
      << "); lengthen its period or lower its peak_force";
    throw StartError(kExitBadInput, m.str());
}

StartupCheck run_startup_check(const Config& config, std::ostream& log) {
    StartupCheck check;
    try {
        check = check_coupling_at_startup(config);
    } catch (const ConfigError& e) {
        throw StartError(kExitBadInput, e.what());
    } catch (const std::invalid_argument& e) {  // a model's own range check
        throw StartError(kExitBadInput, config.source + ": " + e.what());
    }
    if (check.skipped) {
        log << "hapticd: WARNING: " << check.describe() << "\n";
        return check;
    }
    // The verdict's own line first, as haptic-tune check gives it for this config.
    log << "hapticd: " << (check.guarantee && check.passed ? "" : "WARNING: ") << check.describe()
        << "\n";
    if (!check.passed) {
        std::ostringstream m;
        m << config.source
          << ": refusing to arm: [coupling] stiffness = " << config.coupling.stiffness_n_per_m
          << " N/m, damping = " << config.coupling.damping_n_s_per_m << " N s/m";
        if (config.coupling.velocity_filter_hz > 0.0) {
            m << ", velocity_filter = " << config.coupling.velocity_filter_hz << " Hz";
        }
        m << " fail the " << check.model_name() << " model for [device.model] at "
          << config.servo.rate_hz << " Hz: worst margin " << check.worst_margin << " at "
          << check.worst_frequency_hz << " Hz";
        if (!check.worst_case.empty()) m << " (" << check.worst_case << ")";
        if (config.device.model_delay_s > 0.0) {
            m << " with a loop delay of " << config.device.model_delay_s << " s";
        }
        m << "; size them with haptic-tune size --mass " << *config.device.model_mass_kg
          << " --damping " << *config.device.model_damping_n_s_per_m << " --rate "
          << config.servo.rate_hz;
        if (config.device.model_delay_s > 0.0) m << " --delay " << config.device.model_delay_s;
        if (config.coupling.velocity_filter_hz > 0.0) {
            m << " --velocity-filter " << config.coupling.velocity_filter_hz;
        }
        if (config.operators) m << " --model exact --operator-class " << config.source;
        if (config.coupling.environments == EnvironmentClass::scene) {
            m << " --scene "
              << (config.scene_file.empty() ? std::string("config/scenes/demo-wall.toml")
                                            : config.scene_file);
        }
        m << " (the check holds for " << check.holds_for << ")";
        throw StartError(kExitBadInput, m.str());
    }
    return check;
}

/// "sim device, 3 axes, lockstep clock": what the run's first line says of the device.
std::string device_line(const device::DeviceInfo& info) {
    return info.name + " device, " + std::to_string(info.axes) +
           (info.axes == 1 ? " axis, " : " axes, ") + (info.lockstep ? "lockstep" : "real-time") +
           " clock";
}

device::DeviceHandle open_device(const Config& config, bool lockstep) {
    device::DeviceHandle device;
    try {
        device = device::load_device(config.device.plugin);
    } catch (const std::exception& e) {
        throw StartError(kExitBadInput, config.source + ": [device] plugin = \"" +
                                            config.device.plugin + "\": " + e.what());
    }
    device::DeviceConfig device_config;
    device_config.axes = config.device.axes;
    device_config.rate_hz = config.servo.rate_hz;
    device_config.lockstep = lockstep;
    device_config.plugin_table_toml = config.device.plugin_table_toml;
    device_config.plugin_table_path = config.device.plugin_table_path;
    device_config.source = config.source;
    try {
        device->open(device_config);
    } catch (const std::exception& e) {
        device->close();
        throw StartError(kExitBadInput, e.what());
    }
    return device;
}

/// The outputs, opened before the device (prepare_outputs()).
struct Outputs {
    OutputFile log;      ///< --log, locked; emptied when the run starts
    OutputFile summary;  ///< --summary FILE; emptied when the run starts
};

/// Writes the summary; false when --summary FILE could not be written whole (the JSON then
/// goes to `log`, so that it is not lost).
bool write_summary(const RunOptions& options, Outputs& outputs, const servo::Summary& summary,
                   const RunContext& context, std::ostream& out, std::ostream& log) {
    if (!options.summary_path) {
        log << summary_text(summary, context);
        return true;
    }
    const std::string json = summary_json(summary, context) + "\n";
    if (*options.summary_path == "-") {
        out << json << std::flush;
        return static_cast<bool>(out);
    }
    bool written = outputs.summary && write_all(outputs.summary.fd(), json);
    const int error = errno;
    if (outputs.summary && ::close(outputs.summary.release()) != 0 && written) written = false;
    if (!written) {
        log << "hapticd: --summary " << *options.summary_path
            << ": cannot write the summary: " << std::strerror(error) << "\n";
        log << json;
    }
    return written;
}

/// An empty path is an error, not "none".
void refuse_empty_paths(const RunOptions& options) {
    const auto empty = [](const std::optional<std::string>& path) { return path && path->empty(); };
    const char* option = empty(options.config_path)    ? "--config"
                         : empty(options.log_path)     ? "--log"
                         : empty(options.summary_path) ? "--summary"
                                                       : nullptr;
    if (option != nullptr) {
        throw StartError(kExitBadInput,
                         std::string(option) + " \"\": the path is empty; give a file name");
    }
}

/// --duration: finite, at least half a period (it is rounded to whole ticks: anything
/// shorter would be zero ticks, which means no limit), at most kMaxDurationS.
void check_duration(const RunOptions& options, double rate_hz) {
    if (!options.duration_s) return;
    const double d = *options.duration_s;
    const double shortest = 0.5 / rate_hz;
    if (std::isfinite(d) && d >= shortest && d <= kMaxDurationS) return;
    std::ostringstream m;
    m << "--duration " << d << ": must be a number of seconds from half a period (" << shortest
      << " s at [servo] rate_hz = " << rate_hz << ") to " << kMaxDurationS;
    throw StartError(kExitBadInput, m.str());
}

/// Refuses outputs that are inputs (or each other), then creates them: all before the device
/// is opened, so that a run that could not keep its results never starts.
Outputs prepare_outputs(const RunOptions& options, const Config& config) {
    std::vector<NamedPath> inputs;
    if (options.config_path) inputs.push_back({"--config", *options.config_path});
    if (!config.scene_file.empty()) {
        inputs.push_back({"the scene ([scene] file in " + config.source + ")", config.scene_file});
    }
    if (const std::string plugin = plugin_file(config.device.plugin); !plugin.empty()) {
        inputs.push_back({"the device plugin ([device] plugin in " + config.source + ")", plugin});
    }
    std::vector<NamedPath> outputs;
    if (options.log_path) outputs.push_back({"--log", *options.log_path});
    if (options.summary_path && *options.summary_path != "-") {
        outputs.push_back({"--summary", *options.summary_path});
    }
    Outputs opened;
    try {
        refuse_overlapping_paths(inputs, outputs);
        if (options.log_path) opened.log = open_locked_log("--log", *options.log_path);
        if (options.summary_path && *options.summary_path != "-") {
            opened.summary = open_output("--summary", *options.summary_path);
        }
    } catch (const OutputError& e) {
        throw StartError(kExitBadInput, e.what());
    }
    return opened;
}

/// make_servo_config() or make_identify_servo_config(), with config errors as exit 2.
template <typename MakeServoConfig>
servo::ServoConfig servo_config_or_exit(MakeServoConfig make) {
    try {
        return make();
    } catch (const ConfigError& e) {
        throw StartError(kExitBadInput, e.what());
    }
}

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
             Environment& environment, RunContext& context, Outputs& outputs,
             std::atomic<bool>& stop, std::ostream& out, std::ostream& log,
             AfterRun after_run = {}) {
    const device::DeviceInfo info = device.info();

    // From here on the outputs are this run's: emptied now (an old summary must not outlive
    // a run that is killed), kept whatever happens.
    try {
        outputs.log.begin();
        outputs.summary.begin();
    } catch (const OutputError& e) {
        throw StartError(kExitBadInput, e.what());
    }
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

    // This thread: signals, the duration and the status line.
    // --duration counts servo time: from the first tick, not from before the real-time set-up
    // (locking and prefaulting memory can take a tenth of a second).
    auto started = Clock::now();
    bool ticking = false;
    const auto status_every = std::chrono::duration<double>(options.status_interval_s);
    auto next_status = started + std::chrono::duration_cast<Clock::duration>(status_every);
    bool duration_ended = false;
    std::uint32_t logged_faults = 0;
    while (!servo_done.load(std::memory_order_acquire)) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        const auto now = Clock::now();
        if (!ticking && loop.status().tick >= 1) {
            ticking = true;
            started =
                now - std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                          static_cast<double>(loop.status().tick) / config.servo.rate_hz));
            next_status = started + std::chrono::duration_cast<Clock::duration>(status_every);
        }
        if (const servo::StatusSnapshot status = loop.status(); status.faults != logged_faults) {
            if ((status.faults & ~logged_faults) != 0u || status.faults == 0u) {
                log << fault_change_line(logged_faults, status, config) << "\n" << std::flush;
            }
            logged_faults = status.faults;
        }
        if (options.duration_s && !info.lockstep &&
            now - started >= std::chrono::duration<double>(*options.duration_s)) {
            duration_ended = true;
            stop_servo.store(true, std::memory_order_release);
        }
        if (options.status_interval_s > 0.0 && now >= next_status) {
            log << status_line(loop.status(), info.axes) << "\n" << std::flush;
            next_status += std::chrono::duration_cast<Clock::duration>(status_every);
        }
    }
    servo_thread.join();
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
            log << "hapticd: " << e.what() << "\n";
        }
        context.telemetry_log = *options.log_path;
        context.telemetry_records = writer->records_taken();
        context.telemetry_records_written = writer->records_written();
        context.telemetry_complete = writer->complete() && ring->dropped() == 0 &&
                                     writer->records_written() == writer->records_taken();
    }

    const servo::Summary summary = loop.summary();
    context.realtime = loop.realtime_report();
    context.run_time_s = info.lockstep
                             ? static_cast<double>(summary.ticks) / config.servo.rate_hz
                             : std::chrono::duration<double>(Clock::now() - started).count();
    int code = kExitOk;
    if (!servo_error.empty()) {
        log << "hapticd: the servo loop could not run: " << servo_error << "\n";
        context.exit = "error";
        code = kExitFault;
    } else if (run_exit == servo::RunExit::fault) {
        context.exit = "fault";
        code = kExitFault;
        if (loop.link_recovery().gave_up()) {
            log << "hapticd: the device did not come back within [safety] reconnect_timeout = "
                << config.safety.reconnect_timeout_s << " s; stopped on the fault, force zero "
                << "since the tick that saw it:";
        } else {
            log << "hapticd: stopped on a fault, force zeroed in the same tick:";
        }
        for (const std::string& fault : summary.faults) log << " " << fault;
        log << "\n";
    } else if (loop.faults() != 0u) {
        // Stopped (duration or signal) while waiting for the device to come back.
        context.exit = "fault";
        code = kExitFault;
        log << "hapticd: the run ended with the link down (" << fault_names(loop.faults())
            << "), force zero since the tick that saw it\n";
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
        log << "hapticd: stopped by " << context.stopped_by
            << ": force zeroed, telemetry flushed, summary written\n";
    }
    if (!context.realtime.refused.empty() && servo_error.empty()) {
        log << "hapticd: " << context.realtime.brief() << "\n";
    }
    after_run(code, context);
    const bool summary_written = write_summary(options, outputs, summary, context, out, log);
    // An output that is not whole is an exit status of its own, unless a fault (1) says more.
    if (code == kExitOk && (!context.telemetry_complete || !summary_written)) {
        if (!context.telemetry_complete) {
            log << "hapticd: the telemetry log " << context.telemetry_log
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

std::string millimetres(const env::Vec3& v, int axes) {
    std::array<double, servo::kMaxAxes> values{};
    for (int i = 0; i < servo::kMaxAxes; ++i) values[static_cast<std::size_t>(i)] = v[i];
    return format_vector_mm(values, axes, 1e3);
}

/// What the identify run says before it starts: what it does not do, what still applies,
/// and the signal with the values that were chosen for it.
void describe_identify(const Config& config, const IdentifyPlan& plan,
                       const env::ExcitationEnvironment& excitation, const RunOptions& options,
                       std::ostream& log) {
    const env::ExcitationSettings& s = plan.excitation;
    const env::Multisine& signal = excitation.signal();
    log << "hapticd: identify: open loop, the excitation straight to the handle: no coupling, "
           "[scene] and [coupling] not used, so the start-up stability check does not apply; "
        << "the force limit " << s.force_limit_n << " N ([safety] max_force, capped at the "
        << "device's) and [safety] max_speed = " << config.safety.max_speed_mps
        << " m/s apply; the soft start is the excitation's own (a still handle, then a " << s.fade_s
        << " s fade-in); passivity is only observed; any fault ends the run\n";
    log << "hapticd: identify: multisine, lines per axis";
    for (int axis = 0; axis < signal.axes(); ++axis) {
        log << (axis == 0 ? " " : ", ") << signal.lines(axis).size() << " ("
            << signal.lines(axis).front().frequency_hz << ".."
            << signal.lines(axis).back().frequency_hz << " Hz, crest factor "
            << std::setprecision(3) << signal.crest_factor(axis) << std::setprecision(6) << ")";
    }
    log << "; period " << signal.period_s() << " s x " << s.periods << ", fade " << s.fade_s
        << " s in and out; each axis peaks at " << s.signal.peak_force_n << " N; workspace +-"
        << 1e3 * s.workspace_half_width_m << " mm about the start";
    if (plan.predicted_excursion_m) {
        log << "; [device.model] predicts a swing of +-" << 1e3 * *plan.predicted_excursion_m
            << " mm";
    }
    log << "; " << *options.duration_s << " s\n";
    for (const std::string& chosen : plan.chosen)
        log << "hapticd: identify: chose " << chosen << "\n";
    if (plan.predicted_excursion_m && *plan.predicted_excursion_m > s.workspace_half_width_m) {
        log << "hapticd: identify: WARNING: [device.model] predicts a swing of +-"
            << 1e3 * *plan.predicted_excursion_m
            << " mm, beyond [identify] workspace = " << s.workspace_half_width_m
            << " m: the excitation will likely stop at its edge (lower force_amplitude or "
               "raise band_low)\n";
    }
}

/// `hapticd --identify`: the excitation instead of the scene, open loop, logged.
int run_identify(const RunOptions& options, std::atomic<bool>& stop, std::ostream& out,
                 std::ostream& log) {
    if (!options.log_path) {
        throw StartError(kExitBadInput,
                         "--identify needs --log FILE: the run exists to write the telemetry "
                         "CSV that haptic-tune identify reads");
    }
    const Config config = load_any_config(options);
    RunContext context;
    context.config_source = config.source;
    context.lockstep = options.lockstep;
    context.check.skipped = true;
    context.check.skipped_model = "none (identify: open loop, nothing coupled)";
    context.scene = "identify-multisine";
    context.causality = env::to_string(env::Causality::impedance);
    check_duration(options, config.servo.rate_hz);
    Outputs outputs = prepare_outputs(options, config);
    device::DeviceHandle device = open_device(config, options.lockstep);
    const DeviceCloser closer{device.get()};
    const device::DeviceInfo info = device->info();
    context.device = info.name;
    context.lockstep = info.lockstep;
    const servo::ServoConfig servo_config = servo_config_or_exit(
        [&] { return make_identify_servo_config(config, info, options.log_path.has_value()); });
    IdentifyPlan plan;
    try {
        plan = make_identify_plan(config, info);
    } catch (const ConfigError& e) {
        throw StartError(kExitBadInput, e.what());
    }
    std::unique_ptr<env::ExcitationEnvironment> excitation;
    try {
        excitation = std::make_unique<env::ExcitationEnvironment>(plan.excitation);
    } catch (const std::invalid_argument& e) {
        throw StartError(kExitBadInput, config.source + ": [identify]: " + e.what());
    }
    RunOptions run_options = options;
    if (!run_options.duration_s) run_options.duration_s = plan.duration_s;
    log << "hapticd: " << device_line(info) << "; identify; " << config.servo.rate_hz << " Hz\n";
    describe_identify(config, plan, *excitation, run_options, log);

    const double rate_hz = config.servo.rate_hz;
    const int axes = info.axes;
    auto report = [&](int& code, RunContext& ctx) {
        const env::ExcitationEnvironment& e = *excitation;
        const double start_s = static_cast<double>(e.start_tick()) / rate_hz;
        const double played_s = static_cast<double>(e.samples_played()) / rate_hz;
        const double whole_s = static_cast<double>(e.samples()) / rate_hz;
        log << std::defaultfloat << "hapticd: identify: ";
        switch (e.phase()) {
            case env::ExcitationEnvironment::Phase::finished:
                log << "the excitation ran to its end: " << whole_s << " s from tick "
                    << e.start_tick() << " (t = " << start_s << " s); the log is "
                    << *options.log_path << "\n";
                break;
            case env::ExcitationEnvironment::Phase::left_workspace:
                log << "the handle left the workspace at tick "
                    << e.start_tick() + e.samples_played() << " (t = " << start_s + played_s
                    << " s): x = " << millimetres(e.exit_position_m(), axes) << " mm, outside +-"
                    << 1e3 * e.settings().workspace_half_width_m << " mm about "
                    << millimetres(e.center_m(), axes)
                    << " mm; force zero from that tick on, after " << played_s << " of " << whole_s
                    << " s of excitation (lower [identify] force_amplitude, raise "
                    << "band_low or widen workspace)\n";
                ctx.exit = "workspace";
                if (code == kExitOk) code = kExitFault;
                break;
            case env::ExcitationEnvironment::Phase::waiting_for_still:
                log << "WARNING: the handle was never still (|v| < " << e.settings().still_speed_mps
                    << " m/s for " << e.settings().still_time_s << " s), so no excitation ran\n";
                break;
            case env::ExcitationEnvironment::Phase::running:
            case env::ExcitationEnvironment::Phase::interrupted:
                log << "WARNING: the run ended " << played_s << " s into the " << whole_s
                    << " s excitation (from t = " << start_s << " s); the log is "
                    << *options.log_path << "\n";
                break;
        }
    };
    return run_loop(run_options, config, servo_config, *device, *excitation, context, outputs, stop,
                    out, log, report);
}

}  // namespace

int run_daemon(const RunOptions& options, std::atomic<bool>& stop, std::ostream& out,
               std::ostream& log) {
    try {
        refuse_empty_paths(options);
        if (options.identify) return run_identify(options, stop, out, log);
        const Config config = load_any_config(options);
        RunContext context;
        context.config_source = config.source;
        context.lockstep = options.lockstep;
        context.check = run_startup_check(config, log);
        env::Scene scene = load_any_scene(config);
        check_scene_renderable(scene, config,
                               config.scene_file.empty() ? std::string("<embedded demo-wall scene>")
                                                         : config.scene_file);
        context.scene = scene.name;
        context.causality = env::to_string(scene.causality);
        if (!config.coupling.enabled && scene.causality == env::Causality::admittance) {
            throw StartError(kExitBadInput,
                             config.source + ": [coupling] enabled = false, but scene \"" +
                                 scene.name +
                                 "\" is an admittance (constraint) scene, which needs the "
                                 "coupling (22) to produce any force");
        }
        check_duration(options, config.servo.rate_hz);
        Outputs outputs = prepare_outputs(options, config);
        device::DeviceHandle device = open_device(config, options.lockstep);
        const DeviceCloser closer{device.get()};
        const device::DeviceInfo info = device->info();
        context.device = info.name;
        context.lockstep = info.lockstep;
        log << "hapticd: " << device_line(info) << "; scene " << scene.name << " ("
            << context.causality << "); " << config.servo.rate_hz << " Hz\n";
        const servo::ServoConfig servo_config = servo_config_or_exit(
            [&] { return make_servo_config(config, info, options.log_path.has_value()); });
        if (scene.causality == env::Causality::impedance) {
            return run_loop(options, config, servo_config, *device, *scene.impedance, context,
                            outputs, stop, out, log);
        }
        return run_loop(options, config, servo_config, *device, *scene.admittance, context, outputs,
                        stop, out, log);
    } catch (const StartError& e) {
        log << "hapticd: " << e.what() << "\n";
        return e.code;
    } catch (const std::exception& e) {
        log << "hapticd: " << e.what() << "\n";
        return kExitFault;
    }
}

}  // namespace hapticd::daemon
