// hapticctl's side of the control socket (docs/control.md): connect, send a request line,
// read its reply line, with a timeout, and errors that say what to do.
#pragma once

#include <chrono>
#include <csignal>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "hapticd/daemon/control_protocol.hpp"

namespace hapticd::ctl {

/// No daemon answered, or it answered with something that is not the protocol.
class ConnectionError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// A wait for the daemon ended by the flag given to ControlConnection::interrupt_on (a signal).
class Interrupted : public ConnectionError {
  public:
    Interrupted() : ConnectionError("interrupted") {}
};

/// /run/hapticd/NAME.sock: where the template unit hapticd@NAME serves it.
std::string instance_socket(const std::string& name);

class ControlConnection {
  public:
    /// Connects to the daemon at `socket_path`; throws ConnectionError.
    explicit ControlConnection(std::string socket_path,
                               std::chrono::milliseconds timeout = std::chrono::seconds(2));
    ~ControlConnection();
    ControlConnection(const ControlConnection&) = delete;
    ControlConnection& operator=(const ControlConnection&) = delete;

    /// Sends one request and returns its reply (ok or not); throws ConnectionError when the
    /// daemon goes away, is silent for the timeout, or replies outside the protocol.
    nlohmann::json request(daemon::control_socket::RequestKind kind);
    nlohmann::json request(daemon::control_socket::Request request);
    /// The next event line of a subscription (docs/control.md, "subscribe"); throws
    /// ConnectionError as request() does.
    nlohmann::json next_event();
    /// From now on a wait that a signal interrupts throws Interrupted when `*flag` is set
    /// (a signal handler's flag), instead of waiting on.
    void interrupt_on(const volatile std::sig_atomic_t* flag) noexcept { interrupt_ = flag; }

  private:
    std::string read_line();
    /// The next line as a JSON object that is either a reply ("ok") or an event ("event").
    nlohmann::json read_message();

    std::string path_;
    std::chrono::milliseconds timeout_;
    int fd_ = -1;
    std::string pending_;
    std::int64_t next_id_ = 1;
    const volatile std::sig_atomic_t* interrupt_ = nullptr;
};

}  // namespace hapticd::ctl
