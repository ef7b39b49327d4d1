// hapticd as a systemd service (docs/daemon.md, "As a service"): the service manager's side of a
// run, by the protocol of sd_notify(3) (datagrams to NOTIFY_SOCKET; libsystemd reads the watchdog's
// settings). READY=1 once the run is set up and its first good tick
// has run (the config, the scene, the start-up check and the device have all succeeded by
// then); STATUS= lines with the run's state; WATCHDOG=1 only while the servo's tick counter
// advances, so that a hung servo thread trips WatchdogSec= even though this thread lives on;
// STOPPING=1 at the end. Every call comes from the watching thread (run_watcher.cpp), never
// from the servo thread. Without NOTIFY_SOCKET (not started by systemd) nothing is sent.
#pragma once

#include <sys/socket.h>
#include <sys/un.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

namespace hapticd::daemon {

class ServiceNotifier {
  public:
    using Clock = std::chrono::steady_clock;

    /// Reads NOTIFY_SOCKET, and WATCHDOG_USEC (with WATCHDOG_PID, when set, naming this
    /// process) for the watchdog, from the environment.
    ServiceNotifier();
    ~ServiceNotifier();
    ServiceNotifier(const ServiceNotifier&) = delete;
    ServiceNotifier& operator=(const ServiceNotifier&) = delete;

    bool enabled() const noexcept { return enabled_; }
    /// The service manager's watchdog timeout (WatchdogSec=); none when it is off.
    std::optional<std::chrono::microseconds> watchdog_timeout() const noexcept {
        return watchdog_timeout_;
    }

    /// READY=1 and a STATUS= line; only the first call sends.
    void ready(const std::string& status);
    /// A STATUS= line. The caller sends one a second at the most, and on a change of faults.
    void status(const std::string& status);
    /// WATCHDOG=1 when `tick` has advanced since the last ping and half the timeout has
    /// passed since it: a servo thread that stops ticking stops the pings.
    void watch(std::uint64_t tick, Clock::time_point now);
    /// STOPPING=1 and a last STATUS= line.
    void stopping(const std::string& status);

    std::uint64_t watchdog_pings() const noexcept { return pings_; }
    /// Messages the service manager had no room for (its queue full), dropped.
    std::uint64_t dropped() const noexcept { return dropped_; }

  private:
    void send(const std::string& message);

    int fd_ = -1;
    sockaddr_un address_{};
    socklen_t address_length_ = 0;
    bool enabled_ = false;
    std::optional<std::chrono::microseconds> watchdog_timeout_;
    bool ready_sent_ = false;
    std::uint64_t pinged_tick_ = 0;
    Clock::time_point last_ping_{};
    std::uint64_t pings_ = 0;
    std::uint64_t dropped_ = 0;
};

}  // namespace hapticd::daemon
