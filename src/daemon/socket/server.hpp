// hapticd's control socket (docs/control.md): a Unix stream socket on a thread of its own,
// never the servo thread. One epoll loop serves every client; each has bounded buffers and
// deadlines, so that no client can make the daemon allocate without bound, wait for it, or
// hold a place it does not use:
//
//   - a request line longer than kMaxRequestBytes: an error reply, then the disconnect;
//   - replies a client does not read, beyond Limits::max_unread_reply_bytes, or replies it
//     takes nothing of for Limits::stalled_reader: the disconnect;
//   - no request for Limits::idle: an error reply, then the disconnect (a place among
//     Limits::max_clients is not held by a client that says nothing);
//   - more than Limits::max_clients at once: the newcomer is heard for one line, which is
//     served if it is `disarm` (the stop always gets through, whoever holds the places) and
//     otherwise refused ("too many clients"), then the disconnect. Such newcomers are at most
//     Limits::stop_only_clients (to make room, the process holding the most of those places
//     loses its longest waiting one) and wait at most Limits::stop_only_grace for their line;
//     out of file descriptors: accepting pauses for a second, no busy loop;
//   - a client that shuts its side down: its complete requests are answered, then it is
//     closed.
//
// A subscriber (Answer::subscribe_hz) gets an event line at its rate, from the EventSource,
// under the same limits: one that does not read is closed like any other.
//
// The handler answers one parsed request on the server's thread and must not block
// (ServoLoop's arm(), disarm(), request_fault_reset() and status() are atomics and a seqlock).
// Work that takes longer (a stability check, a recording's start or stop) goes in
// Answer::later: one worker thread runs it, one job at a time in the order asked, while the
// server goes on serving the others; that client's further requests wait, so its replies keep
// their order.
// Who connected (SO_PEERCRED), and every disconnect the server chose, become messages for the
// journal that another thread takes (take_messages()): the server never writes to a stream
// that the supervising thread writes to.
#pragma once

#include <sys/stat.h>
#include <sys/types.h>

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "hapticd/daemon/control_protocol.hpp"
#include "hapticd/input/input_error.hpp"

namespace hapticd::daemon::control_socket {

/// The socket could not be made (names the path and why).
class ControlSocketError : public input::InputError {
  public:
    explicit ControlSocketError(const std::string& message) : InputError(message) {}
};

/// The connected process, from SO_PEERCRED.
struct Peer {
    static constexpr uid_t kUnknownUid = static_cast<uid_t>(-1);
    static constexpr gid_t kUnknownGid = static_cast<gid_t>(-1);
    pid_t pid = 0;
    uid_t uid = kUnknownUid;  ///< unknown: no credentials, so no one's rights
    gid_t gid = kUnknownGid;
    std::vector<gid_t> groups{};  ///< supplementary groups (SO_PEERGROUPS)

    /// "pid P uid U gid G", for the journal.
    std::string describe() const;
    /// Whether the peer could read a file of this status itself, as its mode bits say (owner,
    /// then group or supplementary group, then others; root reads all).
    bool may_read(const struct stat& status) const noexcept;
};

struct Limits {
    int max_clients = 16;
    /// Over max_clients: newcomers heard for one line, served only if it is `disarm`.
    int stop_only_clients = 16;
    /// How long such a newcomer may take to send its line.
    std::chrono::milliseconds stop_only_grace{std::chrono::seconds{1}};
    std::size_t max_unread_reply_bytes = std::size_t{64} * 1024;
    /// A client that sends no request for this long is told and closed.
    std::chrono::milliseconds idle{std::chrono::seconds{60}};
    /// A client that takes none of its waiting replies for this long is closed.
    std::chrono::milliseconds stalled_reader{std::chrono::seconds{10}};
    /// At most this many journal lines of one connection cause (connected, refused,
    /// disconnected, socket error) in this window; the rest are counted in one line.
    /// journald allows a service 10,000 lines in 30 s by default: a storm must not spend them.
    int journal_lines_per_cause = 10;
    std::chrono::milliseconds journal_cause_window{std::chrono::seconds{10}};
};

/// What a handler made of a request.
struct Answer {
    std::string reply{};    ///< the reply line (control_protocol.hpp: ok_reply(), error_reply())
    std::string journal{};  ///< a line for the journal (a change of state, who asked); may be empty
    /// Work too slow for the server's thread: when set, `reply` and `journal` are ignored and
    /// the Answer this returns, on the worker thread, is the one sent.
    std::function<Answer()> later{};
    /// Events a second from now on, after the reply (subscribe); 0 ends the subscription.
    std::optional<double> subscribe_hz{};
};

class SocketServer {
  public:
    using Handler = std::function<Answer(const Request&, const Peer&)>;
    /// The event line a subscriber gets now (control_protocol.hpp: event_line()); called on
    /// the server's thread at most once a wake, for every subscriber due.
    using EventSource = std::function<std::string()>;

