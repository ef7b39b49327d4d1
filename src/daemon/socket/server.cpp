#include "socket/server.hpp"

#include <fcntl.h>
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
#include <deque>
#include <optional>
#include <utility>

#include "hapticd/input/printable.hpp"
#include "hapticd/install/group_access.hpp"

namespace hapticd::daemon::control_socket {

struct SocketServer::Client {
    std::uint64_t id = 0;  // never reused, unlike the descriptor: a finished job finds its client
    int fd = -1;
    Peer peer;
    std::string in;  // bytes of the request line being read
    // Complete lines read while a request of this client was on the worker, in order; a
    // disarm among them is carried out as it is read, its reply kept for its turn.
    struct Line {
        std::string text;
        std::size_t oversized = 0;           // its bytes, past kMaxRequestBytes: refused
        std::optional<std::string> early{};  // the reply of a disarm carried out already
    };
    std::deque<Line> lines;
    std::size_t lines_bytes = 0;  // in `lines`: bounded while waiting (kMostWaitingBytes)
    std::string out;              // replies not yet taken by the client
    bool read_closed = false;     // the client shut its side down: answer what came, then close
    bool closing = false;         // answer nothing more; close once `out` is flushed
    bool gone = false;            // the connection broke: close now
    bool waiting = false;         // its request is on the worker; its next ones wait
    bool registered = true;       // with epoll (a hung-up client waiting for its job is not)
    bool stop_only = false;       // came over max_clients: one line, served only if `disarm`
    std::uint32_t watched = EPOLLIN | EPOLLRDHUP;           // the events registered with epoll
    std::chrono::steady_clock::time_point last_request{};   // or the connect
    std::chrono::steady_clock::time_point last_progress{};  // a byte of `out` taken, or new
    std::chrono::steady_clock::duration event_period{0};    // subscribed while > 0
    std::chrono::steady_clock::time_point next_event{};
};

namespace {

std::string errno_text(int error) { return std::strerror(error); }

// The peer's supplementary groups (SO_PEERGROUPS, Linux 4.13): what it may read through them.
// None when the kernel does not say: the peer is then judged by its primary group alone.
std::vector<gid_t> peer_groups(int fd) {
    std::vector<gid_t> groups(64);
    for (int attempt = 0; attempt < 2; ++attempt) {
        auto size = static_cast<socklen_t>(groups.size() * sizeof(gid_t));
        if (::getsockopt(fd, SOL_SOCKET, SO_PEERGROUPS, groups.data(), &size) == 0) {
            groups.resize(size / sizeof(gid_t));
            return groups;
        }
        if (errno != ERANGE) break;
        groups.resize(size / sizeof(gid_t));  // the size the kernel asked for
    }
    return {};
}

sockaddr_un address_of(const std::string& path) {
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    if (path.empty() || path.size() > kMaxSocketPathBytes) {
        throw ControlSocketError("control socket \"" + path + "\": a path of 1 to " +
                                 std::to_string(kMaxSocketPathBytes) +
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
    // Non-blocking: a live daemon whose listen queue is full answers EAGAIN at once, where a
    // blocking connect() would wait for it.
    const int probe = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    if (probe < 0) throw ControlSocketError("control socket: socket(): " + errno_text(errno));
    const int connected =
        ::connect(probe, reinterpret_cast<const sockaddr*>(&address), sizeof(address));
    const int error = errno;
    ::close(probe);
    if (connected == 0 || error == EAGAIN || error == EINPROGRESS) {
        throw ControlSocketError("control socket \"" + path +
                                 "\" is in use: another hapticd answers on it (one socket per "
                                 "instance: --socket, or the instance name)");
    }
    if (error != ECONNREFUSED && error != ENOENT) {
        throw ControlSocketError("control socket \"" + path +
                                 "\": cannot tell whether it is in use (" + errno_text(error) +
                                 "); remove it or choose another with --socket");
    }
    ::unlink(path.c_str());
}

}  // namespace

std::string Peer::describe() const {
    return "pid " + std::to_string(pid) + " uid " + std::to_string(uid) + " gid " +
           std::to_string(gid);
}

bool Peer::may_read(const struct stat& status) const noexcept {
    if (uid == 0) return true;
    if (uid == kUnknownUid) return false;
    if (status.st_uid == uid) return (status.st_mode & S_IRUSR) != 0;
    if (status.st_gid == gid ||
        std::find(groups.begin(), groups.end(), status.st_gid) != groups.end()) {
        return (status.st_mode & S_IRGRP) != 0;
    }
    return (status.st_mode & S_IROTH) != 0;
}

SocketServer::SocketServer(std::string path, Limits limits, const std::string& group)
    : path_(std::move(path)), limits_(limits) {
    const sockaddr_un address = address_of(path_);
    clear_stale_socket(path_, address);
    listen_fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    if (listen_fd_ < 0) throw ControlSocketError("control socket: socket(): " + errno_text(errno));
    // Created as 0660 at once: no moment when others could connect. listen() follows bind()
    // at once: a socket file that refuses connections is what another daemon's start-up
    // takes for stale (clear_stale_socket).
    const mode_t old_mask = ::umask(0117);
    const int bound =
        ::bind(listen_fd_, reinterpret_cast<const sockaddr*>(&address), sizeof(address));
    const int bind_error = errno;
    ::umask(old_mask);
    // A short queue: a connect storm that fills it is refused by the kernel (EAGAIN) while a
    // disarm's blocking connect() waits for room, behind at most this many; with the kernel's
    // 4096 a disarm waited behind the whole storm (about 0.1 s here).
    constexpr int kListenQueue = 64;
    const int listening = bound == 0 ? ::listen(listen_fd_, kListenQueue) : -1;
    const int listen_error = errno;
    if (bound != 0 || listening != 0) {
        if (bound == 0) ::unlink(path_.c_str());
        ::close(listen_fd_);
        throw ControlSocketError("control socket \"" + path_ + "\": " +
                                 (bound != 0 ? "bind(): " + errno_text(bind_error)
                                             : "listen(): " + errno_text(listen_error)));
    }
    ::chmod(path_.c_str(), 0660);
    const std::string group_note =
        install::give_to_group(path_, group, "control socket " + path_, "docs/control.md");
    if (!group_note.empty()) note(group_note);
    epoll_fd_ = ::epoll_create1(EPOLL_CLOEXEC);
    stop_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    done_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    bool watched = epoll_fd_ >= 0 && stop_fd_ >= 0 && done_fd_ >= 0;
    for (const int fd : {listen_fd_, stop_fd_, done_fd_}) {
        epoll_event event{};
        event.events = EPOLLIN;
        event.data.fd = fd;
        watched = watched && ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, fd, &event) == 0;
    }
    if (!watched) {
        const int error = errno;
        ::unlink(path_.c_str());
        for (const int fd : {listen_fd_, epoll_fd_, stop_fd_, done_fd_}) {
            if (fd >= 0) ::close(fd);
        }
        throw ControlSocketError("control socket \"" + path_ + "\": " + errno_text(error));
    }
}

SocketServer::~SocketServer() {
    stop();
    for (const Client& client : clients_) ::close(client.fd);
    ::unlink(path_.c_str());
    for (const int fd : {listen_fd_, epoll_fd_, stop_fd_, done_fd_}) ::close(fd);
}

void SocketServer::start(Handler handler, EventSource events) {
    handler_ = std::move(handler);
    events_ = std::move(events);
    worker_ = std::thread([this] { work(); });
    thread_ = std::thread([this] { serve(); });
}

// The server first, then the worker: a job under way is finished (a stability check takes
// seconds at most) and its answer dropped.
void SocketServer::stop() noexcept {
    const std::uint64_t one = 1;
    (void)!::write(stop_fd_, &one, sizeof(one));
    if (thread_.joinable()) thread_.join();
    {
        const std::lock_guard lock(job_mutex_);
        worker_stopping_ = true;
    }
    job_ready_.notify_one();
    if (worker_.joinable()) worker_.join();
}

namespace {

constexpr std::array<const char*, 4> kCauseNames{"client connected", "refused", "disconnected",
                                                 "socket error"};

}  // namespace

void SocketServer::say_suppressed(Clock::time_point now) {
    for (std::size_t i = 0; i < cause_windows_.size(); ++i) {
        CauseWindow& window = cause_windows_[i];
        if (now - window.start < limits_.journal_cause_window) continue;
        if (window.suppressed > 0) {
            messages_.push_back("control: " + std::to_string(window.suppressed) + " more \"" +
                                kCauseNames[i] + "\" lines not written (rate-limited: at most " +
                                std::to_string(limits_.journal_lines_per_cause) + " of a kind in " +
                                std::to_string(limits_.journal_cause_window.count()) + " ms)");
        }
        window = CauseWindow{.start = now, .written = 0, .suppressed = 0};
    }
}

void SocketServer::note_connection(Cause cause, const std::string& message) {
    {
        const std::lock_guard lock(messages_mutex_);
        say_suppressed(Clock::now());
        CauseWindow& window = cause_windows_[static_cast<std::size_t>(cause)];
        if (window.written >= limits_.journal_lines_per_cause) {
            ++window.suppressed;
            return;
        }
        ++window.written;
    }
    note(message);
}

std::vector<std::string> SocketServer::take_messages() {
    const std::lock_guard lock(messages_mutex_);
    say_suppressed(Clock::now());
    std::vector<std::string> taken = std::exchange(messages_, {});
    if (dropped_messages_ > 0) {
        taken.push_back("control: " + std::to_string(dropped_messages_) +
                        " more messages for the journal dropped (at most 256 wait)");
        dropped_messages_ = 0;
    }
    return taken;
}

void SocketServer::note(const std::string& message) {
    const std::lock_guard lock(messages_mutex_);
    constexpr std::size_t kMostMessages = 256;  // a flood of connects does not grow this
    if (messages_.size() < kMostMessages) {
        // A client's string in it (an id, a path, a scene's name) makes no line of its own.
        messages_.push_back(input::printable(message));
    } else {
        ++dropped_messages_;
    }
}

SocketServer::Client* SocketServer::find_client(int fd) {
    const auto it = std::find_if(clients_.begin(), clients_.end(),
                                 [fd](const Client& c) { return c.fd == fd; });
    return it == clients_.end() ? nullptr : &*it;
}

void SocketServer::serve() noexcept {
    std::array<epoll_event, 32> events{};
    // Deadlines are swept a few times per the shorter limit, and at least once a second, while
    // anyone is connected or accepting is paused; otherwise the thread sleeps until an event.
    for (;;) {
        const int n = ::epoll_wait(epoll_fd_, events.data(), static_cast<int>(events.size()),
                                   wait_ms(Clock::now()));
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) {
            note_connection(Cause::socket_error, "control socket " + path_ +
                                                     ": epoll_wait(): " + errno_text(errno) +
                                                     "; the socket no longer answers");
            return;
        }
        bool connecting = false;
        for (int i = 0; i < n; ++i) {
            const int fd = events[static_cast<std::size_t>(i)].data.fd;
            const std::uint32_t what = events[static_cast<std::size_t>(i)].events;
            if (fd == stop_fd_) return;
            if (fd == listen_fd_) {
                connecting = true;
                continue;
            }
            if (fd == done_fd_) {
                take_finished_job();
                continue;
            }
            Client* client = find_client(fd);
            if (client == nullptr) continue;  // closed earlier in this batch
            if ((what & EPOLLERR) != 0u) {
                client->gone = true;
                continue;
            }
            if ((what & EPOLLOUT) != 0u) flush(*client);
            // A client that sent its requests and closed at once (EPOLLHUP, often with the
            // requests still unread) has them carried out all the same; replies to it fail
            // and end it.
            if ((what & (EPOLLIN | EPOLLRDHUP | EPOLLHUP)) != 0u) read_from(*client);
            if ((what & EPOLLHUP) != 0u && client->waiting && client->registered) {
                // EPOLLHUP cannot be masked: off epoll until its job is back, or it would
                // wake this thread in a loop.
                ::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, client->fd, nullptr);
                client->registered = false;
            }
        }
        // The connected clients' lines first, then the newcomers: a disarm heard over the
        // limit is read before a storm of connects can take its place (accept_clients).
        if (connecting) accept_clients();
        const Clock::time_point now = Clock::now();
        send_events(now);
        enforce_deadlines(now);
        // Clients done with: everything answered and flushed, or gone.
        for (std::size_t i = clients_.size(); i-- > 0;) {
            const Client& client = clients_[i];
            const bool finished =
                (client.closing || client.read_closed) && client.out.empty() && !client.waiting;
            if (client.gone || finished) close_client(client.fd);
        }
    }
}

