#include "control_requests.hpp"

#include <string_view>
#include <vector>

#include "hapticd/servo/faults.hpp"
#include "hapticd/servo/servo_state.hpp"

namespace hapticd::daemon::control {
namespace {

nlohmann::json first_axes(const std::array<double, servo::kMaxAxes>& v, int axes) {
    return std::vector<double>(v.begin(), v.begin() + axes);
}

nlohmann::json fault_list(std::uint32_t faults) {
    nlohmann::json names = nlohmann::json::array();
    servo::for_each_fault(faults, [&](std::string_view name) { names.push_back(name); });
    return names;
}

std::string who(const Peer& peer) {
    return "pid " + std::to_string(peer.pid) + " uid " + std::to_string(peer.uid);
}

std::string state_of(const servo::StatusSnapshot& s) {
    return std::string(servo::servo_state_name(s.state));
}

}  // namespace

nlohmann::json status_body(const servo::StatusSnapshot& s, const RunFacts& facts) {
    nlohmann::json j;
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
    j["wake_latency_us"] = {{"p50", s.wake_p50_us}, {"p99", s.wake_p99_us}, {"max", s.wake_max_us}};
    j["tick_compute_us"] = {
        {"p50", s.compute_p50_us}, {"p99", s.compute_p99_us}, {"max", s.compute_max_us}};
    j["link"] = {{"read_timeouts", s.read_timeouts}, {"link_recoveries", s.link_recoveries}};
    j["axes"] = facts.axes;
    j["x_m"] = first_axes(s.x_m, facts.axes);
    j["xe_m"] = first_axes(s.xe_m, facts.axes);
    j["f_n"] = first_axes(s.f_n, facts.axes);
    j["device"] = facts.device;
    j["config_path"] = facts.config_path;
    return j;
}

Answer answer(const Request& request, const Peer& peer, ServoControl& loop, const RunFacts& facts) {
    const servo::StatusSnapshot now = loop.status();
    const std::string name(request_name(request.kind));
    switch (request.kind) {
        case RequestKind::status:
            return {.reply = ok_reply(request.id, {{"status", status_body(now, facts)}}),
                    .journal = {}};
        case RequestKind::arm:
            if (now.faults != 0u) {
                const std::string why = "a fault is latched (" + fault_list(now.faults).dump() +
                                        "): reset it first (hapticctl reset)";
                return {.reply = error_reply(request.id, "arm refused: " + why),
                        .journal = "control: arm from " + who(peer) + " refused: " + why};
            }
            loop.arm();
            break;
        case RequestKind::disarm:
            loop.disarm();
            break;
        case RequestKind::reset:
            loop.reset();
            break;
    }
    // The servo thread takes the request at the start of its next tick; the reply says the
    // state it was asked in, and `status` shows what came of it.
    return {.reply = ok_reply(request.id, {{"state_before", state_of(now)}}),
            .journal =
                "control: " + name + " from " + who(peer) + " (state was " + state_of(now) + ")"};
}

}  // namespace hapticd::daemon::control
