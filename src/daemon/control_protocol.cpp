#include "hapticd/daemon/control_protocol.hpp"

#include <array>
#include <utility>

namespace hapticd::daemon::control {
namespace {

constexpr std::array kRequests{RequestKind::status, RequestKind::arm, RequestKind::disarm,
                               RequestKind::reset};

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

}  // namespace

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
    }
    return "unknown";
}

ParsedRequest parse_request(std::string_view line) {
    ParsedRequest parsed;
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
    for (auto it = j.begin(); it != j.end(); ++it) {
        if (it.key() != "v" && it.key() != "id" && it.key() != "request") {
            parsed.error = "unknown field \"" + it.key() + "\" in a \"" + name->get<std::string>() +
                           "\" request: it takes only v, id, request";
            return parsed;
        }
    }
    for (const RequestKind kind : kRequests) {
        if (*name == request_name(kind)) {
            parsed.request = Request{.kind = kind, .id = parsed.id};
            return parsed;
        }
    }
    parsed.error = "unknown request " + shown(*name) + ": one of " + request_names();
    return parsed;
}

std::string request_line(RequestKind kind, const nlohmann::json& id) {
    nlohmann::json j{{"v", kProtocolVersion}, {"request", request_name(kind)}};
    if (!id.is_null()) j["id"] = id;
    return j.dump() + "\n";
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

}  // namespace hapticd::daemon::control