// How long epoll may sleep: until the next subscriber's event, and while anyone is connected
// (or accepting is paused) a few times per the shorter deadline (a newcomer's grace over the
// limit among them), at least once a second; otherwise until an event.
int SocketServer::wait_ms(Clock::time_point now) const {
    if (clients_.empty() && accepting_) return -1;
    auto wait =
        std::clamp(std::min({limits_.idle, limits_.stalled_reader, limits_.stop_only_grace}) / 4,
                   std::chrono::milliseconds{10}, std::chrono::milliseconds{1000});
    for (const Client& client : clients_) {
        // send_events() passes over these: their next event is not due while they are so.
        if (client.event_period.count() == 0 || client.waiting || client.closing || client.gone) {
            continue;
        }
        const auto until = std::chrono::ceil<std::chrono::milliseconds>(client.next_event - now);
        wait = std::min(wait, std::max(until, std::chrono::milliseconds{0}));
    }
    return static_cast<int>(wait.count());
}

// Every subscriber that is due gets the same event line, made once. A subscriber more than a
// period behind (a slow wake) skips ahead instead of getting a burst.
void SocketServer::send_events(Clock::time_point now) {
    std::string line;
    for (Client& client : clients_) {
        if (client.event_period.count() == 0 || client.next_event > now || client.gone ||
            client.closing || client.waiting) {
            continue;
        }
        if (line.empty() && events_) line = events_();
        if (client.out.empty()) client.last_progress = now;
        client.out += line;
        client.next_event += client.event_period;
        if (client.next_event <= now) client.next_event = now + client.event_period;
        flush(client);
        if (drop_unread(client, "events")) client.gone = true;
    }
}

