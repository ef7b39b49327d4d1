#include "identify_run.hpp"

#include <iomanip>
#include <memory>
#include <ostream>

#include "hapticd/daemon/journal.hpp"
#include "hapticd/daemon/servo_settings.hpp"
#include "hapticd/env/excitation.hpp"
#include "run_messages.hpp"
#include "run_outputs.hpp"
#include "run_setup.hpp"
#include "supervised_run.hpp"

namespace hapticd::daemon {
namespace {

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
        log << priority::warning
            << "hapticd: identify: WARNING: [device.model] predicts a swing of +-"
            << 1e3 * *plan.predicted_excursion_m
            << " mm, beyond [identify] workspace = " << s.workspace_half_width_m
            << " m: the excitation will likely stop at its edge (lower force_amplitude or "
               "raise band_low)\n";
    }
}

}  // namespace

int run_identify(const RunOptions& options, const RunStamp& stamp, std::atomic<bool>& stop,
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
    const IdentifyPlan plan = make_identify_plan(config, info);
    std::unique_ptr<env::ExcitationEnvironment> excitation;
    try {
        excitation = std::make_unique<env::ExcitationEnvironment>(plan.excitation);
    } catch (const std::invalid_argument& e) {
        throw BadInput(config.source + ": [identify]: " + e.what());
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
        using Phase = env::ExcitationEnvironment::Phase;
        log << (e.phase() == Phase::finished         ? priority::info
                : e.phase() == Phase::left_workspace ? priority::err
                                                     : priority::warning)
            << std::defaultfloat << "hapticd: identify: ";
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
    return run_loop(run_options, config, servo_config, *device, *excitation, RunScene{}, context,
                    outputs, stop, out, log, report);
}

}  // namespace hapticd::daemon
