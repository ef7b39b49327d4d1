#include "hapticd/daemon/control_server.hpp"

#include <fcntl.h>
#include <grp.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <utility>

namespace hapticd::daemon::control {

struct ControlServer::Client {
    int fd = -1;
    Peer peer;
    std::string in;   // bytes of the request line being read
    std::string out;  // replies not yet taken by the client
    bool read_closed = false;
    bool closing = false;                          // close once `out` is flushed
    std::uint32_t watched = EPOLLIN | EPOLLRDHUP;  // the events registered with epoll
};

namespace {

std::string errno_text(int error) { return std::strerror(error); }

sockaddr_un address_of(const std::string& path) {
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    if (path.empty() || path.size() >= sizeof(address.sun_path)) {
        throw ControlSocketError("control socket \"" + path + "\": a path of 1 to " +
                                 std::to_string(sizeof(address.sun_path) - 1) +
                                 " bytes is needed (--socket)");
    }
    std::memcpy(address.sun_path, path.data(), path.size());
    return address;
}

// A socket file left by a daemon that died is replaced; a live one is another daemon's.
void clear_stale_socket(const std::string& path, const sockaddr_un& address) {
    struct stat st {};
    if (::lstat(path.c_str(), &st) != 0) return;  // nothing there
    if (!S_ISSOCK(st.st_mode)) {
        throw ControlSocketError("control socket \"" + path +
                                 "\": the path exists and is not a socket; remove it or "
                                 "choose another with --socket");
    }
    const int probe = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (probe < 0) throw ControlSocketError("control socket: socket(): " + errno_text(errno));
    const bool live =
        ::connect(probe, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) == 0;
    ::close(probe);
    if (live) {
        throw ControlSocketError("control socket \"" + path +
                                 "\" is in use: another hapticd answers on it (one socket per "
                                 "instance: --socket, or the instance name)");
    }
    ::unlink(path.c_str());
}

void give_group(const std::string& path, const std::string& group_name, std::string& note) {
    if (group_name.empty()) return;
    std::array<char, 4096> buffer{};
    struct group entry {};
    struct group* found = nullptr;
    if (::getgrnam_r(group_name.c_str(), &entry, buffer.data(), buffer.size(), &found) != 0 ||
        found == nullptr) {
        note = "control socket " + path + ": no group \"" + group_name +
               "\" on this system, so only this daemon's user may connect (docs/control.md)";
        return;
    }
    if (::chown(path.c_str(), static_cast<uid_t>(-1), found->gr_gid) != 0) {
        note = "control socket " + path + ": could not give it to group \"" + group_name +
               "\": " + errno_text(errno) + "; only this daemon's user may connect";
    }
}

}  // namespace

ControlServer::ControlServer(std::string path, Limits limits, std::string group)
    : path_(std::move(path)), limits_(limits) {
    const sockaddr_un address = address_of(path_);
    clear_stale_socket(path_, address);
    listen_fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    if (listen_fd_ < 0) throw ControlSocketError("control socket: socket(): " + errno_text(errno));
    // Created as 0660 at once: no moment when others could connect.
    const mode_t old_mask = ::umask(0117);
    const int bound =
        ::bind(listen_fd_, reinterpret_cast<const sockaddr*>(&address), sizeof(address));
    const int bind_error = errno;
    ::umask(old_mask);
    if (bound != 0) {
        ::close(listen_fd_);
        throw ControlSocketError("control socket \"" + path_ +
                                 "\": bind(): " + errno_text(bind_error));
    }
    ::chmod(path_.c_str(), 0660);
    std::string group_note;
    give_group(path_, group, group_note);
    if (!group_note.empty()) note(group_note);
    epoll_fd_ = ::epoll_create1(EPOLL_CLOEXEC);
    stop_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if (::listen(listen_fd_, limits_.max_clients) != 0 || epoll_fd_ < 0 || stop_fd_ < 0) {
        const int error = errno;
        ::unlink(path_.c_str());
        for (const int fd : {listen_fd_, epoll_fd_, stop_fd_}) {
            if (fd >= 0) ::close(fd);
        }
        throw ControlSocketError("control socket \"" + path_ + "\": " + errno_text(error));
    }
    epoll_event event{};
    event.events = EPOLLIN;
    event.data.fd = listen_fd_;
    ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, listen_fd_, &event);
    event.data.fd = stop_fd_;
    ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, stop_fd_, &event);
}

