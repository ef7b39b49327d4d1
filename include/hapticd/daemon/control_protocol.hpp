// The control protocol (docs/control.md): one JSON object per line each way on hapticd's
// control socket. This file is the protocol's one statement in code: its version, its
// limits, its requests and how a line becomes a request or an error. The daemon's server
// (socket/server.hpp) and hapticctl both use it.
#pragma once

#include <sys/un.h>

#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

namespace hapticd::daemon::control_socket {

/// The `v` of every request and reply; a request of another version is refused.
inline constexpr int kProtocolVersion = 1;
/// The longest request line, its newline included.
inline constexpr std::size_t kMaxRequestBytes = 4096;

/// The slowest and fastest telemetry stream a client may subscribe to, and the default rate.
/// The slowest is one event in about 17 minutes; its period still fits the server's clock.
inline constexpr double kMinSubscribeRateHz = 0.001;
inline constexpr double kMaxSubscribeRateHz = 100.0;
inline constexpr double kDefaultSubscribeRateHz = 10.0;

/// The longest control socket path (--socket, hapticd's and hapticctl's): what a Unix socket
/// address holds, sun_path less its terminating 0 (107 bytes on Linux).
inline constexpr std::size_t kMaxSocketPathBytes = sizeof(sockaddr_un::sun_path) - 1;

/// The longest path a record_start or scene_load request may name (PATH_MAX less its
/// terminator).
inline constexpr std::size_t kMaxRequestPathBytes = 4095;

/// The longest text a mark request may carry, in bytes (UTF-8).
inline constexpr std::size_t kMaxMarkTextBytes = 200;

/// Why `text` cannot be a mark (empty, too long, a control character at byte N), or nullopt
/// when it can. UTF-8 validity is the JSON reader's (parse_request refuses a line without it).
std::optional<std::string> mark_text_problem(std::string_view text);

enum class RequestKind {
    status,
    arm,
    disarm,
    reset,
    coupling,
    subscribe,
    unsubscribe,
    record_start,
    record_stop,
    scene_load,
    identify,
    mark
};

/// The name on the wire ("status", ...).
std::string_view request_name(RequestKind kind) noexcept;

struct Request {
    RequestKind kind = RequestKind::status;
    nlohmann::json id{};  ///< echoed in the reply; null when the request had none
    /// coupling: "stiffness" (required), k_c of (16), N/m; finite. Its range is the
    /// daemon's to check ([coupling] stiffness), as is the stability check.
    std::optional<double> stiffness_n_per_m{};
    /// coupling: "damping" (optional: the damping in force stays), b_c, N s/m; finite.
    std::optional<double> damping_n_s_per_m{};
    /// subscribe: "rate_hz" (optional, kDefaultSubscribeRateHz), the telemetry events a
    /// second; kMinSubscribeRateHz <= rate_hz <= kMaxSubscribeRateHz.
    std::optional<double> rate_hz{};
    /// record_start: "path" (required), the file the recording goes to; identify: "path"
    /// (optional: the daemon names one), the excitation's log; each a file name alone or an
    /// absolute path. scene_load: "path" (required), the scene file to render, absolute. At
    /// most kMaxRequestPathBytes, no control character. Whether the daemon may create or read
    /// it is the daemon's to say (docs/control.md, "Paths and strings").
    std::optional<std::string> path{};
    /// mark: "text" (required), the trial marker the recordings carry (docs/control.md,
    /// "mark"): 1 to 200 bytes of UTF-8, no control character.
    std::optional<std::string> text{};
};

/// A line, parsed: the request, or the error to reply with (the id is kept where the line
/// had one, so that the client can match the error to its request).
// bugprone-exception-escape sees a throw that nlohmann::json's destructor can reach only when
// freeing a nested value runs out of memory (its std::vector of children): not a case here.
// NOLINTNEXTLINE(bugprone-exception-escape)
struct ParsedRequest {
    std::optional<Request> request;
    nlohmann::json id;
    std::string error;  ///< names the field, the value and what is allowed
};

/// Parses one request line (without its newline).
ParsedRequest parse_request(std::string_view line);

/// A request line, its newline included: {"v":1,"id":id,"request":name} and the request's
/// own fields (coupling: stiffness, and damping when given).
std::string request_line(const Request& request);
std::string request_line(RequestKind kind, const nlohmann::json& id = nullptr);

/// A reply line, its newline included: `body` with "v", "id" and "ok": true added.
std::string ok_reply(const nlohmann::json& id, nlohmann::json body = nlohmann::json::object());
/// A reply line, its newline included: {"v":1,"id":id,"ok":false,"error":message}.
std::string error_reply(const nlohmann::json& id, std::string_view message);
/// An event line (a subscription's telemetry), its newline included: `body` with "v" and
/// "event": name added. Events carry "event" and never "ok", replies the other way round.
std::string event_line(std::string_view name, nlohmann::json body);

}  // namespace hapticd::daemon::control_socket
