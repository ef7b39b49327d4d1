#include "run/run_setup.hpp"

#include <cmath>
#include <filesystem>
#include <ostream>
#include <sstream>

#include "hapticd/daemon/device_open.hpp"
#include "hapticd/daemon/journal.hpp"
#include "hapticd/env/external_channel.hpp"

namespace hapticd::daemon {

Config load_any_config(const RunOptions& options) {
    Config config = options.config_path ? load_config(*options.config_path) : default_config();
    // The plugin's own table, read as its open() will read it, as haptic-tune reads it: a bad
    // one is refused here, before the start-up check. A plugin that cannot be loaded is left
    // to open_device_or_exit, after the outputs are checked (one of them may be the plugin).
    check_device_config(config, UnloadablePlugin::defer, options.lockstep);
    return config;
}

env::SceneOptions run_scene_options(const Config& config, const RunOptions& options,
                                    const std::atomic<bool>& stop) {
    return {.rate_hz = config.servo.rate_hz,
            .external_channel =
                options.socket_path ? env::channel_beside(*options.socket_path) : std::string(),
            .stop = &stop};
}

env::Scene load_any_scene(const Config& config, const RunOptions& options,
                          const env::SceneOptions& scene_options) {
    if (config.scene_file.empty()) {
        return env::parse_scene(default_scene_text(), "<embedded demo-wall scene>",
                                config.device.axes, scene_options);
    }
    env::Scene scene = env::load_scene(config.scene_file, config.device.axes, scene_options);
    if (scene.external && !options.socket_path) {
        throw BadInput(config.scene_file +
                       ": [external] is a world another process renders "
                       "through a channel beside the control socket: run "
                       "hapticd with --socket PATH (the unit gives one)");
    }
    return scene;
}

// A detent with a short period or a large peak force has such a stiffness between its
// notches; the solve failed on every tick.
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
    throw BadInput(m.str());
}

StartupCheck run_startup_check(const Config& config, std::ostream& log) {
    StartupCheck check;
    try {
        check = check_coupling_at_startup(config);
    } catch (const std::invalid_argument& e) {  // a model's own range check
        throw BadInput(config.source + ": " + e.what());
    }
    if (check.skipped) {
        log << priority::warning << "hapticd: WARNING: " << check.describe() << "\n";
        return check;
    }
    // The verdict's own line first, as haptic-tune check gives it for this config.
    const bool holds = check.guarantee && check.passed;
    log << (holds ? priority::info : priority::warning) << "hapticd: " << (holds ? "" : "WARNING: ")
        << check.describe() << "\n";
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
        if (config.device.model.delay_s > 0.0) {
            m << " with a loop delay of " << config.device.model.delay_s << " s";
        }
        m << "; size them with haptic-tune size --mass " << *config.device.model.mass_kg
          << " --damping " << *config.device.model.damping_n_s_per_m << " --rate "
          << config.servo.rate_hz;
        if (config.device.model.delay_s > 0.0) m << " --delay " << config.device.model.delay_s;
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
        throw BadInput(m.str());
    }
    return check;
}

// A plugin that cannot be loaded is bad input (exit 2), and so is a device the plugin
// refuses to open.
device::DeviceHandle open_device_or_exit(const Config& config, bool lockstep) {
    try {
        return open_device(config, lockstep);
    } catch (const std::exception& e) {
        throw BadInput(e.what());
    }
}

void refuse_empty_paths(const RunOptions& options) {
    const auto empty = [](const std::optional<std::string>& path) { return path && path->empty(); };
    const char* option = empty(options.config_path)    ? "--config"
                         : empty(options.log_path)     ? "--log"
                         : empty(options.summary_path) ? "--summary"
                         : empty(options.socket_path)  ? "--socket"
                                                       : nullptr;
    if (option != nullptr) {
        throw BadInput(std::string(option) + " \"\": the path is empty; give a file name");
    }
}

RunOptions with_start(RunOptions options, const RunStamp& stamp) {
    if (options.log_path) options.log_path = with_start(*options.log_path, stamp);
    if (options.summary_path) options.summary_path = with_start(*options.summary_path, stamp);
    return options;
}

RunContext begin_context(const RunOptions& options, const Config& config, const RunStamp& stamp) {
    RunContext context;
    context.stamp = stamp;
    context.name = config.servo.name;
    context.config_source = config.source;
    if (options.config_path) {
        std::error_code error;
        const std::filesystem::path absolute =
            std::filesystem::absolute(*options.config_path, error);
        context.config_path = error ? *options.config_path : absolute.lexically_normal().string();
    }
    context.lockstep = options.lockstep;
    return context;
}

void keep_other_threads_off_servo_cpu(const servo::RealtimeRequest& request, RunContext& context,
                                      std::ostream& log) {
    if (request.cpu < 0 || request.mode == servo::RealtimeMode::off) return;
    context.other_threads = servo::keep_other_threads_off(request.cpu);
    if (context.other_threads.off_servo_cpu) {
        log << "hapticd: other threads on cpus " << context.other_threads.cpus
            << ", off the servo's cpu " << request.cpu << "\n";
    } else {
        log << (request.mode == servo::RealtimeMode::enforce ? priority::warning : priority::notice)
            << "hapticd: other threads not kept off the servo's cpu " << request.cpu << ": "
            << context.other_threads.why_not << "\n";
    }
}

void check_duration(const RunOptions& options, double rate_hz) {
    if (!options.duration_s) return;
    const double d = *options.duration_s;
    const double shortest = 0.5 / rate_hz;
    if (std::isfinite(d) && d >= shortest && d <= kMaxDurationS) return;
    std::ostringstream m;
    m << "--duration " << d << ": must be a number of seconds from half a period (" << shortest
      << " s at [servo] rate_hz = " << rate_hz << ") to " << kMaxDurationS;
    throw BadInput(m.str());
}

}  // namespace hapticd::daemon
