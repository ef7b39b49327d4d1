// HilServiceNotify: hapticd under a service manager, which this test plays: it binds the
// NOTIFY_SOCKET (a datagram socket, as systemd's), runs the real hapticd with NOTIFY_SOCKET and
// WATCHDOG_USEC in its environment, and reads what arrived, each message with its kernel
// receive time (SO_TIMESTAMP). READY=1 comes after the first good tick and STOPPING=1 last;
// STATUS= lines say the state, rate, tick, overruns and faults, a fault at once, and do not
// flood; WATCHDOG=1 comes every half timeout while the
// servo ticks, and stops while the servo thread is held (the sim's read() returning a second
// late on the realtime clock) although the watching thread goes on.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "control_daemon.hpp"
#include "hapticd_run.hpp"
#include "pen_display.hpp"

namespace hapticd::testing {
namespace {

struct Notification {
    std::string text;
    double t_s = 0.0;  ///< kernel receive time, CLOCK_REALTIME
};

/// The service manager's end: an AF_UNIX datagram socket bound at `path`.
class NotifySocket {
  public:
    explicit NotifySocket(const std::string& path) : path_(path) {
        fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
        if (fd_ < 0) throw std::runtime_error(std::string("socket: ") + std::strerror(errno));
        const int on = 1;
        ::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMP, &on, sizeof on);
        const int buffer = 1 << 20;  // every message of a run, read after it ends
        ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &buffer, sizeof buffer);
        sockaddr_un address{};
        address.sun_family = AF_UNIX;
        if (path.size() >= sizeof address.sun_path) throw std::runtime_error("path too long");
        std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
        if (::bind(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
            throw std::runtime_error("bind " + path + ": " + std::strerror(errno));
        }
    }
    NotifySocket(const NotifySocket&) = delete;
    NotifySocket& operator=(const NotifySocket&) = delete;
    ~NotifySocket() {
        ::close(fd_);
        ::unlink(path_.c_str());
    }

    /// Everything that has arrived, in order.
    std::vector<Notification> drain() const {
        std::vector<Notification> out;
        for (;;) {
            std::array<char, 4096> text{};
            std::array<char, CMSG_SPACE(sizeof(timeval))> control{};
            iovec io{text.data(), text.size()};
            msghdr message{};
            message.msg_iov = &io;
            message.msg_iovlen = 1;
            message.msg_control = control.data();
            message.msg_controllen = control.size();
            const ssize_t n = ::recvmsg(fd_, &message, 0);
            if (n < 0) break;  // EAGAIN: all read
            Notification note{std::string(text.data(), static_cast<std::size_t>(n))};
            for (cmsghdr* c = CMSG_FIRSTHDR(&message); c != nullptr; c = CMSG_NXTHDR(&message, c)) {
                if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMP) {
                    timeval tv{};
                    std::memcpy(&tv, CMSG_DATA(c), sizeof tv);
                    note.t_s =
                        static_cast<double>(tv.tv_sec) + 1e-6 * static_cast<double>(tv.tv_usec);
                }
            }
            out.push_back(note);
        }
        return out;
    }

  private:
    std::string path_;
    int fd_ = -1;
};

/// Half of Colgate and Schenkel's 2b/T: the passive check arms it.
constexpr CouplingGains kHalfColgateGains{.stiffness_n_per_m = 0.5 * kColgateStiffnessNPerM,
                                          .damping_n_s_per_m = 0.0};

