// The reference device behind an emulated hidraw node (hid_device_server.hpp).
#include "hid_device_server.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "hapticd/device/protocol/transport.hpp"

namespace hapticd::testing {
namespace {

namespace proto = device::protocol;
constexpr std::size_t kReport = proto::hid::kReportSize;
constexpr int kIdleMs = 2;  ///< a pause should the master ever poll a hangup

}  // namespace

HidDeviceServer::HidDeviceServer(int master_fd, const proto::EmulatorConfig& config)
    : master_(master_fd), device_(std::make_unique<proto::DeviceEmulator>(config)) {
    wake_ = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if (wake_ < 0) throw std::runtime_error(std::string("eventfd: ") + std::strerror(errno));
    thread_ = std::thread([this] { run(); });
}

HidDeviceServer::~HidDeviceServer() {
    stop();
    ::close(wake_);
}

void HidDeviceServer::stop() {
    if (!thread_.joinable()) return;
    const std::uint64_t one = 1;
    (void)::write(wake_, &one, sizeof one);
    thread_.join();
}

void HidDeviceServer::inject_input_report(std::span<const std::byte> report) { write_all(report); }

bool HidDeviceServer::await_answered(std::uint64_t output_reports,
                                     std::chrono::nanoseconds timeout) {
    std::unique_lock lock(answered_mutex_);
    return answered_changed_.wait_for(lock, timeout, [&] { return answered_ >= output_reports; });
}

void HidDeviceServer::write_all(std::span<const std::byte> bytes) {
    std::lock_guard lock(write_mutex_);
    // Counted first: a client may read the report before write() returns here.
    input_reports_.fetch_add(1);
    while (!bytes.empty()) {
        const ssize_t n = ::write(master_, bytes.data(), bytes.size());
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return;  // not while the master is open: a pty keeps what nobody reads
        bytes = bytes.subspan(static_cast<std::size_t>(n));
    }
}

void HidDeviceServer::run() {
    std::array<std::byte, kReport> report{};
    std::size_t have = 0;
    std::array<std::byte, proto::DeviceEmulator::kMaxReplyFrames * kReport> replies{};
    for (;;) {
        std::array<pollfd, 2> fds{{{master_, POLLIN, 0}, {wake_, POLLIN, 0}}};
        if (::poll(fds.data(), fds.size(), -1) < 0 && errno != EINTR) return;
        if ((fds[1].revents & POLLIN) != 0) return;
        if ((fds[0].revents & POLLIN) == 0) {
            // The node keeps its slave open (UmockdevHidraw::plug()), so the master does not
            // hang up when a client closes, only once the node is unplugged, after stop():
            // this is not reached. Should it be, a pause instead of a busy loop.
            if ((fds[0].revents & (POLLHUP | POLLERR | POLLNVAL)) != 0) {
                pollfd wake{wake_, POLLIN, 0};
                if (::poll(&wake, 1, kIdleMs) > 0) return;
            }
            continue;
        }
        const ssize_t n = ::read(master_, report.data() + have, report.size() - have);
        if (n <= 0) continue;
        have += static_cast<std::size_t>(n);
        if (have < report.size()) continue;
        have = 0;
        output_reports_.fetch_add(1);
        std::size_t size = 0;
        {
            std::lock_guard lock(mutex_);
            size = device_->handle_hid_report(report, replies);
        }
        for (std::size_t offset = 0; offset < size; offset += kReport) {
            write_all(std::span<const std::byte>(replies.data() + offset, kReport));
        }
        {
            std::lock_guard lock(answered_mutex_);
            ++answered_;
        }
        answered_changed_.notify_all();
    }
}

}  // namespace hapticd::testing