    /// Binds `path` (mode 0660; group `group` when that group exists and this process may
    /// give it) and listens. A socket file that nobody listens on is replaced; one that a
    /// process answers on is refused, as is any other kind of file. Throws ControlSocketError.
    SocketServer(std::string path, Limits limits = {}, const std::string& group = "hapticd");
    /// Stops the thread, closes every client and removes the socket file.
    ~SocketServer();

    SocketServer(const SocketServer&) = delete;
    SocketServer& operator=(const SocketServer&) = delete;

    /// Serves on a thread of its own until stop() or the destructor, answering with
    /// `handler`; subscribers get `events`' lines. Clients that connect before this wait in the
    /// listen queue.
    void start(Handler handler, EventSource events = {});
    void stop() noexcept;

    const std::string& path() const noexcept { return path_; }
    /// Lines for the journal since the last call (connects, refusals, disconnects); when more
    /// than 256 waited, the last line says how many were dropped.
    std::vector<std::string> take_messages();

  private:
    struct Client;
    using Clock = std::chrono::steady_clock;
    void serve() noexcept;
    void accept_clients();
    void admit_stop_only(Client client);
    void refuse_too_many(Client& client);
    std::size_t served_clients() const;
    void read_from(Client& client);
    void answer_lines(Client& client);
    static bool may_read(const Client& client);
    void take_lines(Client& client);
    void carry_out_waiting_disarms(Client& client);
    void answer_line(Client& client, std::string_view line);
    void flush(Client& client);
    void close_client(int fd);
    bool drop_unread(Client& client, std::string_view what);
    void watch(Client& client);
    void watch_listener(bool on);
    void enforce_deadlines(Clock::time_point now);
    void send_events(Clock::time_point now);
    void subscribe(Client& client, double rate_hz);
    int wait_ms(Clock::time_point now) const;
    void take_finished_job();
    void work() noexcept;
    Client* find_client(int fd);
    void note(const std::string& message);
    /// What a client's connection did (connected, refused, disconnected): lines a storm of
    /// connects makes by the ten thousand, past journald's rate limit, which would then drop
    /// the fault lines that follow. At most a few of each cause in a window; the
    /// rest are counted and said in one line (Limits::journal_lines_per_cause). Requests' state
    /// changes go through note() and are never limited.
    enum class Cause { connected, refused, disconnected, socket_error };
    void note_connection(Cause cause, const std::string& message);
    void say_suppressed(Clock::time_point now);  // under messages_mutex_

    std::string path_;
    Handler handler_;
    EventSource events_;
    Limits limits_;
    int listen_fd_ = -1;
    int epoll_fd_ = -1;
    int stop_fd_ = -1;  // an eventfd: written by stop()
    int done_fd_ = -1;  // an eventfd: written by the worker when a job is done
    std::vector<Client> clients_;
    std::uint64_t next_client_id_ = 1;
    bool accepting_ = true;  // false for a second after accept() ran out of descriptors
    Clock::time_point accept_again_{};
    std::thread thread_;

    // The worker: one job at a time, in the order asked (a client has at most one queued,
    // since its next requests wait for it), from the server's thread to the worker and back.
    struct Job {
        std::uint64_t client_id = 0;
        std::function<Answer()> work{};
        Answer answer{};
    };
    std::thread worker_;
    std::mutex job_mutex_;
    std::condition_variable job_ready_;
    std::deque<Job> jobs_;          // waiting for the worker (guarded)
    std::deque<Job> done_;          // answered, for the server's thread (guarded)
    bool worker_stopping_ = false;  // guarded

    std::mutex messages_mutex_;
    std::vector<std::string> messages_;
    std::size_t dropped_messages_ = 0;  // guarded by messages_mutex_
    struct CauseWindow {                // guarded by messages_mutex_
        Clock::time_point start{};
        int written = 0;
        std::uint64_t suppressed = 0;
    };
    std::array<CauseWindow, 4> cause_windows_{};
};

}  // namespace hapticd::daemon::control_socket
