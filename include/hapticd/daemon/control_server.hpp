// hapticd's control socket (docs/control.md): a Unix stream socket on a thread of its own,
// never the servo thread. One epoll loop serves every client; each has bounded buffers, so
// that no client can make the daemon allocate without bound or wait for it:
//
//   - a request line longer than kMaxRequestBytes: an error reply, then the disconnect;
//   - replies a client does not read, beyond Limits::max_unread_reply_bytes: the disconnect;
//   - more than Limits::max_clients at once: an error reply to the newcomer, then its
//     disconnect;
//   - a client that shuts its side down: its complete requests are answered, then it is
//     closed.
//
// The handler answers one parsed request; it runs on the server's thread and must not block
// (ServoLoop's arm(), disarm(), request_fault_reset() and status() are atomics and a seqlock).
// Who connected (SO_PEERCRED), and every disconnect the server chose, become messages for the
// journal that another thread takes (take_messages()): the server never writes to a stream
// that the supervising thread writes to.
#pragma once

#include <sys/types.h>

#include <atomic>
#include <cstddef>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "hapticd/daemon/control_protocol.hpp"

namespace hapticd::daemon::control {

/// The socket could not be made (names the path and why).
class ControlSocketError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// The connected process, from SO_PEERCRED.
struct Peer {
    pid_t pid = 0;
    uid_t uid = 0;
    gid_t gid = 0;
};

struct Limits {
    int max_clients = 16;
    std::size_t max_unread_reply_bytes = std::size_t{64} * 1024;
};

/// What a handler made of a request.
struct Answer {
    std::string reply{};    ///< the reply line (control_protocol.hpp: ok_reply(), error_reply())
    std::string journal{};  ///< a line for the journal (a change of state, who asked); may be empty
};

class ControlServer {
  public:
    using Handler = std::function<Answer(const Request&, const Peer&)>;

    /// Binds `path` (mode 0660; group `group` when that group exists and this process may
    /// give it) and listens. A socket file that nobody listens on is replaced; one that a
    /// process answers on is refused, as is any other kind of file. Throws ControlSocketError.
    ControlServer(std::string path, Limits limits = {}, std::string group = "hapticd");
    /// Stops the thread, closes every client and removes the socket file.
    ~ControlServer();

    ControlServer(const ControlServer&) = delete;
    ControlServer& operator=(const ControlServer&) = delete;

    /// Serves on a thread of its own until stop() or the destructor, answering with
    /// `handler`. Clients that connect before this wait in the listen queue.
    void start(Handler handler);
    void stop() noexcept;

    const std::string& path() const noexcept { return path_; }
    /// Lines for the journal since the last call (connects, refusals, disconnects).
    std::vector<std::string> take_messages();

  private:
    struct Client;
    void serve() noexcept;
    void accept_clients();
    void read_from(Client& client);
    void answer_lines(Client& client);
    void flush(Client& client);
    void close_client(int fd);
    void watch(Client& client);
    void note(std::string message);

    std::string path_;
    Handler handler_;
    Limits limits_;
    int listen_fd_ = -1;
    int epoll_fd_ = -1;
    int stop_fd_ = -1;  // an eventfd: written by stop()
    std::vector<Client> clients_;
    std::thread thread_;
    std::mutex messages_mutex_;
    std::vector<std::string> messages_;
};

}  // namespace hapticd::daemon::control