void SocketServer::enforce_deadlines(Clock::time_point now) {
    if (!accepting_ && now >= accept_again_) watch_listener(true);
    for (Client& client : clients_) {
        if (client.gone) continue;
        if (client.stop_only && !client.closing &&
            now - client.last_request > limits_.stop_only_grace) {
            refuse_too_many(client);
            continue;
        }
        if (!client.out.empty() && now - client.last_progress > limits_.stalled_reader) {
            note_connection(Cause::disconnected,
                            "control: disconnected " + client.peer.describe() +
                                ": it took none of its " + std::to_string(client.out.size()) +
                                " bytes of replies for " +
                                std::to_string(limits_.stalled_reader.count()) + " ms");
            client.gone = true;
            continue;
        }
        // A part of a line is no request: a client that trickles bytes is idle too.
        const bool quiet = !client.waiting && !client.closing && !client.read_closed &&
                           client.out.empty() && client.event_period.count() == 0;
        if (quiet && now - client.last_request > limits_.idle) {
            client.out =
                error_reply(nullptr, "no request for " + std::to_string(limits_.idle.count()) +
                                         " ms: closed; connect again when needed");
            client.last_progress = now;
            client.closing = true;
            note_connection(Cause::disconnected, "control: disconnected " + client.peer.describe() +
                                                     ": idle for " +
                                                     std::to_string(limits_.idle.count()) + " ms");
            flush(client);
        }
    }
}