/// Runs `run` while a thread reads the socket as a service manager does (an AF_UNIX datagram
/// socket queues at most net.unix.max_dgram_qlen = 10 messages; hapticd drops what finds it
/// full rather than wait); returns every message, with its kernel receive time.
template <typename Run>
std::vector<Notification> collect_while(const NotifySocket& socket, Run run) {
    std::atomic<bool> done{false};
    std::vector<Notification> notes;
    std::thread reader([&] {
        while (!done.load()) {
            for (Notification& n : socket.drain()) notes.push_back(std::move(n));
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        for (Notification& n : socket.drain()) notes.push_back(std::move(n));
    });
    run();
    done.store(true);
    reader.join();
    return notes;
}

bool has(const Notification& n, const std::string& line) {
    return ("\n" + n.text + "\n").find("\n" + line + "\n") != std::string::npos;
}

std::string status_of(const Notification& n) {
    const std::size_t at = ("\n" + n.text).find("\nSTATUS=");
    if (at == std::string::npos) return "";
    const std::size_t begin = at + std::string("STATUS=").size();
    return n.text.substr(begin, n.text.find('\n', begin) - begin);
}

TEST(HilServiceNotify, ReadyAfterTheFirstTickThenStatusThenStopping) {
    const ScratchDir dir;
    const NotifySocket socket(dir.file("notify.sock"));
    DaemonConfig config;
    config.coupling = coupling_table(kHalfColgateGains, "passive");
    DaemonRun run;
    const std::vector<Notification> notes = collect_while(socket, [&] {
        run = run_hapticd(dir, {.config_toml = config.toml(),
                                .scene_toml = "[scene]\nname = \"free\"\naxes = 1\n",
                                // Lockstep runs about a million ticks a second: 1 s of
                                // it could end before the watcher's first look (10 ms).
                                .duration_s = 60.0,
                                .lockstep = true,
                                .identify = false,
                                .with_log = true,
                                .environment = {{"NOTIFY_SOCKET", dir.file("notify.sock")}}});
    });
    ASSERT_EQ(run.exit_code, 0) << run.err;
    ASSERT_GE(notes.size(), 2u);
    EXPECT_TRUE(has(notes.front(), "READY=1")) << notes.front().text;
    // Lockstep: the rate is the device's, so no measured rate.
    EXPECT_NE(status_of(notes.front()).find(", 1000 Hz, tick "), std::string::npos)
        << notes.front().text;
    EXPECT_TRUE(has(notes.back(), "STOPPING=1")) << notes.back().text;
    EXPECT_EQ(status_of(notes.back()), "stopping: duration");
    std::size_t ready = 0, watchdog = 0;
    for (const Notification& n : notes) {
        ready += has(n, "READY=1");
        watchdog += has(n, "WATCHDOG=1");
    }
    EXPECT_EQ(ready, 1u);
    EXPECT_EQ(watchdog, 0u);  // no WATCHDOG_USEC: no watchdog
    // No flood: a STATUS= a second at the most, and on a change of faults (none here).
    EXPECT_LE(notes.size(),
              2u + static_cast<std::size_t>(run.summary.at("run_time_s").get<double>()) + 1u);
}

TEST(HilServiceNotify, TheWatchdogStopsWhileTheServoThreadIsHeld) {
    const ScratchDir dir;
    const NotifySocket socket(dir.file("notify.sock"));
    DaemonConfig config;
    config.coupling = coupling_table(kHalfColgateGains, "passive");
    config.sim_clock = "realtime";
    config.faults = "late_at = [1.0]\nlate_by = 1.0\n";  // read() at 1 s returns 1 s late
    config.safety_keys = "max_missed_periods = 5000\nmax_consecutive_overruns = 5000\n";
    constexpr double kTimeoutS = 0.2;
    DaemonRun run;
    const std::vector<Notification> notes = collect_while(socket, [&] {
        run = run_hapticd(
            dir,
            {.config_toml = config.toml(),
             .scene_toml = "[scene]\nname = \"free\"\naxes = 1\n",
             // Four seconds: the hold spans [1, 2) s, and the last two leave whole seconds
             // it does not span for the measured rate below (with three, only the second
             // just before the hold and the very end did, and a loaded machine missed both).
             .duration_s = 4.0,
             .lockstep = false,
             .identify = false,
             .with_log = true,
             .environment = {{"NOTIFY_SOCKET", dir.file("notify.sock")},
                             {"WATCHDOG_USEC", std::to_string(std::llround(kTimeoutS * 1e6))}}});
    });
    ASSERT_EQ(run.exit_code, 0) << run.err;
    std::vector<double> pings;
    for (const Notification& n : notes) {
        if (has(n, "WATCHDOG=1")) pings.push_back(n.t_s);
    }
    ASSERT_GE(pings.size(), 10u);
    // Judged on what the daemon does, not on whether the host kept time: another test's
    // real-time threads on the same two cores may delay a ping now and then.
    std::vector<double> gaps;
    for (std::size_t i = 1; i < pings.size(); ++i) gaps.push_back(pings[i] - pings[i - 1]);
    const double longest_gap_s = *std::max_element(gaps.begin(), gaps.end());
    std::vector<double> sorted = gaps;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double median_gap_s = sorted[sorted.size() / 2];
    std::cout << "[hil] watchdog: " << pings.size() << " pings, longest gap " << longest_gap_s
              << " s, median " << median_gap_s << " s\n";
    // The held second: no ping, the watchdog would fire (timeout 0.2 s); then the pings
    // resume (a watcher that never did would leave the last 2 s of the run without one).
    EXPECT_GE(longest_gap_s, 0.9);
    EXPECT_LT(longest_gap_s, 2.0);
    // Otherwise every half timeout (the watcher polls every 10 ms).
    EXPECT_LE(median_gap_s, 0.75 * kTimeoutS);
    // A real-time run's STATUS= says the rate measured over the last second once there is one,
    // near 1000 Hz in a second that the hold does not span.
    const std::string measured_at = ", 1000 Hz (measured ";
    std::size_t measured = 0;
    std::size_t near_rate = 0;
    for (const Notification& n : notes) {
        const std::string status = status_of(n);
        const std::size_t at = status.find(measured_at);
        if (at == std::string::npos) continue;
        ++measured;
        near_rate += std::abs(std::stod(status.substr(at + measured_at.size())) - 1000.0) < 200.0;
    }
    EXPECT_GE(measured, 1u);
    EXPECT_GE(near_rate, 1u);
}

/// NAME=VALUE in the test's environment, which the daemons it starts inherit, until the end of
/// the scope.
class ScopedEnvironment {
  public:
    ScopedEnvironment(const char* name, const std::string& value) : name_(name) {
        ::setenv(name, value.c_str(), 1);
    }
    ScopedEnvironment(const ScopedEnvironment&) = delete;
    ScopedEnvironment& operator=(const ScopedEnvironment&) = delete;
    ~ScopedEnvironment() { ::unsetenv(name_); }

  private:
    const char* name_;
};

// A daemon with a control socket, as the unit runs it: an encoder jump at 1.5 s latches a
// fault that waits for hapticctl reset. STATUS= tells the fault at once, within a few
// watcher looks of the tick that latched it (the flight record's name says which), not at the
// next once-a-second line, and its return to none.
TEST(HilServiceNotify, StatusSaysStateRateTickOverrunsAndFaultsAndAFaultAtOnce) {
    const ScratchDir dir;
    const NotifySocket socket(dir.file("notify.sock"));
    const ScopedEnvironment notify("NOTIFY_SOCKET", dir.file("notify.sock"));
    int stopped_with = -1;
    const std::vector<Notification> notes = collect_while(socket, [&] {
        Daemon d(dir, "lab", "[device.sim.faults]\njump_at = 1.5\njump_counts = 20000\n");
        if (!d.process.wait_for_socket(d.socket)) return;
        status_when(d.socket, [](const nlohmann::json& s) { return s["state"] == "fault"; });
        std::this_thread::sleep_for(std::chrono::milliseconds(1200));  // a periodic line
        EXPECT_EQ(hapticctl(d.socket, "reset").exit_code, 0);
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        stopped_with = d.process.stop();
    });
    ASSERT_EQ(stopped_with, 0);

    const std::regex line(
        "(disabled|arming|running|fault), 1000 Hz( \\(measured [0-9]+\\.[0-9]\\))?, tick "
        "([0-9]+), overruns [0-9]+, faults (none|[a-z_,]+)(, .*)?");
    double ready_s = -1.0;
    double fault_s = -1.0;
    double cleared_s = -1.0;
    std::uint64_t fault_status_tick = 0;
    std::size_t ready = 0;
    std::uint64_t last_tick = 0;
    for (const Notification& n : notes) {
        const std::string status = status_of(n);
        SCOPED_TRACE(n.text);
        if (has(n, "READY=1")) {
            ++ready;
            ready_s = n.t_s;
            EXPECT_LT(fault_s, 0.0) << "READY before the fault";
        }
        if (status.empty() || status.starts_with("stopping: ")) continue;
        std::smatch m;
        ASSERT_TRUE(std::regex_match(status, m, line)) << status;
        const std::uint64_t tick = std::stoull(m[3].str());
        EXPECT_GE(tick, last_tick);  // in order
        last_tick = tick;
        const bool faulted = m[4] != "none";
        EXPECT_EQ(m[1] == "fault", faulted) << status;
        if (faulted) {
            EXPECT_NE(m[4].str().find("encoder_jump"), std::string::npos) << status;
            if (fault_s < 0.0) {
                fault_s = n.t_s;
                fault_status_tick = tick;
            }
        } else if (fault_s >= 0.0 && cleared_s < 0.0) {
            cleared_s = n.t_s;
        }
    }
    EXPECT_EQ(ready, 1u);
    ASSERT_GE(ready_s, 0.0);
    ASSERT_GE(fault_s, 0.0) << "no STATUS= with the fault";
    ASSERT_GE(cleared_s, 0.0) << "no STATUS= after the reset";
    // The tick that latched the fault names the flight record (flight-START-tickN.csv, beside
    // the summary). The watcher looks every 10 ms: the fault's STATUS= follows within a few
    // looks, where the once-a-second line could come up to 1000 ticks later.
    std::uint64_t fault_tick = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
        const std::string name = entry.path().filename().string();
        if (name.starts_with("flight-") && name.ends_with(".csv")) {
            fault_tick = std::stoull(name.substr(name.rfind("-tick") + 5));
        }
    }
    ASSERT_GT(fault_tick, 0u) << "no flight record";
    EXPECT_GE(fault_status_tick, fault_tick);
    EXPECT_LE(fault_status_tick, fault_tick + 150);
    EXPECT_GT(fault_s, ready_s);
    EXPECT_GT(cleared_s - fault_s, 1.0);  // the reset came 1.2 s after the fault was seen
    EXPECT_TRUE(has(notes.back(), "STOPPING=1")) << notes.back().text;
}

