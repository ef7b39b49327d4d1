// RunWatcher (src/daemon/run_watcher.hpp) against a scripted loop: what it tells the service
// manager (NOTIFY_SOCKET, a datagram socket this test binds) look by look. The control socket
// runs on its own thread, so the loop's status can change between any two of the watcher's
// reads of it within one look; STATUS= must still tell each change of faults at once.
#include "run/run_watcher.hpp"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <array>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "hapticd/servo/faults.hpp"
#include "scratch_dir.hpp"

namespace hapticd::daemon {
namespace {

/// The service manager's end, bound at `path` and named in NOTIFY_SOCKET until destroyed.
class ServiceManager {
  public:
    explicit ServiceManager(const std::string& path) : path_(path) {
        fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
        sockaddr_un address{};
        address.sun_family = AF_UNIX;
        std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
        bound_ = fd_ >= 0 && path.size() < sizeof address.sun_path &&
                 ::bind(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0;
        ::setenv("NOTIFY_SOCKET", path.c_str(), 1);
    }
    ServiceManager(const ServiceManager&) = delete;
    ServiceManager& operator=(const ServiceManager&) = delete;
    ~ServiceManager() {
        ::unsetenv("NOTIFY_SOCKET");
        if (fd_ >= 0) ::close(fd_);
        ::unlink(path_.c_str());
    }

    bool bound() const { return bound_; }

    /// The STATUS= values that arrived, in order.
    std::vector<std::string> statuses() const {
        std::vector<std::string> out;
        for (;;) {
            std::array<char, 4096> text{};
            const ssize_t n = ::recv(fd_, text.data(), text.size(), 0);
            if (n < 0) return out;
            const std::string message(text.data(), static_cast<std::size_t>(n));
            const std::size_t at = message.find("STATUS=");
            if (at != std::string::npos) out.push_back(message.substr(at + 7));
        }
    }

  private:
    std::string path_;
    int fd_ = -1;
    bool bound_ = false;
};

bool tells_fault(const std::string& status) {
    return status.find("faults encoder_jump") != std::string::npos;
}

/// A RunWatcher over a scripted loop (its status, and whether it is done) with `options`,
/// `each_look` called at every look until the loop is done; what the watcher logged.
std::string watch_scripted_loop(const std::function<servo::StatusSnapshot()>& status,
                                const std::function<bool()>& done, const RunOptions& options,
                                const std::function<void()>& each_look) {
    const servo::RealtimeReport realtime_report;
    const WatchedLoop loop{
        .status = status,
        .realtime_report = [&]() -> const servo::RealtimeReport& { return realtime_report; },
        .done = done};
    const Config config;
    const servo::RealtimeRequest realtime;
    const device::DeviceInfo info;
    std::atomic<bool> stop{false};
    std::atomic<double> measured_rate_hz{0.0};
    std::ostringstream log;
    RunWatcher watcher(loop, options, config, realtime, info, stop, measured_rate_hz, log);
    watcher.watch(each_look);
    return log.str();
}

// The fault latches inside look 1, and a reset served on the control socket's thread clears it
// inside look 4: each after the watcher told the service and before it logged the change. The
// fault's STATUS= comes at look 2 and the cleared one's at look 5, not at the next
// once-a-second line (the run ends at look 8, 80 ms in). Both were lost while the service's
// STATUS= followed the journal's record of faults.
TEST(DaemonRunWatcher, AFaultClearedBetweenTheWatchersReadsIsToldAtTheNextLook) {
    const testing::ScratchDir dir;
    const ServiceManager manager(dir.file("notify.sock"));
    ASSERT_TRUE(manager.bound());

    int look = 0;
    std::uint64_t tick = 0;
    std::uint32_t faults = 0;
    const std::string log = watch_scripted_loop(
        [&] {
            servo::StatusSnapshot s;
            s.tick = ++tick;
            s.faults = faults;
            s.state = faults != 0u ? servo::ServoState::fault : servo::ServoState::running;
            return s;
        },
        [&] { return look >= 8; }, RunOptions{},
        [&] {
            ++look;
            if (look == 1) faults = servo::kFaultEncoderJump;  // the tick latches it, mid-look
            if (look == 4) faults = 0;                         // the reset, mid-look
        });

    const std::vector<std::string> told = manager.statuses();
    std::size_t first_fault = told.size();
    for (std::size_t i = 0; i < told.size(); ++i) {
        if (tells_fault(told[i])) {
            first_fault = i;
            break;
        }
    }
    ASSERT_LT(first_fault, told.size()) << "no STATUS= with the fault";
    bool cleared_told = false;
    for (std::size_t i = first_fault + 1; i < told.size(); ++i) {
        cleared_told = cleared_told || told[i].find("faults none") != std::string::npos;
    }
    EXPECT_TRUE(cleared_told) << "no STATUS= after the reset; the log said:\n" << log;
    // And the journal has both changes.
    EXPECT_NE(log.find("encoder_jump"), std::string::npos) << log;
}

// The watcher's look after a stall (here its own callback sleeps 350 ms, as a stalled host
// or a slow start would hold it) is late by three figures intervals of 0.1 s. It writes one
// figures line over the time since the last, not three of the same moment: the loop's tick
// moves only between looks here, and every figures line has a tick of its own.
TEST(DaemonRunWatcher, ALateLookWritesOneFiguresLineNotOnePerIntervalMissed) {
    int look = 0;
    RunOptions options;
    options.figures_interval_s = 0.1;
    const std::string log = watch_scripted_loop(
        [&] {
            servo::StatusSnapshot s;
            s.tick = 1 + 10 * static_cast<std::uint64_t>(look);
            s.state = servo::ServoState::running;
            return s;
        },
        [&] { return look >= 30; }, options,
        [&] {
            ++look;
            if (look == 2) std::this_thread::sleep_for(std::chrono::milliseconds(350));
        });

    std::istringstream lines(log);
    std::vector<std::uint64_t> ticks;
    for (std::string line; std::getline(lines, line);) {
        const std::size_t at = line.find(", tick ");
        if (line.find(" Hz over the last ") == std::string::npos || at == std::string::npos)
            continue;
        ticks.push_back(std::stoull(line.substr(at + 7)));
        if (ticks.size() == 1) {
            // The first, after the stall: over the 0.35 s or more since the start.
            const std::size_t over = line.find(" Hz over the last ") + 18;
            EXPECT_GE(std::stod(line.substr(over)), 0.3) << line;
        }
    }
    ASSERT_FALSE(ticks.empty()) << log;
    for (std::size_t i = 1; i < ticks.size(); ++i) {
        EXPECT_GT(ticks[i], ticks[i - 1]) << "two figures lines of one moment:\n" << log;
    }
}

}  // namespace
}  // namespace hapticd::daemon