ControlServer::~ControlServer() {
    stop();
    for (const Client& client : clients_) ::close(client.fd);
    ::unlink(path_.c_str());
    for (const int fd : {listen_fd_, epoll_fd_, stop_fd_}) ::close(fd);
}

void ControlServer::start(Handler handler) {
    handler_ = std::move(handler);
    thread_ = std::thread([this] { serve(); });
}

void ControlServer::stop() noexcept {
    const std::uint64_t one = 1;
    (void)!::write(stop_fd_, &one, sizeof(one));
    if (thread_.joinable()) thread_.join();
}

std::vector<std::string> ControlServer::take_messages() {
    const std::lock_guard lock(messages_mutex_);
    return std::exchange(messages_, {});
}

void ControlServer::note(std::string message) {
    const std::lock_guard lock(messages_mutex_);
    constexpr std::size_t kMostMessages = 256;  // a flood of connects does not grow this
    if (messages_.size() < kMostMessages) messages_.push_back(std::move(message));
}

void ControlServer::serve() noexcept {
    std::array<epoll_event, 32> events{};
    for (;;) {
        const int n = ::epoll_wait(epoll_fd_, events.data(), static_cast<int>(events.size()), -1);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) {
            note("control socket " + path_ + ": epoll_wait(): " + errno_text(errno) +
                 "; the socket no longer answers");
            return;
        }
        for (int i = 0; i < n; ++i) {
            const int fd = events[static_cast<std::size_t>(i)].data.fd;
            const std::uint32_t what = events[static_cast<std::size_t>(i)].events;
            if (fd == stop_fd_) return;
            if (fd == listen_fd_) {
                accept_clients();
                continue;
            }
            const auto it = std::find_if(clients_.begin(), clients_.end(),
                                         [fd](const Client& c) { return c.fd == fd; });
            if (it == clients_.end()) continue;  // closed earlier in this batch
            Client& client = *it;
            if ((what & EPOLLOUT) != 0u) flush(client);
            if ((what & (EPOLLIN | EPOLLRDHUP | EPOLLHUP | EPOLLERR)) != 0u) read_from(client);
        }
        // Clients done with: everything answered and flushed, or dropped.
        for (std::size_t i = clients_.size(); i-- > 0;) {
            Client& client = clients_[i];
            if (client.closing && client.out.empty()) close_client(client.fd);
        }
    }
}

void ControlServer::accept_clients() {
    for (;;) {
        const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
        if (fd < 0) return;  // EAGAIN: none left; anything else: try at the next event
        Client client;
        client.fd = fd;
        ucred credentials{};
        socklen_t size = sizeof(credentials);
        if (::getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &credentials, &size) == 0) {
            client.peer =
                Peer{.pid = credentials.pid, .uid = credentials.uid, .gid = credentials.gid};
        }
        const std::string who = "pid " + std::to_string(client.peer.pid) + " uid " +
                                std::to_string(client.peer.uid) + " gid " +
                                std::to_string(client.peer.gid);
        if (static_cast<int>(clients_.size()) >= limits_.max_clients) {
            const std::string refusal = error_reply(
                nullptr, "too many clients: this hapticd serves " +
                             std::to_string(limits_.max_clients) + " at once; try again later");
            (void)!::send(fd, refusal.data(), refusal.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
            ::close(fd);
            note("control: refused " + who + ": " + std::to_string(limits_.max_clients) +
                 " clients already connected");
            continue;
        }
        note("control: client connected: " + who);
        epoll_event event{};
        event.events = EPOLLIN | EPOLLRDHUP;
        event.data.fd = fd;
        ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, fd, &event);
        clients_.push_back(std::move(client));
    }
}

