// The run's set-up steps, each before the device moves: the config, the scene and whether
// the coupling can render it, the start-up stability check, the command line's values, and
// the device. Each refuses bad input with a message that is final and exit 2: BadInput for
// what the daemon finds itself, ConfigError for what the readers find (run.cpp maps both).
#pragma once

#include <iosfwd>
#include <stdexcept>
#include <string>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/run.hpp"
#include "hapticd/daemon/startup_check.hpp"
#include "hapticd/device/plugin_loader.hpp"
#include "hapticd/env/scene.hpp"
#include "hapticd/input/input_error.hpp"
#include "hapticd/servo/realtime.hpp"
#include "outputs/summary_json.hpp"
#include "run/run_stamp.hpp"

namespace hapticd::daemon {

/// Bad input the daemon finds itself (a command-line value, a config and scene that do not
/// go together, a device that refuses to open): exit 2 with this message.
struct BadInput : input::InputError {
    explicit BadInput(const std::string& message) : InputError(message) {}
};

/// Leaves the device at zero force and closes it, whatever path leaves the run.
struct DeviceCloser {
    device::Device* device;
    ~DeviceCloser() {
        if (device != nullptr) device->close();
    }
};

/// --config, else the embedded default. Throws ConfigError.
Config load_any_config(const RunOptions& options);
/// How this run reads scenes: its rate; an [external] world's channel beside the control
/// socket (none without one: private), whose lockstep waits end at `stop`.
env::SceneOptions run_scene_options(const Config& config, const RunOptions& options,
                                    const std::atomic<bool>& stop);
/// [scene] file, else the embedded demo wall. Throws env::SceneError; BadInput for an
/// [external] scene without a control socket (nobody could reach its channel).
env::Scene load_any_scene(const Config& config, const RunOptions& options,
                          const env::SceneOptions& scene_options);
/// A scene the coupling cannot render is refused before the device opens: an object whose
/// stiffness is more negative than -k_c leaves the massless tool of (17) no stable balance.
void check_scene_renderable(const env::Scene& scene, const Config& config,
                            const std::string& scene_source);
/// The start-up stability check (startup_check.hpp), its verdict on `log`; BadInput when
/// the coupling fails it, saying how to size one that passes.
StartupCheck run_startup_check(const Config& config, std::ostream& log);
/// The device, open (device_open.hpp); BadInput naming the plugin or what open() said.
device::DeviceHandle open_device_or_exit(const Config& config, bool lockstep);
/// An empty path is an error, not "none".
void refuse_empty_paths(const RunOptions& options);
/// The options with `{start}` in --log and --summary replaced by the stamp's start time.
RunOptions with_start(RunOptions options, const RunStamp& stamp);
/// What the summary says of every run from the start: the stamp, the config, the clock.
RunContext begin_context(const RunOptions& options, const Config& config, const RunStamp& stamp);
/// When the servo thread will pin itself (`request`: real time asked for, a cpu), every other
/// thread of hapticd, those there and those started after, leaves that CPU to it
/// (servo::keep_other_threads_off); the result in `context`, a line on `log`. Call it once the
/// servo's settings are made (they know whether the device is lockstep), before the loop.
void keep_other_threads_off_servo_cpu(const servo::RealtimeRequest& request, RunContext& context,
                                      std::ostream& log);
/// --duration: finite, at least half a period (it is rounded to whole ticks: anything
/// shorter would be zero ticks, which means no limit), at most kMaxDurationS.
void check_duration(const RunOptions& options, double rate_hz);

}  // namespace hapticd::daemon