// Out of descriptors (EMFILE, ENFILE) the listening socket stays readable: it is taken off
// epoll for a second, or until a client closes, instead of waking this thread in a loop.
void SocketServer::watch_listener(bool on) {
    epoll_event event{};
    event.events = on ? EPOLLIN : 0u;
    event.data.fd = listen_fd_;
    ::epoll_ctl(epoll_fd_, EPOLL_CTL_MOD, listen_fd_, &event);
    accepting_ = on;
    accept_again_ = Clock::now() + std::chrono::seconds{1};
}

void SocketServer::accept_clients() {
    // At most 16 a wake: a flood of connects (over max_clients each heard for one line only)
    // cannot keep this thread from the clients it serves; epoll comes back for the rest.
    for (int accepted = 0; accepted < 16; ++accepted) {
        const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
        if (fd < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return;  // none left
        if (fd < 0 && (errno == EINTR || errno == ECONNABORTED)) continue;
        if (fd < 0) {
            note_connection(Cause::socket_error,
                            "control: accept(): " + errno_text(errno) +
                                "; new clients wait (accepting again in a second)");
            watch_listener(false);
            return;
        }
        const Clock::time_point now = Clock::now();
        Client client;
        client.id = next_client_id_++;
        client.fd = fd;
        client.last_request = now;
        client.last_progress = now;
        ucred credentials{};
        socklen_t size = sizeof(credentials);
        if (::getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &credentials, &size) == 0) {
            client.peer =
                Peer{.pid = credentials.pid, .uid = credentials.uid, .gid = credentials.gid};
            client.peer.groups = peer_groups(fd);
        }
        client.stop_only = static_cast<int>(served_clients()) >= limits_.max_clients;
        epoll_event event{};
        event.events = EPOLLIN | EPOLLRDHUP;
        event.data.fd = fd;
        if (::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, fd, &event) != 0) {
            note_connection(Cause::refused, "control: refused " + client.peer.describe() +
                                                ": epoll_ctl(): " + errno_text(errno));
            ::close(fd);
            continue;
        }
        if (client.stop_only) {
            admit_stop_only(std::move(client));
            continue;
        }
        note_connection(Cause::connected, "control: client connected: " + client.peer.describe());
        clients_.push_back(std::move(client));
    }
}