// No READY=1 for a start that fails (a config refused: exit 2, nothing sent at all) or a run
// whose first tick faults (an encoder jump at t = 0: exit 1; the service never became ready,
// so systemd reports a failed start rather than a service that ran).
TEST(HilServiceNotify, NoReadyWhenTheStartFailsOrTheFirstTickFaults) {
    const ScratchDir dir;
    const NotifySocket socket(dir.file("notify.sock"));
    DaemonRun run;
    // One run of `config_toml` for 1 s, free space, the service's socket: what it sent.
    const auto notes_of = [&](const std::string& config_toml, bool lockstep) {
        return collect_while(socket, [&] {
            run = run_hapticd(dir, {.config_toml = config_toml,
                                    .scene_toml = "[scene]\nname = \"free\"\naxes = 1\n",
                                    .duration_s = 1.0,
                                    .lockstep = lockstep,
                                    .identify = false,
                                    .with_log = false,
                                    .environment = {{"NOTIFY_SOCKET", dir.file("notify.sock")}}});
        });
    };
    DaemonConfig refused;
    refused.coupling = coupling_table(kHalfColgateGains, "passive");
    std::string slow = refused.toml();
    slow.replace(slow.find("rate_hz = "), std::string("rate_hz = ").size(), "rate_hz = 50 #");
    std::vector<Notification> notes = notes_of(slow, true);
    EXPECT_EQ(run.exit_code, 2) << run.err;
    EXPECT_NE(run.err.find("rate_hz"), std::string::npos) << run.err;
    EXPECT_TRUE(notes.empty()) << notes.front().text;

    DaemonConfig faulting;
    faulting.coupling = coupling_table(kHalfColgateGains, "passive");
    faulting.sim_clock = "realtime";
    faulting.faults = "jump_at = 0.0\njump_counts = 20000\n";
    notes = notes_of(faulting.toml(), false);
    EXPECT_EQ(run.exit_code, 1) << run.err;
    ASSERT_TRUE(run.summary.is_object()) << run.err;
    EXPECT_NE(run.summary.at("faults").dump().find("encoder_jump"), std::string::npos)
        << run.summary.dump(2);
    for (const Notification& n : notes) EXPECT_FALSE(has(n, "READY=1")) << n.text;
    ASSERT_FALSE(notes.empty());
    EXPECT_TRUE(has(notes.back(), "STOPPING=1")) << notes.back().text;
}