void ControlServer::read_from(Client& client) {
    std::array<char, 4096> buffer{};
    // At most 16 reads a wake: epoll (level-triggered) comes back for the rest, so a client
    // that writes as fast as it reads cannot keep this thread from the others, or from stop().
    constexpr int kReadsPerWake = 16;
    for (int reads = 0; reads < kReadsPerWake && !client.read_closed && !client.closing; ++reads) {
        const ssize_t got = ::recv(client.fd, buffer.data(), buffer.size(), MSG_DONTWAIT);
        if (got < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
        if (got < 0 && errno == EINTR) continue;
        if (got <= 0) {  // the client shut its side down, or the connection broke
            client.read_closed = true;
            client.closing = true;
            break;
        }
        client.in.append(buffer.data(), static_cast<std::size_t>(got));
        answer_lines(client);
    }
    flush(client);
}

void ControlServer::answer_lines(Client& client) {
    std::size_t begin = 0;
    for (std::size_t end; (end = client.in.find('\n', begin)) != std::string::npos;
         begin = end + 1) {
        if (client.closing) break;
        if (end - begin + 1 > kMaxRequestBytes) {
            client.out += error_reply(
                nullptr, "a request line of " + std::to_string(end - begin + 1) +
                             " bytes: at most " + std::to_string(kMaxRequestBytes) + " allowed");
            client.closing = true;
            break;
        }
        std::string_view line(client.in.data() + begin, end - begin);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        if (line.empty()) continue;
        const ParsedRequest parsed = parse_request(line);
        if (parsed.request) {
            Answer answer = handler_(*parsed.request, client.peer);
            if (!answer.journal.empty()) note(std::move(answer.journal));
            client.out += answer.reply;
        } else {
            client.out += error_reply(parsed.id, parsed.error);
        }
        // Unread means not taken by the socket: offer the replies first.
        if (client.out.size() > limits_.max_unread_reply_bytes) flush(client);
        if (client.out.size() > limits_.max_unread_reply_bytes) {
            note("control: disconnected pid " + std::to_string(client.peer.pid) +
                 ": it left more than " + std::to_string(limits_.max_unread_reply_bytes) +
                 " bytes of replies unread");
            client.out.clear();
            client.closing = true;
            break;
        }
    }
    client.in.erase(0, begin);
    if (!client.closing && client.in.size() >= kMaxRequestBytes) {
        client.out +=
            error_reply(nullptr, "a request line longer than " + std::to_string(kMaxRequestBytes) +
                                     " bytes without its newline: at most " +
                                     std::to_string(kMaxRequestBytes) + " allowed");
        client.closing = true;
    }
    if (client.closing) client.in.clear();
}

void ControlServer::flush(Client& client) {
    while (!client.out.empty()) {
        const ssize_t sent =
            ::send(client.fd, client.out.data(), client.out.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
        if (sent < 0 && errno == EINTR) continue;
        if (sent < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
        if (sent < 0) {  // the client is gone: nothing more to say to it
            client.out.clear();
            client.closing = true;
            break;
        }
        client.out.erase(0, static_cast<std::size_t>(sent));
    }
    watch(client);
}

// EPOLLOUT only while replies wait, EPOLLIN only while the client may still send: a client
// that reads nothing, or has shut its side down, costs no wake-ups.
void ControlServer::watch(Client& client) {
    const std::uint32_t want =
        (client.read_closed || client.closing ? 0u
                                              : static_cast<std::uint32_t>(EPOLLIN | EPOLLRDHUP)) |
        (client.out.empty() ? 0u : static_cast<std::uint32_t>(EPOLLOUT));
    if (want == client.watched) return;
    epoll_event event{};
    event.events = want;
    event.data.fd = client.fd;
    ::epoll_ctl(epoll_fd_, EPOLL_CTL_MOD, client.fd, &event);
    client.watched = want;
}

void ControlServer::close_client(int fd) {
    const auto it = std::find_if(clients_.begin(), clients_.end(),
                                 [fd](const Client& c) { return c.fd == fd; });
    if (it == clients_.end()) return;
    ::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, fd, nullptr);
    ::close(fd);
    clients_.erase(it);
}

}  // namespace hapticd::daemon::control