std::size_t SocketServer::served_clients() const {
    return static_cast<std::size_t>(std::count_if(clients_.begin(), clients_.end(),
                                                  [](const Client& c) { return !c.stop_only; }));
}

// A newcomer over max_clients is heard for one line: its request may be the disarm that must
// get through. Read at once (hapticctl writes its line right after connect(), so it is usually
// there already); otherwise it waits, among at most stop_only_clients. To make room, the
// process that holds the most of those places loses its longest waiting one: a storm of
// connects from one process takes its own places, never another's disarm.
void SocketServer::admit_stop_only(Client client) {
    const auto heard = [](const Client& c) { return c.stop_only && !c.closing && !c.gone; };
    if (std::count_if(clients_.begin(), clients_.end(), heard) >= limits_.stop_only_clients) {
        Client* oldest_of_most = nullptr;
        std::ptrdiff_t most = 0;
        for (Client& c : clients_) {  // in order of arrival
            if (!heard(c)) continue;
            const std::ptrdiff_t held = std::count_if(
                clients_.begin(), clients_.end(),
                [&](const Client& other) { return heard(other) && other.peer.pid == c.peer.pid; });
            if (held > most) most = held, oldest_of_most = &c;
        }
        if (oldest_of_most != nullptr) refuse_too_many(*oldest_of_most);
    }
    clients_.push_back(std::move(client));
    read_from(clients_.back());
}

void SocketServer::refuse_too_many(Client& client) {
    client.out += error_reply(nullptr, "too many clients: this hapticd serves " +
                                           std::to_string(limits_.max_clients) +
                                           " at once, and over that only disarm; try again later");
    client.last_progress = Clock::now();
    client.closing = true;
    client.in.clear();
    note_connection(Cause::refused, "control: refused " + client.peer.describe() + ": " +
                                        std::to_string(limits_.max_clients) +
                                        " clients already connected");
    flush(client);
}

namespace {

// While a client's request is on the worker its next lines wait, but are read (a disarm among
// them is carried out at once): up to this many bytes of them.
constexpr std::size_t kMostWaitingBytes = 4 * kMaxRequestBytes;

}  // namespace

bool SocketServer::may_read(const Client& client) {
    if (client.read_closed || client.closing || client.gone) return false;
    return !client.waiting || client.in.size() + client.lines_bytes < kMostWaitingBytes;
}

void SocketServer::read_from(Client& client) {
    std::array<char, 4096> buffer{};
    // At most 16 reads a wake: epoll (level-triggered) comes back for the rest, so a client
    // that writes as fast as it reads cannot keep this thread from the others, or from stop().
    constexpr int kReadsPerWake = 16;
    for (int reads = 0; reads < kReadsPerWake && may_read(client); ++reads) {
        const ssize_t got = ::recv(client.fd, buffer.data(), buffer.size(), MSG_DONTWAIT);
        if (got < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) {  // the connection broke
            client.gone = true;
            break;
        }
        if (got == 0) {  // the client shut its side down: what it sent is still answered
            client.read_closed = true;
            break;
        }
        client.in.append(buffer.data(), static_cast<std::size_t>(got));
        answer_lines(client);
    }
    flush(client);
}

