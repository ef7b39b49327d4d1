#include "socket/requests.hpp"

#include <sys/stat.h>

#include <sstream>
#include <string_view>
#include <vector>

#include "hapticd/daemon/config_schema.hpp"
#include "hapticd/env/external_environment.hpp"
#include "hapticd/input/printable.hpp"
#include "hapticd/input/range.hpp"
#include "hapticd/input/text_input.hpp"
#include "hapticd/servo/faults.hpp"
#include "hapticd/servo/servo_state.hpp"
#include "outputs/percentiles_json.hpp"

namespace hapticd::daemon::control_socket {
namespace {

// "mode 0640, owner uid 0, group gid 0": what decided a file's reading.
std::string mode_text(const struct stat& status) {
    std::ostringstream text;
    text << "mode 0" << std::oct << (status.st_mode & 0777U) << std::dec << ", owner uid "
         << status.st_uid << ", group gid " << status.st_gid;
    return text.str();
}

nlohmann::json first_axes(const std::array<double, servo::kMaxAxes>& v, int axes) {
    return std::vector<double>(v.begin(), v.begin() + axes);
}

nlohmann::json fault_list(std::uint32_t faults) {
    nlohmann::json names = nlohmann::json::array();
    servo::for_each_fault(faults, [&](std::string_view name) { names.push_back(name); });
    return names;
}

std::string state_of(const servo::StatusSnapshot& s) {
    return std::string(servo::servo_state_name(s.state));
}

// Whether identify's excitation plays: asked on the worker, when a request's work runs.
bool identify_playing(const RunFacts& facts) {
    return facts.identify != nullptr && facts.identify->active();
}

// A change of gains or scene as one of the run's notes: the recordings say from which row on
// it holds (a run that keeps no notes, or holds the most, goes without).
void note(const RunFacts& facts, ServoControl& loop, const std::string& text) {
    if (facts.notes == nullptr) return;
    (void)facts.notes->add(input::printable(text), [&loop](std::uint32_t n) { loop.mark(n); });
}

constexpr const char* kIdentifyPlaying =
    "identify is playing the excitation: wait for its end, or stop it with hapticctl disarm";

// coupling: the range of [coupling] stiffness and damping here, then, on the server's worker
// (Answer::later: the exact model's check takes seconds), the start-up stability check on the
// config with the new gains; only gains that pass reach the loop.
Answer set_coupling(const Request& request, const Peer& peer, ServoControl& loop,
                    const RunFacts& facts, const servo::StatusSnapshot& now) {
    const auto refusal = [id = request.id, peer](const std::string& why) {
        return Answer{.reply = error_reply(id, "coupling refused: " + why),
                      .journal = "control: coupling from " + peer.describe() + " refused: " + why};
    };
    if (!facts.coupling_enabled) {
        return refusal("the config runs without the coupling ([coupling] enabled = false)");
    }
    const servo::CouplingGains gains{
        .stiffness_n_per_m = request.stiffness_n_per_m.value_or(0.0),
        .damping_n_s_per_m = request.damping_n_s_per_m.value_or(loop.coupling().damping_n_s_per_m),
        .velocity_filter_hz = facts.velocity_filter_hz};
    const input::Range& k_range = schema::kCouplingStiffness.range;
    const input::Range& b_range = schema::kCouplingDamping.range;
    if (!k_range.contains(gains.stiffness_n_per_m)) {
        return refusal(input::out_of_range("stiffness", gains.stiffness_n_per_m, k_range));
    }
    if (!b_range.contains(gains.damping_n_s_per_m)) {
        return refusal(input::out_of_range("damping", gains.damping_n_s_per_m, b_range));
    }
    // Refused whatever [coupling] check says, as the servo's config refuses it at the start.
    if (gains.renders_nothing()) {
        return refusal(
            "stiffness and damping are both 0: a coupling of zero renders nothing "
            "(hapticctl disarm renders no force)");
    }
    if (!facts.check_coupling) return refusal("this run has no stability check to pass");
    return {.later = [&loop, &facts, gains, refusal, id = request.id, peer,
                      state_before = state_of(now)]() -> Answer {
        // Here, when the work runs, not when the line was read: an identify queued before
        // this request may have started since.
        if (identify_playing(facts)) return refusal(kIdentifyPlaying);
        const CouplingVerdict verdict = facts.check_coupling(gains);
        if (!verdict.accepted) return refusal(verdict.verdict);
        loop.set_coupling(gains);
        std::ostringstream set;
        set << "k_c " << input::format_number(gains.stiffness_n_per_m) << " N/m, b_c "
            << input::format_number(gains.damping_n_s_per_m) << " N s/m";
        // The note's numbers exact, for a reader that takes k_c from it (haptic-tune
        // plot-run); the journal's and the reply's text keep six digits.
        note(facts, loop,
             "coupling k_c " + input::exact_number(gains.stiffness_n_per_m) + " N/m, b_c " +
                 input::exact_number(gains.damping_n_s_per_m) + " N s/m; " + verdict.verdict);
        return {.reply = ok_reply(id, {{"state_before", state_before},
                                       {"stiffness", gains.stiffness_n_per_m},
                                       {"damping", gains.damping_n_s_per_m},
                                       {"verdict", verdict.verdict}}),
                .journal = "control: coupling from " + peer.describe() + ": " + set.str() +
                           " from the next tick, through the soft start; " + verdict.verdict};
    }};
}

// mark: the text kept in the run's notes, its number to the loop, which stamps it on every
// record from its next tick on.
Answer mark(const Request& request, const Peer& peer, ServoControl& loop, const RunFacts& facts,
            const servo::StatusSnapshot& now) {
    if (facts.notes == nullptr) {
        return {.reply = error_reply(request.id, "mark refused: this run keeps no notes"),
                .journal = {}};
    }
    const std::string& text = request.text.value();
    const std::optional<std::uint32_t> number =
        facts.notes->add(text, [&loop](std::uint32_t n) { loop.mark(n); });
    if (!number) {
        const std::string why = "the run holds " + std::to_string(kMaxRunNotes) +
                                " marks and changes already, the most it keeps";
        return {.reply = error_reply(request.id, "mark refused: " + why),
                .journal = "control: mark from " + peer.describe() + " refused: " + why};
    }
    return {.reply = ok_reply(request.id, {{"mark", *number}, {"after_tick", now.tick}}),
            .journal = "control: mark " + std::to_string(*number) + " from " + peer.describe() +
                       ": " + input::printable(text)};
}

// record_start, record_stop: on the worker (a file to create, a writer to drain).
Answer record(const Request& request, const Peer& peer, const RunFacts& facts) {
    const std::string name(request_name(request.kind));
    if (facts.recording == nullptr) {
        return {.reply = error_reply(request.id, name + " refused: this run cannot record"),
                .journal = {}};
    }
    return {.later = [recording = facts.recording, &facts, kind = request.kind, path = request.path,
                      id = request.id, peer, name]() -> Answer {
        if (kind == RequestKind::record_stop && identify_playing(facts)) {
            return {.reply = error_reply(id, name + " refused: the recording is identify's log, "
                                                    "which ends with the excitation"),
                    .journal = {}};
        }
        const RecordingResult result = kind == RequestKind::record_start
                                           ? recording->start(path.value_or(std::string()))
                                           : recording->stop();
        if (!result.ok) {
            return {.reply = error_reply(id, name + " refused: " + result.message),
                    .journal = "control: " + name + " from " + peer.describe() +
                               " refused: " + result.message};
        }
        nlohmann::json body{{"path", result.path}};
        if (kind == RequestKind::record_start) {
            body["first_tick"] = result.first_tick;
        } else {
            body["records"] = result.records;
            body["dropped"] = result.dropped;
            body["complete"] = result.complete;
            if (!result.complete) body["failure"] = result.failure;
        }
        return {.reply = ok_reply(id, body),
                .journal = "control: " + name + " from " + peer.describe() + ": " + result.message};
    }};
}

// scene_load: on the worker (a file to read and build, the stability check to run), checked
// against the gains in force; the loop takes the scene at the start of a tick.
Answer load_scene(const Request& request, const Peer& peer, ServoControl& loop,
                  const RunFacts& facts, const servo::StatusSnapshot& now) {
    if (facts.scenes == nullptr) {
        return {.reply = error_reply(request.id,
                                     "scene_load refused: this run renders no scene (an "
                                     "identification run)"),
                .journal = {}};
    }
    return {.later = [scenes = facts.scenes, &loop, path = request.path.value_or(std::string()),
                      &facts, id = request.id, peer, state_before = state_of(now)]() -> Answer {
        if (identify_playing(facts)) {
            return {
                .reply = error_reply(id, std::string("scene_load refused: ") + kIdentifyPlaying),
                .journal = {}};
        }
        // A client loads only a regular file it could read itself: the daemon may read more
        // than its clients, and a refusal quotes the file (docs/control.md, "Paths and strings").
        const SceneLoadResult result =
            scenes->load(path, loop.coupling(), [&peer](const struct stat& status) {
                if (std::string why = input::regular_file_only(status); !why.empty()) return why;
                if (peer.may_read(status)) return std::string();
                return "the client (uid " + std::to_string(peer.uid) +
                       ") may not read it itself (" + mode_text(status) +
                       "): a client loads only a scene it could read";
            });
        if (!result.ok) {
            return {.reply = error_reply(id, "scene_load refused: " + result.message),
                    .journal = "control: scene_load from " + peer.describe() +
                               " refused: " + result.message};
        }
        note(facts, loop, "scene " + result.name + " (" + result.path + "); " + result.verdict);
        return {.reply = ok_reply(id, {{"state_before", state_before},
                                       {"scene", result.name},
                                       {"path", result.path},
                                       {"verdict", result.verdict}}),
                .journal = "control: scene_load from " + peer.describe() + ": " + result.message};
    }};
}

// identify: on the worker (a plan to make, tables to build, a file to create); the loop takes
// the excitation at the start of a tick, and the supervising thread sees it end
// (excitation_session.hpp).
Answer identify(const Request& request, const Peer& peer, const RunFacts& facts) {
    if (facts.identify == nullptr) {
        return {.reply = error_reply(request.id,
                                     "identify refused: this run is an identification run "
                                     "(hapticd --identify) already"),
                .journal = {}};
    }
    return {.later = [session = facts.identify, path = request.path, id = request.id,
                      peer]() -> Answer {
        const IdentifyStart started = session->start(path);
        if (!started.ok) {
            return {.reply = error_reply(id, "identify refused: " + started.message),
                    .journal = "control: identify from " + peer.describe() +
                               " refused: " + started.message};
        }
        return {.reply = ok_reply(id, {{"path", started.path},
                                       {"excitation_s", started.excitation_s},
                                       {"wait_s", started.wait_s}}),
                .journal = "control: identify from " + peer.describe() + ": " + started.message};
    }};
}

nlohmann::json identify_body(const RunFacts& facts) {
    const std::optional<IdentifyProgress> p =
        facts.identify != nullptr ? facts.identify->progress() : std::nullopt;
    if (!p) return nullptr;
    nlohmann::json j{{"active", p->active},
                     {"phase", p->phase},
                     {"path", p->path},
                     {"played_s", p->played_s},
                     {"excitation_s", p->excitation_s}};
    if (!p->active) {
        j["outcome"] = p->outcome;
        j["complete"] = p->complete;
    }
    return j;
}

/// status's `link`: the loop's own counts, then the device's (zeros, counted false, for a
/// device that keeps none). On the server's thread: link_quality() never waits for the tick.
nlohmann::json link_body(const servo::StatusSnapshot& s, const RunFacts& facts) {
    const device::LinkQuality q =
        facts.link_source != nullptr ? facts.link_source->link_quality() : device::LinkQuality{};
    return {{"read_timeouts", s.read_timeouts},
            {"link_recoveries", s.link_recoveries},
            {"counted", q.counted},
            {"frames_sent", q.frames_sent},
            {"frames_received", q.frames_received},
            {"bad_frames", q.bad_frames},
            {"transfer_errors", q.transfer_errors},
            {"reply_timeouts", q.reply_timeouts},
            {"missed_samples", q.missed_samples},
            {"late", q.late},
            {"duplicate", q.duplicate},
            {"device_errors", q.device_errors},
            {"disconnects", q.disconnects},
            {"reconnects", q.reconnects},
            {"wrong_session", q.wrong_session},
            {"unexpected", q.unexpected},
            {"out_of_step", q.out_of_step}};
}

}  // namespace

// An [external] scene's world (env/external_environment.hpp); null for hapticd's own scenes.
nlohmann::json external_world_body(const servo::EnvironmentPortReport& port) {
    if (!port.external) return nullptr;
    const auto state = static_cast<env::WorldState>(port.world_state);
    std::string why;
    if (state == env::WorldState::waiting) {
        why = "no update from the world yet: the tool follows the handle, no force";
    } else if (state == env::WorldState::stale) {
        why = "no update from the world for " + input::exact_number(port.since_update_s) +
              " s: the tool holds, and its force ramps to zero";
    }
    return {{"state", env::to_string(state)},
            {"why", why},
            {"update", port.update},
            {"since_update_s", port.since_update_s},
            {"stale_episodes", port.stale_episodes},
            {"rejected_updates", port.rejected_updates},
            {"energy_j", port.energy_j},
            {"energy_removed_j", port.energy_removed_j}};
}

nlohmann::json status_body(const servo::StatusSnapshot& s, const RunFacts& facts) {
    nlohmann::json j;
    j["name"] = facts.name;
    j["state"] = state_of(s);
    j["armed"] = s.armed;
    j["tick"] = s.tick;
    j["t_s"] = s.t_s;
    j["rate_hz"] = facts.rate_hz;
    j["measured_rate_hz"] =
        facts.measured_rate_hz != nullptr ? facts.measured_rate_hz->load() : 0.0;
    j["soft_start_scale"] = s.soft_start_scale;
    j["faults"] = fault_list(s.faults);
    j["overruns"] = s.overruns;
    j["solver_not_converged"] = s.solver_not_converged;
    j["energy_j"] = s.energy_j;
    j["coupling"] = {{"stiffness", s.stiffness_n_per_m}, {"damping", s.damping_n_s_per_m}};
    j["wake_latency_us"] = percentiles_json<nlohmann::json>(s.wake_latency_us);
    j["tick_compute_us"] = percentiles_json<nlohmann::json>(s.tick_compute_us);
    j["link"] = link_body(s, facts);
    j["external_world"] = external_world_body(s.environment);
    j["axes"] = facts.axes;
    j["x_m"] = first_axes(s.x_m, facts.axes);
    j["xe_m"] = first_axes(s.xe_m, facts.axes);
    j["f_n"] = first_axes(s.f_n, facts.axes);
    j["device"] = facts.device;
    j["config_path"] = facts.config_path;
    // identify before the recording: an excitation that has ended has closed its recording
    // first (ExcitationSession::end), so a status that shows it ended never shows its log
    // still open. Read the other way round, the two could straddle the end.
    const nlohmann::json identify = identify_body(facts);
    const std::optional<std::string> recording =
        facts.recording != nullptr ? facts.recording->active_path() : std::nullopt;
    j["recording"] = recording ? nlohmann::json(*recording) : nlohmann::json(nullptr);
    const std::optional<bool> whole =
        facts.recording != nullptr ? facts.recording->active_whole() : std::nullopt;
    j["recording_whole"] = whole ? nlohmann::json(*whole) : nlohmann::json(nullptr);
    j["identify"] = identify;
    if (facts.scenes != nullptr) {
        const SceneInForce scene = facts.scenes->in_force();
        j["scene"] = {{"name", scene.name}, {"source", scene.source}};
    } else {
        j["scene"] = nullptr;
    }
    return j;
}

std::string telemetry_event(const servo::StatusSnapshot& s, const RunFacts& facts) {
    return event_line("telemetry", {{"tick", s.tick},
                                    {"t_s", s.t_s},
                                    {"state", state_of(s)},
                                    {"x_m", first_axes(s.x_m, facts.axes)},
                                    {"xe_m", first_axes(s.xe_m, facts.axes)},
                                    {"f_n", first_axes(s.f_n, facts.axes)},
                                    {"faults", fault_list(s.faults)}});
}

Answer answer(const Request& request, const Peer& peer, ServoControl& loop, const RunFacts& facts) {
    // A status reply may be a few ms old, whoever asks how often; a request that decides on
    // the status reads the latest.
    const servo::StatusSnapshot now =
        request.kind == RequestKind::status ? loop.recent_status() : loop.status();
    const std::string name(request_name(request.kind));
    switch (request.kind) {
        case RequestKind::status: {
            nlohmann::json body = status_body(now, facts);
            // Why the world failed, while the fault `environment` is latched.
            const std::string failure = (now.faults & servo::kFaultEnvironment) != 0u
                                            ? loop.environment_failure()
                                            : std::string();
            body["environment_failure"] =
                failure.empty() ? nlohmann::json(nullptr) : nlohmann::json(failure);
            return {.reply = ok_reply(request.id, {{"status", body}}), .journal = {}};
        }
        case RequestKind::arm:
            // A reset asked for that this status does not show taken (a pipelined reset, arm)
            // clears the latch at a tick's start, before or with the arming.
            if (now.faults != 0u && now.fault_resets_taken >= loop.resets_requested()) {
                const std::string why = "a fault is latched (" + fault_list(now.faults).dump() +
                                        "): reset it first (hapticctl reset)";
                return {.reply = error_reply(request.id, "arm refused: " + why),
                        .journal = "control: arm from " + peer.describe() + " refused: " + why};
            }
            loop.arm();
            break;
        case RequestKind::disarm:
            loop.disarm();
            break;
        case RequestKind::reset:
            loop.reset();
            break;
        case RequestKind::coupling:
            return set_coupling(request, peer, loop, facts, now);
        case RequestKind::subscribe: {
            const double rate_hz = request.rate_hz.value_or(kDefaultSubscribeRateHz);
            return {.reply = ok_reply(request.id, {{"rate_hz", rate_hz}, {"axes", facts.axes}}),
                    .journal = "control: " + peer.describe() + " subscribed at " +
                               input::format_number(rate_hz) + " Hz",
                    .subscribe_hz = rate_hz};
        }
        case RequestKind::unsubscribe:
            return {.reply = ok_reply(request.id), .journal = {}, .subscribe_hz = 0.0};
        case RequestKind::record_start:
        case RequestKind::record_stop:
            return record(request, peer, facts);
        case RequestKind::scene_load:
            return load_scene(request, peer, loop, facts, now);
        case RequestKind::identify:
            return identify(request, peer, facts);
        case RequestKind::mark:
            return mark(request, peer, loop, facts, now);
    }
    // The servo thread takes the request at the start of its next tick; the reply says the
    // state it was asked in, and `status` shows what came of it.
    return {.reply = ok_reply(request.id, {{"state_before", state_of(now)}}),
            .journal = "control: " + name + " from " + peer.describe() + " (state was " +
                       state_of(now) + ")"};
}

}  // namespace hapticd::daemon::control_socket
