#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <utility>
#include <vector>

#include "hapticd/daemon/control_protocol.hpp"
#include "hapticd/input/printable.hpp"

namespace hapticd::daemon::control_socket {
namespace {

constexpr std::array kRequests{
    RequestKind::status,      RequestKind::arm,          RequestKind::disarm,
    RequestKind::reset,       RequestKind::coupling,     RequestKind::subscribe,
    RequestKind::unsubscribe, RequestKind::record_start, RequestKind::record_stop,
    RequestKind::scene_load,  RequestKind::identify,     RequestKind::mark};

// The fields each request takes besides v, id and request.
std::vector<std::string_view> own_fields(RequestKind kind) {
    if (kind == RequestKind::coupling) return {"stiffness", "damping"};
    if (kind == RequestKind::subscribe) return {"rate_hz"};
    if (kind == RequestKind::mark) return {"text"};
    if (kind == RequestKind::record_start || kind == RequestKind::scene_load ||
        kind == RequestKind::identify) {
        return {"path"};
    }
    return {};
}

std::string request_names() {
    std::string names;
    for (const RequestKind kind : kRequests) {
        if (!names.empty()) names += ", ";
        names += request_name(kind);
    }
    return names;
}

// A value for a message: its JSON, cut short.
std::string shown(const nlohmann::json& value) {
    std::string text = value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    constexpr std::size_t kLongest = 40;
    if (text.size() > kLongest) text = text.substr(0, kLongest) + "...";
    return text;
}

// A finite number, or the error that says what it is instead.
std::optional<double> finite_number(const nlohmann::json& j, std::string_view field,
                                    std::string& error) {
    if (!j.is_number() || !std::isfinite(j.get<double>())) {
        error = "\"" + std::string(field) + "\" = " + shown(j) + ": must be a finite number";
        return std::nullopt;
    }
    return j.get<double>();
}

}  // namespace

std::optional<std::string> mark_text_problem(std::string_view text) {
    if (text.empty()) return "empty: a mark needs a text (1 to 200 bytes)";
    if (text.size() > kMaxMarkTextBytes) {
        return std::to_string(text.size()) + " bytes: allowed 1 to " +
               std::to_string(kMaxMarkTextBytes);
    }
    if (const std::size_t at = input::find_control(text); at != std::string_view::npos) {
        return "a control character at byte " + std::to_string(at + 1) +
               ": a mark is one line of text without them";
    }
    return std::nullopt;
}

std::string_view request_name(RequestKind kind) noexcept {
    switch (kind) {
        case RequestKind::status:
            return "status";
        case RequestKind::arm:
            return "arm";
        case RequestKind::disarm:
            return "disarm";
        case RequestKind::reset:
            return "reset";
        case RequestKind::coupling:
            return "coupling";
        case RequestKind::subscribe:
            return "subscribe";
        case RequestKind::unsubscribe:
            return "unsubscribe";
        case RequestKind::record_start:
            return "record_start";
        case RequestKind::record_stop:
            return "record_stop";
        case RequestKind::scene_load:
            return "scene_load";
        case RequestKind::identify:
            return "identify";
        case RequestKind::mark:
            return "mark";
    }
    return "unknown";
}

ParsedRequest parse_request(std::string_view line) {
    ParsedRequest parsed;
    // nlohmann's reader ends its input at a NUL byte, so "disarm\0arm" would be read as a
    // disarm: a line that holds one is refused whole.
    if (const std::size_t nul = line.find('\0'); nul != std::string_view::npos) {
        parsed.error = "the request holds a NUL byte (byte " + std::to_string(nul + 1) +
                       " of the line): one JSON object per line, docs/control.md";
        return parsed;
    }
    const nlohmann::json j = nlohmann::json::parse(line, nullptr, /*allow_exceptions=*/false);
    if (j.is_discarded()) {
        parsed.error = "the request is not JSON (one JSON object per line, docs/control.md)";
        return parsed;
    }
    if (!j.is_object()) {
        parsed.error = "the request " + shown(j) + " is not a JSON object";
        return parsed;
    }
    if (const auto id = j.find("id"); id != j.end()) {
        if (!id->is_number_integer() && !id->is_string() && !id->is_null()) {
            parsed.error = "\"id\" = " + shown(*id) + ": must be an integer, a string or null";
            return parsed;
        }
        parsed.id = *id;
    }
    const auto v = j.find("v");
    if (v == j.end()) {
        parsed.error = "\"v\" is missing: the protocol version, " +
                       std::to_string(kProtocolVersion) + " for this hapticd";
        return parsed;
    }
    if (!v->is_number_integer() || v->get<std::int64_t>() != kProtocolVersion) {
        parsed.error = "\"v\" = " + shown(*v) + ": this hapticd speaks control protocol version " +
                       std::to_string(kProtocolVersion);
        return parsed;
    }
    const auto name = j.find("request");
    if (name == j.end() || !name->is_string()) {
        parsed.error = (name == j.end() ? std::string("\"request\" is missing")
                                        : "\"request\" = " + shown(*name) + " is not a string") +
                       ": one of " + request_names();
        return parsed;
    }
    const auto kind = std::find_if(kRequests.begin(), kRequests.end(),
                                   [&](RequestKind k) { return *name == request_name(k); });
    if (kind == kRequests.end()) {
        parsed.error = "unknown request " + shown(*name) + ": one of " + request_names();
        return parsed;
    }
    const std::vector<std::string_view> own = own_fields(*kind);
    for (auto it = j.begin(); it != j.end(); ++it) {
        if (it.key() == "v" || it.key() == "id" || it.key() == "request") continue;
        if (std::find(own.begin(), own.end(), it.key()) != own.end()) continue;
        std::string allowed = "v, id, request";
        for (const std::string_view field : own) allowed += ", " + std::string(field);
        parsed.error = "unknown field \"" + it.key() + "\" in a \"" + name->get<std::string>() +
                       "\" request: it takes only " + allowed;
        return parsed;
    }
    Request request{.kind = *kind, .id = parsed.id};
    if (*kind == RequestKind::coupling) {
        const auto stiffness = j.find("stiffness");
        if (stiffness == j.end()) {
            parsed.error = "\"stiffness\" is missing: a coupling request sets k_c, N/m";
            return parsed;
        }
        request.stiffness_n_per_m = finite_number(*stiffness, "stiffness", parsed.error);
        if (!request.stiffness_n_per_m) return parsed;
        if (const auto damping = j.find("damping"); damping != j.end()) {
            request.damping_n_s_per_m = finite_number(*damping, "damping", parsed.error);
            if (!request.damping_n_s_per_m) return parsed;
        }
    }
    if (*kind == RequestKind::subscribe) {
        request.rate_hz = kDefaultSubscribeRateHz;
        if (const auto rate = j.find("rate_hz"); rate != j.end()) {
            request.rate_hz = finite_number(*rate, "rate_hz", parsed.error);
            if (!request.rate_hz) return parsed;
            if (!(*request.rate_hz >= kMinSubscribeRateHz) ||
                *request.rate_hz > kMaxSubscribeRateHz) {
                parsed.error = "\"rate_hz\" = " + shown(*rate) +
                               ": allowed >= 0.001 and <= 100 (events a second)";
                return parsed;
            }
        }
    }
    if (*kind == RequestKind::record_start || *kind == RequestKind::scene_load ||
        (*kind == RequestKind::identify && j.contains("path"))) {
        const auto path = j.find("path");
        if (path == j.end()) {
            parsed.error = *kind == RequestKind::record_start
                               ? "\"path\" is missing: record_start names the file to record to"
                               : "\"path\" is missing: scene_load names the scene file to render";
            return parsed;
        }
        if (!path->is_string()) {
            parsed.error = "\"path\" = " + shown(*path) + ": must be a string";
            return parsed;
        }
        const std::string& text = path->get_ref<const std::string&>();
        if (input::find_control(text) != std::string::npos) {
            parsed.error = "\"path\" = " + shown(*path) +
                           ": holds a control character: allowed a path without them";
            return parsed;
        }
        // A recording or a log may be a name alone: the daemon makes it in its outputs
        // directory (docs/control.md, "Paths and strings"), which decides what else it accepts.
        const bool name_alone_allowed = *kind != RequestKind::scene_load;
        if (text.empty() || text.size() > kMaxRequestPathBytes ||
            (text.front() != '/' && !name_alone_allowed)) {
            parsed.error = "\"path\" = " + shown(*path) +
                           (name_alone_allowed
                                ? ": a file name, or an absolute path of at most 4095 bytes, is "
                                  "needed"
                                : ": an absolute path of at most 4095 bytes is needed (the "
                                  "daemon's working directory is not the client's)");
            return parsed;
        }
        request.path = text;
    }
    if (*kind == RequestKind::mark) {
        const auto text = j.find("text");
        if (text == j.end() || !text->is_string()) {
            parsed.error = (text == j.end() ? std::string("\"text\" is missing")
                                            : "\"text\" = " + shown(*text) + " is not a string") +
                           ": mark names the trial, 1 to 200 bytes of text";
            return parsed;
        }
        const std::string& value = text->get_ref<const std::string&>();
        if (const std::optional<std::string> problem = mark_text_problem(value)) {
            parsed.error = "\"text\" = " + shown(*text) + ": " + *problem;
            return parsed;
        }
        request.text = value;
    }
    parsed.request = request;
    return parsed;
}

std::string request_line(const Request& request) {
    nlohmann::json j{{"v", kProtocolVersion}, {"request", request_name(request.kind)}};
    if (!request.id.is_null()) j["id"] = request.id;
    if (request.stiffness_n_per_m) j["stiffness"] = *request.stiffness_n_per_m;
    if (request.damping_n_s_per_m) j["damping"] = *request.damping_n_s_per_m;
    if (request.rate_hz) j["rate_hz"] = *request.rate_hz;
    if (request.path) j["path"] = *request.path;
    if (request.text) j["text"] = *request.text;
    return j.dump() + "\n";
}

std::string request_line(RequestKind kind, const nlohmann::json& id) {
    return request_line(Request{.kind = kind, .id = id});
}

std::string ok_reply(const nlohmann::json& id, nlohmann::json body) {
    body["v"] = kProtocolVersion;
    body["id"] = id;
    body["ok"] = true;
    return body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

std::string error_reply(const nlohmann::json& id, std::string_view message) {
    const nlohmann::json j{
        {"v", kProtocolVersion}, {"id", id}, {"ok", false}, {"error", std::string(message)}};
    return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

std::string event_line(std::string_view name, nlohmann::json body) {
    body["v"] = kProtocolVersion;
    body["event"] = std::string(name);
    return body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

}  // namespace hapticd::daemon::control_socket