// The complete lines of `in` into `lines`, in order.
void SocketServer::take_lines(Client& client) {
    std::size_t begin = 0;
    for (;;) {
        const std::size_t end = client.in.find('\n', begin);
        if (end == std::string::npos) break;
        std::string_view text(client.in.data() + begin, end - begin);
        begin = end + 1;
        Client::Line line{.text = {},
                          .oversized = text.size() + 1 > kMaxRequestBytes ? text.size() + 1 : 0};
        if (line.oversized == 0) {
            if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
            if (text.empty()) continue;
            line.text = std::string(text);
        }
        client.lines_bytes += line.text.size() + 1;
        client.lines.push_back(std::move(line));
    }
    client.in.erase(0, begin);
}

// While the client waits for the worker, a disarm among its waiting lines is carried out now:
// the stop does not wait behind a slow request (a coupling's exact check may take seconds);
// only its reply keeps its place.
void SocketServer::carry_out_waiting_disarms(Client& client) {
    for (Client::Line& line : client.lines) {
        if (line.oversized > 0 || line.early) continue;
        const ParsedRequest parsed = parse_request(line.text);
        if (!parsed.request || parsed.request->kind != RequestKind::disarm) continue;
        Answer answer = handler_(*parsed.request, client.peer);
        if (answer.later) answer = answer.later();  // a disarm has no work to wait for
        if (!answer.journal.empty()) note(answer.journal);
        line.early = std::move(answer.reply);
        client.last_request = Clock::now();
    }
}

void SocketServer::answer_lines(Client& client) {
    take_lines(client);
    while (!client.closing && !client.waiting && !client.lines.empty()) {
        Client::Line line = std::move(client.lines.front());
        client.lines.pop_front();
        client.lines_bytes -= line.text.size() + 1;
        if (client.out.empty()) client.last_progress = Clock::now();  // replies from now on
        if (line.oversized > 0) {
            client.out += error_reply(
                nullptr, "a request line of " + std::to_string(line.oversized) +
                             " bytes: at most " + std::to_string(kMaxRequestBytes) + " allowed");
            client.closing = true;
            break;
        }
        if (line.early) {  // carried out as it was read; the reply in its turn
            client.out += *line.early;
        } else {
            answer_line(client, line.text);
        }
        // Unread means not taken by the socket: offer the replies first.
        if (client.out.size() > limits_.max_unread_reply_bytes) flush(client);
        if (drop_unread(client, "replies")) {
            client.closing = true;
            break;
        }
    }
    if (client.waiting && !client.stop_only) carry_out_waiting_disarms(client);
    if (!client.closing && !client.waiting && client.in.size() >= kMaxRequestBytes) {
        client.out +=
            error_reply(nullptr, "a request line longer than " + std::to_string(kMaxRequestBytes) +
                                     " bytes without its newline: at most " +
                                     std::to_string(kMaxRequestBytes) + " allowed");
        client.closing = true;
    }
    if (client.closing) {
        client.in.clear();
        client.lines.clear();
        client.lines_bytes = 0;
    }
}

void SocketServer::answer_line(Client& client, std::string_view line) {
    client.last_request = Clock::now();
    const ParsedRequest parsed = parse_request(line);
    if (client.stop_only && !(parsed.request && parsed.request->kind == RequestKind::disarm)) {
        refuse_too_many(client);
        return;
    }
    if (client.stop_only) client.closing = true;  // its one request, then the disconnect
    if (!parsed.request) {
        client.out += error_reply(parsed.id, parsed.error);
    } else if (Answer answer = handler_(*parsed.request, client.peer); answer.later) {
        {
            const std::lock_guard lock(job_mutex_);
            jobs_.push_back(
                Job{.client_id = client.id, .work = std::move(answer.later), .answer = {}});
        }
        job_ready_.notify_one();
        client.waiting = true;
    } else {
        if (!answer.journal.empty()) note(answer.journal);
        client.out += answer.reply;
        if (answer.subscribe_hz) subscribe(client, *answer.subscribe_hz);
    }
}

void SocketServer::subscribe(Client& client, double rate_hz) {
    if (rate_hz <= 0.0) {
        client.event_period = Clock::duration{0};
        return;
    }
    client.event_period =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / rate_hz));
    client.next_event = Clock::now();  // the first event right after the reply
}

