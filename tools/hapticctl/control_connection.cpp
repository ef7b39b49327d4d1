#include "control_connection.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>

namespace hapticd::ctl {
namespace {

std::string connect_advice(int error) {
    switch (error) {
        case ENOENT:
        case ECONNREFUSED:
            return "no hapticd is serving it (is the instance running? systemctl status "
                   "hapticd@NAME; or give hapticd --socket)";
        case EACCES:
        case EPERM:
            return "permission denied: the socket is mode 0660, group hapticd; join that group "
                   "(adduser $USER hapticd) or run as the daemon's user";
        default:
            return std::strerror(error);
    }
}

}  // namespace

std::string instance_socket(const std::string& name) { return "/run/hapticd/" + name + ".sock"; }

ControlConnection::ControlConnection(std::string socket_path, std::chrono::milliseconds timeout)
    : path_(std::move(socket_path)), timeout_(timeout) {
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    using daemon::control_socket::kMaxSocketPathBytes;
    if (path_.empty() || path_.size() > kMaxSocketPathBytes) {
        throw ConnectionError("socket \"" + path_ + "\": a path of 1 to " +
                              std::to_string(kMaxSocketPathBytes) + " bytes is needed");
    }
    std::memcpy(address.sun_path, path_.data(), path_.size());
    fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0) throw ConnectionError(std::string("socket(): ") + std::strerror(errno));
    if (::connect(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0) {
        const int error = errno;
        ::close(fd_);
        fd_ = -1;
        throw ConnectionError("cannot connect to " + path_ + ": " + connect_advice(error));
    }
}

ControlConnection::~ControlConnection() {
    if (fd_ >= 0) ::close(fd_);
}

nlohmann::json ControlConnection::request(daemon::control_socket::RequestKind kind) {
    return request(daemon::control_socket::Request{.kind = kind});
}

nlohmann::json ControlConnection::request(daemon::control_socket::Request request) {
    const std::int64_t id = next_id_++;
    request.id = id;
    const std::string line = daemon::control_socket::request_line(request);
    for (std::size_t sent = 0; sent < line.size();) {
        const ssize_t n = ::send(fd_, line.data() + sent, line.size() - sent, MSG_NOSIGNAL);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) {
            throw ConnectionError("hapticd at " + path_ + " went away: " + std::strerror(errno));
        }
        sent += static_cast<std::size_t>(n);
    }
    for (;;) {
        nlohmann::json reply = read_message();
        if (reply.contains("event")) continue;  // a subscription's, between the replies
        // A reply without our id is one the daemon sent on its own (a refusal): it is ours.
        if (reply.value("id", nlohmann::json(id)) == id || reply["id"].is_null()) return reply;
    }
}

nlohmann::json ControlConnection::next_event() {
    for (;;) {
        nlohmann::json message = read_message();
        if (message.contains("event")) return message;
        // A reply now is the daemon's own word (a refusal, the idle close): it ends the stream.
        if (!message.value("ok", true)) {
            throw ConnectionError("hapticd at " + path_ + ": " +
                                  message.value("error", std::string("refused")));
        }
    }
}

nlohmann::json ControlConnection::read_message() {
    const std::string line = read_line();
    nlohmann::json message = nlohmann::json::parse(line, nullptr, false);
    if (message.is_discarded() || !message.is_object() ||
        (!message.contains("ok") && !message.contains("event"))) {
        throw ConnectionError("hapticd at " + path_ +
                              " replied outside the protocol: " + line.substr(0, 80));
    }
    return message;
}

std::string ControlConnection::read_line() {
    const auto deadline = std::chrono::steady_clock::now() + timeout_;
    for (;;) {
        if (const std::size_t end = pending_.find('\n'); end != std::string::npos) {
            std::string line = pending_.substr(0, end);
            pending_.erase(0, end + 1);
            return line;
        }
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
            deadline - std::chrono::steady_clock::now());
        pollfd p{.fd = fd_, .events = POLLIN, .revents = 0};
        const int ready = left.count() > 0 ? ::poll(&p, 1, static_cast<int>(left.count())) : 0;
        if (ready < 0 && errno == EINTR) {
            if (interrupt_ != nullptr && *interrupt_ != 0) throw Interrupted();
            continue;
        }
        if (ready == 0) {
            throw ConnectionError("hapticd at " + path_ + " did not reply within " +
                                  std::to_string(timeout_.count()) + " ms");
        }
        std::array<char, 4096> buffer{};
        const ssize_t got = ::recv(fd_, buffer.data(), buffer.size(), 0);
        if (got < 0 && errno == EINTR) continue;
        if (got <= 0) throw ConnectionError("hapticd at " + path_ + " closed the connection");
        pending_.append(buffer.data(), static_cast<std::size_t>(got));
        constexpr std::size_t kLongestReply = std::size_t{1} << 20;
        if (pending_.size() > kLongestReply) {
            throw ConnectionError("hapticd at " + path_ + " sent a reply longer than 1 MiB");
        }
    }
}

}  // namespace hapticd::ctl