// A service manager that stops reading (its queue of 10 datagrams full) never holds the run:
// the messages it has no room for are dropped, and the run ends on its duration.
TEST(HilServiceNotify, AManagerThatStopsReadingDoesNotHoldTheRun) {
    const ScratchDir dir;
    const NotifySocket socket(dir.file("notify.sock"));  // never read during the run
    DaemonConfig config;
    config.coupling = coupling_table(kHalfColgateGains, "passive");
    config.sim_clock = "realtime";
    const auto started = std::chrono::steady_clock::now();
    const DaemonRun run = run_hapticd(
        dir,
        {.config_toml = config.toml(),
         .scene_toml = "[scene]\nname = \"free\"\naxes = 1\n",
         .duration_s = 2.0,
         .lockstep = false,
         .identify = false,
         .with_log = true,
         .environment = {{"NOTIFY_SOCKET", dir.file("notify.sock")}, {"WATCHDOG_USEC", "100000"}}});
    const double took_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_EQ(run.summary.at("exit"), "duration");
    EXPECT_LT(took_s, 5.0);
    // The queue's worth (the kernel queues max_dgram_qlen + 1); the rest were dropped.
    const std::size_t queued = socket.drain().size();
    EXPECT_GE(queued, 10u);
    EXPECT_LE(queued, 11u);
}

}  // namespace
}  // namespace hapticd::testing