// The worker thread: runs each job's work, outside the lock, and tells the server's thread.
void SocketServer::work() noexcept {
    for (;;) {
        Job job;
        {
            std::unique_lock lock(job_mutex_);
            job_ready_.wait(lock, [this] { return worker_stopping_ || !jobs_.empty(); });
            if (worker_stopping_) return;
            job = std::move(jobs_.front());
            jobs_.pop_front();
        }
        try {
            job.answer = job.work();
        } catch (const std::exception& e) {
            job.answer.reply = error_reply(nullptr, std::string("internal error: ") + e.what());
        }
        job.work = nullptr;
        {
            const std::lock_guard lock(job_mutex_);
            done_.push_back(std::move(job));
        }
        const std::uint64_t one = 1;
        (void)!::write(done_fd_, &one, sizeof(one));
    }
}

// On the server's thread: the finished job's answer goes to its client, if it is still
// connected, and the client's waiting requests are answered.
void SocketServer::take_finished_job() {
    std::uint64_t count = 0;
    (void)!::read(done_fd_, &count, sizeof(count));
    std::deque<Job> done;
    {
        const std::lock_guard lock(job_mutex_);
        done.swap(done_);
    }
    for (Job& job : done) {
        if (!job.answer.journal.empty()) note(job.answer.journal);
        const auto it = std::find_if(clients_.begin(), clients_.end(),
                                     [&](const Client& c) { return c.id == job.client_id; });
        if (it == clients_.end()) continue;  // it left while its request was worked on
        Client& client = *it;
        client.waiting = false;
        client.last_request = Clock::now();
        if (client.gone) continue;
        if (client.out.empty()) client.last_progress = client.last_request;
        client.out += job.answer.reply;
        answer_lines(client);  // its requests that waited (a next slow one queues behind others)
        flush(client);
        if (!client.registered) {  // hung up: what it sent before is still carried out
            while (!client.waiting && !client.read_closed && !client.gone) read_from(client);
            if (!client.waiting) client.gone = true;
        }
    }
}

void SocketServer::flush(Client& client) {
    while (!client.out.empty()) {
        const ssize_t sent =
            ::send(client.fd, client.out.data(), client.out.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
        if (sent < 0 && errno == EINTR) continue;
        if (sent < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
        if (sent < 0) {  // the client is gone: nothing more to say to it
            client.out.clear();
            client.gone = true;
            break;
        }
        if (sent > 0) client.last_progress = Clock::now();
        client.out.erase(0, static_cast<std::size_t>(sent));
    }
    watch(client);
}

// EPOLLOUT only while replies wait, EPOLLIN only while the client may still send: a client
// that reads nothing, or has shut its side down, costs no wake-ups.
void SocketServer::watch(Client& client) {
    const std::uint32_t want =
        (may_read(client) ? static_cast<std::uint32_t>(EPOLLIN | EPOLLRDHUP) : 0u) |
        (client.out.empty() ? 0u : static_cast<std::uint32_t>(EPOLLOUT));
    if (want == client.watched || !client.registered) return;
    epoll_event event{};
    event.events = want;
    event.data.fd = client.fd;
    ::epoll_ctl(epoll_fd_, EPOLL_CTL_MOD, client.fd, &event);
    client.watched = want;
}

// More than the limit of `what` (replies, events) that the socket did not take: the client
// gets no more of them, and the journal says why it is disconnected. True when so.
bool SocketServer::drop_unread(Client& client, std::string_view what) {
    if (client.out.size() <= limits_.max_unread_reply_bytes) return false;
    note_connection(Cause::disconnected, "control: disconnected " + client.peer.describe() +
                                             ": it left more than " +
                                             std::to_string(limits_.max_unread_reply_bytes) +
                                             " bytes of " + std::string(what) + " unread");
    client.out.clear();
    return true;
}

void SocketServer::close_client(int fd) {
    const Client* const client = find_client(fd);
    if (client == nullptr) return;
    ::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, fd, nullptr);
    ::close(fd);
    clients_.erase(clients_.begin() + (client - clients_.data()));
    if (!accepting_) watch_listener(true);  // a descriptor is free again
}

}  // namespace hapticd::daemon::control_socket
