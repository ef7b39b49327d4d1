// The control socket's server with a handler that counts what reached it, and the client's
// side: the fixture of control_server_test.cpp and control_server_work_test.cpp.
#pragma once

#include <atomic>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "socket/server.hpp"
#include "unix_client.hpp"

namespace hapticd::daemon::control_socket {

using hapticd::testing::UnixClient;

// A server whose handler answers status with the number of requests it has seen.
struct Served {
    explicit Served(const std::string& path, Limits limits = {})
        : server(std::make_unique<SocketServer>(path, limits, /*group=*/"")) {
        server->start([this](const Request& request, const Peer& peer) {
            if (request.kind == RequestKind::coupling) {  // through the worker
                return Answer{.later = [id = request.id] {
                    return Answer{.reply = ok_reply(id, {{"worked", true}})};
                }};
            }
            const int n = ++requests;
            last_peer_pid = peer.pid;
            return Answer{.reply = ok_reply(request.id, {{"seen", n}}),
                          .journal = request.kind == RequestKind::status
                                         ? std::string()
                                         : "changed by pid " + std::to_string(peer.pid) +
                                               (request.id.is_string()
                                                    ? " for " + request.id.get<std::string>()
                                                    : std::string())};
        });
    }
    std::atomic<int> requests{0};
    std::atomic<pid_t> last_peer_pid{0};
    std::unique_ptr<SocketServer> server;
};

inline nlohmann::json reply_of(UnixClient& client) {
    const auto line = client.line();
    if (!line) return nullptr;
    return nlohmann::json::parse(*line);
}

inline bool any_message_has(const std::vector<std::string>& messages, const std::string& text) {
    for (const std::string& m : messages) {
        if (m.find(text) != std::string::npos) return true;
    }
    return false;
}

inline const std::string kStatus = R"({"v":1,"id":1,"request":"status"})"
                                   "\n";

}  // namespace hapticd::daemon::control_socket
