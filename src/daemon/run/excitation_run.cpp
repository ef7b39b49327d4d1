#include "run/excitation_run.hpp"

#include <memory>
#include <ostream>

#include "hapticd/daemon/journal.hpp"
#include "hapticd/daemon/servo_settings.hpp"
#include "hapticd/env/excitation.hpp"
#include "run/run_messages.hpp"
#include "run/run_outputs.hpp"
#include "run/run_setup.hpp"
#include "run/supervised_run.hpp"
#include "socket/excitation_session.hpp"

namespace hapticd::daemon {
namespace {

/// What the excitation run says before it starts: what it does not do, what still applies,
/// and the signal with the values that were chosen for it.
void describe_identify(const Config& config, const IdentifyPlan& plan,
                       const env::ExcitationEnvironment& excitation, const RunOptions& options,
                       std::ostream& log) {
    const env::ExcitationSettings& s = plan.excitation;
    log << "hapticd: identify: open loop, the excitation straight to the handle: no coupling, "
           "[scene] and [coupling] not used, so the start-up stability check does not apply; "
        << "the force limit " << s.force_limit_n << " N ([safety] max_force, capped at the "
        << "device's) and [safety] max_speed = " << config.safety.max_speed_mps
        << " m/s apply; the soft start is the excitation's own (a still handle, then a " << s.fade_s
        << " s fade-in); passivity is only observed; any fault ends the run\n";
    log << "hapticd: identify: " << describe_excitation(plan, excitation.signal()) << "; "
        << *options.duration_s << " s\n";
    for (const std::string& chosen : plan.chosen)
        log << "hapticd: identify: chose " << chosen << "\n";
}

}  // namespace

int run_excitation(const RunOptions& options, const RunStamp& stamp, std::atomic<bool>& stop,
                   std::ostream& out, std::ostream& log) {
    if (!options.log_path) {
        throw BadInput(
            "--identify needs --log FILE: the run exists to write the telemetry "
            "CSV that haptic-tune identify reads");
    }
    const Config config = load_any_config(options);
    RunContext context = begin_context(options, config, stamp);
    context.check.skipped = true;
    context.check.skipped_model = "none (identify: open loop, nothing coupled)";
    context.scene = "identify-multisine";
    context.causality = env::to_string(env::Causality::impedance);
    check_duration(options, config.servo.rate_hz);
    Outputs outputs = prepare_outputs(options, config);
    device::DeviceHandle device = open_device_or_exit(config, options.lockstep);
    const DeviceCloser closer{device.get()};
    const device::DeviceInfo info = device->info();
    context.device = info.name;
    context.lockstep = info.lockstep;
    const servo::ServoConfig servo_config =
        make_identify_servo_config(config, info, options.log_path.has_value());
    keep_other_threads_off_servo_cpu(servo_config.realtime, context, log);
    const IdentifyPlan plan = make_identify_plan(config, info);
    std::unique_ptr<env::ExcitationEnvironment> excitation;
    try {
        excitation = std::make_unique<env::ExcitationEnvironment>(plan.excitation);
    } catch (const std::invalid_argument& e) {
        throw BadInput(config.source + ": [identify]: " + e.what());
    }
    RunOptions run_options = options;
    if (!run_options.duration_s) run_options.duration_s = plan.duration_s;
    log << start_line_prefix(config) << device_line(info) << "; identify; " << config.servo.rate_hz
        << " Hz\n";
    describe_identify(config, plan, *excitation, run_options, log);

    auto report = [&](int& code, RunContext& ctx) {
        const IdentifyOutcome outcome =
            identify_outcome(*excitation, config.servo.rate_hz, info.axes, *options.log_path,
                             /*log_ticks=*/true);
        log << outcome.priority << "hapticd: identify: " << outcome.text << "\n";
        if (outcome.left_workspace) {
            ctx.exit = "workspace";
            if (code == kExitOk) code = kExitFault;
        }
    };
    return run_loop(run_options, config, servo_config, *device, *excitation, RunScene{}, context,
                    outputs, stop, out, log, report);
}

}  // namespace hapticd::daemon
