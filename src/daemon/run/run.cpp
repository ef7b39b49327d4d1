#include "hapticd/daemon/run.hpp"

#include <chrono>
#include <ostream>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/journal.hpp"
#include "hapticd/daemon/servo_settings.hpp"
#include "hapticd/env/scene.hpp"
#include "hapticd/input/printable.hpp"
#include "run/excitation_run.hpp"
#include "run/run_messages.hpp"
#include "run/run_outputs.hpp"
#include "run/run_setup.hpp"
#include "run/supervised_run.hpp"

namespace hapticd::daemon {

int run_daemon(const RunOptions& given, std::atomic<bool>& stop, std::ostream& out,
               std::ostream& log) {
    try {
        refuse_empty_paths(given);
        const RunStamp stamp = stamp_run(std::chrono::system_clock::now());
        const RunOptions options = with_start(given, stamp);
        if (options.identify) return run_excitation(options, stamp, stop, out, log);
        const Config config = load_any_config(options);
        RunContext context = begin_context(options, config, stamp);
        context.check = run_startup_check(config, log);
        const env::SceneOptions scene_options = run_scene_options(config, options, stop);
        env::Scene scene = load_any_scene(config, options, scene_options);
        const std::string scene_source = config.scene_file.empty()
                                             ? std::string("<embedded demo-wall scene>")
                                             : config.scene_file;
        check_scene_renderable(scene, config, scene_source);
        context.scene = scene.name;
        context.causality = env::to_string(scene.causality);
        if (!config.coupling.enabled && scene.causality == env::Causality::admittance) {
            throw BadInput(config.source + ": [coupling] enabled = false, but scene \"" +
                           scene.name +
                           "\" is an admittance (constraint) scene, which needs the "
                           "coupling (22) to produce any force");
        }
        check_duration(options, config.servo.rate_hz);
        if (!config.safety.arm_at_start && !options.socket_path) {
            throw BadInput(config.source +
                           ": [safety] arm_at_start = false waits for hapticctl arm, which needs "
                           "a control socket (--socket PATH; the unit gives one); without it "
                           "the device would never push");
        }
        Outputs outputs = prepare_outputs(options, config);
        device::DeviceHandle device = open_device_or_exit(config, options.lockstep);
        const DeviceCloser closer{device.get()};
        const device::DeviceInfo info = device->info();
        context.device = info.name;
        context.lockstep = info.lockstep;
        log << start_line_prefix(config) << device_line(info) << "; scene " << scene.name << " ("
            << context.causality << "); " << config.servo.rate_hz << " Hz\n";
        servo::ServoConfig servo_config =
            make_servo_config(config, info, options.log_path.has_value());
        keep_other_threads_off_servo_cpu(servo_config.realtime, context, log);
        // An operator on the control socket can reset a fault: it latches at zero force
        // and waits (docs/control.md, "Faults and reset"). Without one nobody can, so
        // the run ends on it.
        if (options.socket_path) servo_config.stop_on_fault = false;
        if (scene.external) {
            log << "hapticd: the external world's channel: " << input::printable(*scene.external)
                << "\n";
            if (!scene.external_note.empty()) {
                log << priority::warning << "hapticd: " << input::printable(scene.external_note)
                    << "\n";
            }
        }
        const RunScene rendered{.scene = &scene, .source = scene_source, .options = scene_options};
        if (scene.causality == env::Causality::impedance) {
            return run_loop(options, config, servo_config, *device, *scene.impedance, rendered,
                            context, outputs, stop, out, log);
        }
        return run_loop(options, config, servo_config, *device, *scene.admittance, rendered,
                        context, outputs, stop, out, log);
    } catch (const input::InputError& e) {  // found before the device moved
        log << priority::err << "hapticd: " << e.what() << "\n";
        return kExitBadInput;
    } catch (const std::exception& e) {
        log << priority::err << "hapticd: " << e.what() << "\n";
        return kExitFault;
    }
}

}  // namespace hapticd::daemon
