#include "run/run_control.hpp"

#include <exception>
#include <ostream>

#include "hapticd/daemon/journal.hpp"
#include "hapticd/daemon/startup_check.hpp"
#include "run/run_messages.hpp"
#include "run/run_telemetry.hpp"

namespace hapticd::daemon {

std::string scene_in_force(const RunScene& scene, const SceneSwitch* scenes) {
    if (scene.scene == nullptr) return "none (the excitation plays open loop)";
    const SceneInForce now =
        scenes != nullptr ? scenes->in_force() : SceneInForce{scene.scene->name, scene.source};
    return now.name + " (" + env::to_string(scene.scene->causality) + ", " + now.source + ")";
}

control_socket::CouplingVerdict check_new_coupling(const Config& config, const SceneSwitch* scenes,
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

RunControl::RunControl(const Config& config, const device::DeviceInfo& info, const RunScene& scene,
                       const RunContext& context, const SocketLoopPorts& ports,
                       control_socket::SocketServer* server, const OutputsDirectory* outputs,
                       std::ostream& log, const device::Device* device, RunNotes& notes)
    : config_(config), control_(ports.control), server_(server) {
    // scene_load (scene_switch.hpp): a scene of the run's causality, only with a control socket.
    if (server_ != nullptr && scene.scene != nullptr) {
        scenes_.emplace(config_, *scene.scene, scene.source, scene.options, ports.scenes);
    }
    facts_ = control_socket::RunFacts{
        .name = config_.servo.name,
        .axes = info.axes,
        .rate_hz = config_.servo.rate_hz,
        .device = device_line(info),
        .config_path =
            context.config_path.empty() ? std::string("(embedded default)") : context.config_path,
        .measured_rate_hz = &measured_rate_hz_,
        .velocity_filter_hz = config_.coupling.velocity_filter_hz,
        .coupling_enabled = config_.coupling.enabled,
        .check_coupling =
            [this](const servo::CouplingGains& gains) {
                return check_new_coupling(config_, scenes_ ? &*scenes_ : nullptr, gains);
            },
        .scenes = scenes_ ? &*scenes_ : nullptr,
        .link_source = device,
        .notes = &notes};
    // record start/stop (recording.hpp): a ring for the run, only with a control socket.
    if (server_ != nullptr) {
        recording_.emplace(
            ports.attach_recording, ports.tick, info.axes, info.lockstep, outputs,
            [this, &context, info, scene] { return recording_preamble(context, info, scene); },
            &notes);
        facts_.recording = &*recording_;
    }
    // identify (excitation_session.hpp): the excitation played open loop on a disarmed run that
    // renders a scene, only with a control socket.
    if (recording_ && scene.scene != nullptr) {
        identify_.emplace(config_, info, *recording_, ports.identify, context.stamp.start_name);
        facts_.identify = &*identify_;
    }
    stopper_.server = server_;
    if (server_ != nullptr) {
        server_->start(
            [this](const control_socket::Request& request, const control_socket::Peer& peer) {
                return control_socket::answer(request, peer, control_, facts_);
            },
            [this] { return control_socket::telemetry_event(control_.recent_status(), facts_); });
        log << priority::info << "hapticd: control socket " << server_->path() << "\n";
    }
}

std::string RunControl::recording_preamble(const RunContext& context,
                                           const device::DeviceInfo& info,
                                           const RunScene& scene) const {
    const servo::CouplingGains gains = control_.coupling();
    const SceneSwitch* scenes = scenes_ ? &*scenes_ : nullptr;
    return telemetry_preamble(telemetry_header(config_, context, info, gains,
                                               check_new_coupling(config_, scenes, gains).verdict,
                                               scene_in_force(scene, scenes)));
}

void RunControl::poll(std::ostream& log) {
    drain_messages(log);
    if (identify_) identify_->poll(log);
}

void RunControl::finish(RunContext& context, std::ostream& log) {
    if (server_ != nullptr) server_->stop();
    drain_messages(log);
    if (identify_) identify_->finish_at_exit(log);
    if (recording_) finish_recording(context, log);
    if (identify_) {
        for (const IdentifyProgress& ended : identify_->ended()) {
            context.excitations.push_back(
                {.path = ended.path, .outcome = ended.outcome, .complete = ended.complete});
        }
    }
    if (scenes_) context.scene = scenes_->in_force().name;  // the last loaded, if any was
}

void RunControl::drain_messages(std::ostream& log) {
    if (server_ == nullptr) return;
    for (const std::string& line : server_->take_messages()) {
        log << priority::info << "hapticd: " << line << "\n" << std::flush;
    }
}

// A recording still running ends with the run, whole.
void RunControl::finish_recording(RunContext& context, std::ostream& log) {
    if (const std::optional<RecordingResult> ended = recording_->finish_at_exit()) {
        log << (ended->complete ? priority::notice : priority::err) << "hapticd: " << ended->message
            << ", at the end of the run\n";
    }
    for (const RecordingResult& closed : recording_->closed()) {
        context.recordings.push_back({.path = closed.path,
                                      .records = closed.records,
                                      .dropped = closed.dropped,
                                      .complete = closed.complete,
                                      .failure = closed.failure});
    }
}

}  // namespace hapticd::daemon
