#include "run/service_notifier.hpp"

#include <sys/socket.h>
#include <sys/un.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>

namespace hapticd::daemon {
namespace {

/// NOTIFY_SOCKET as an address: a path, or "@name" in the abstract namespace (sd_notify(3)).
bool notify_address(const char* socket, sockaddr_un& address, socklen_t& length) {
    const std::size_t size = std::strlen(socket);
    if (size == 0 || size >= sizeof address.sun_path || (socket[0] != '/' && socket[0] != '@')) {
        return false;
    }
    address = {};
    address.sun_family = AF_UNIX;
    std::memcpy(address.sun_path, socket, size);
    if (socket[0] == '@') address.sun_path[0] = '\0';
    length =
        static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + size + (socket[0] == '@' ? 0 : 1));
    return true;
}

}  // namespace

ServiceNotifier::ServiceNotifier() {
    const char* socket = std::getenv("NOTIFY_SOCKET");
    if (socket == nullptr || !notify_address(socket, address_, address_length_)) return;
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    enabled_ = fd_ >= 0;
    std::uint64_t timeout_us = 0;
    // > 0: WATCHDOG_USEC is set and WATCHDOG_PID, if set, is this process.
    if (enabled_ && sd_watchdog_enabled(0, &timeout_us) > 0 && timeout_us > 0) {
        watchdog_timeout_ = std::chrono::microseconds(static_cast<std::int64_t>(timeout_us));
    }
}

ServiceNotifier::~ServiceNotifier() {
    if (fd_ >= 0) ::close(fd_);
}

void ServiceNotifier::send(const std::string& message) {
    if (!enabled_) return;
    // Never waits: libsystemd 252's sd_notify() blocks while the manager's queue is full (10
    // datagrams), which would hold this thread and with it the run's duration and status. A
    // message the manager has no room for is dropped and counted.
    const ssize_t sent = ::sendto(fd_, message.data(), message.size(), MSG_DONTWAIT | MSG_NOSIGNAL,
                                  reinterpret_cast<const sockaddr*>(&address_), address_length_);
    if (sent < 0) ++dropped_;
}

void ServiceNotifier::ready(const std::string& status) {
    if (ready_sent_) return;
    ready_sent_ = true;
    send("READY=1\nSTATUS=" + status);
}

void ServiceNotifier::status(const std::string& status) { send("STATUS=" + status); }

void ServiceNotifier::watch(std::uint64_t tick, Clock::time_point now) {
    if (!watchdog_timeout_ || !ready_sent_ || tick == pinged_tick_) return;
    if (pings_ > 0 && now - last_ping_ < *watchdog_timeout_ / 2) return;
    send("WATCHDOG=1");
    pinged_tick_ = tick;
    last_ping_ = now;
    ++pings_;
}

void ServiceNotifier::stopping(const std::string& status) { send("STOPPING=1\nSTATUS=" + status); }

}  // namespace hapticd::daemon
