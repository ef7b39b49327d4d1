// The `hid` transport: frames in HID reports through hidapi (hid_link.hpp,
// docs/transport-hid.md, docs/protocol.md 6.2).
#include "hapticd/device/hid/hid_link.hpp"

#include <fcntl.h>
#include <hidapi.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace hapticd::device::hid {
namespace {

namespace report = protocol::hid;
using link::LinkResult;

constexpr std::int64_t kNsPerMs = 1'000'000;
constexpr std::int64_t kMaxWaitMs = 1'000'000;  ///< one hid_read_timeout() call at most
constexpr int kDiscardLimit = 1024;             ///< reports discard_input() drops at most
constexpr int kWriteAttempts = 3;               ///< a write interrupted by a signal is retried

/// errno values of a write to a hidraw node whose device is gone (hidraw: ENODEV; a tty-
/// backed emulation: EIO).
bool device_gone(int error) noexcept {
    return error == ENODEV || error == EIO || error == ENXIO || error == EPIPE ||
           error == ESHUTDOWN;
}

std::string quoted(const std::string& text) { return "\"" + text + "\""; }

/// The hidraw line of config/udev/70-hapticd.rules for one device.
std::string udev_rule_line(std::uint16_t vid, std::uint16_t pid) {
    char line[200];
    std::snprintf(line, sizeof line,
                  "KERNEL==\"hidraw*\", SUBSYSTEM==\"hidraw\", ATTRS{idVendor}==\"%04x\", "
                  "ATTRS{idProduct}==\"%04x\", MODE=\"0660\", GROUP=\"plugdev\", "
                  "TAG+=\"uaccess\"",
                  vid, pid);
    return line;
}

}  // namespace

HidLink::HidLink(HidSettings settings) : settings_(std::move(settings)) {
    description_ = settings_.path.empty() ? "hid " + hex_ids(settings_.vid, settings_.pid)
                                          : "hid at " + settings_.path;
}

HidLink::~HidLink() { close(); }

void HidLink::open() {
    close();
    const std::vector<HidDeviceEntry> seen = enumerate_hid_devices();
    std::string path;
    if (settings_.path.empty()) {
        entry_ = select_hid_device(seen, settings_);
        path = entry_->path;
    } else {
        entry_ = check_configured_path(seen, settings_);
        path = settings_.path;
    }

    lock_node(path);
    errno = 0;
    device_ = hid_open_path(path.c_str());
    if (device_ == nullptr) fail_open(path, errno, utf8_from_wide(hid_error(nullptr)));

    if (entry_) {
        description_ = "hid " + hex_ids(entry_->vid, entry_->pid) + " serial " +
                       (entry_->serial.empty() ? std::string("(none)") : quoted(entry_->serial)) +
                       " at " + path +
                       (entry_->product.empty() ? "" : " (" + quoted(entry_->product) + ")");
    } else {
        description_ = "hid at " + path;
    }
    if (opened_once_) counts_.reopens.fetch_add(1, std::memory_order_relaxed);
    opened_once_ = true;
}

void HidLink::fail_open(const std::string& path, int error, const std::string& hidapi_error) const {
    const std::string what = entry_ ? entry_->describe() : path;
    const bool denied =
        error == EACCES || error == EPERM ||
        (::access(path.c_str(), R_OK | W_OK) != 0 && (errno == EACCES || errno == EPERM));
    if (denied) {
        const std::uint16_t vid = entry_ ? entry_->vid : settings_.vid;
        const std::uint16_t pid = entry_ ? entry_->pid : settings_.pid;
        throw std::runtime_error(
            "hid: permission denied opening " + what +
            ": this user may not read and write the hidraw node. Install the udev rule that "
            "grants access (sudo cp config/udev/70-hapticd.rules /etc/udev/rules.d/ && sudo "
            "udevadm control --reload-rules && sudo udevadm trigger, then replug the device); "
            "for this device it needs the line " +
            udev_rule_line(vid, pid) + " (docs/transport-hid.md, \"Access\")");
    }
    if (error == ENOENT) {
        throw std::runtime_error("hid: " + what +
                                 " went away before it could be opened (No such file or "
                                 "directory); is it being replugged?");
    }
    throw std::runtime_error(
        "hid: cannot open " + what + ": " +
        (hidapi_error.empty() ? std::string(std::strerror(error)) : hidapi_error) +
        " (docs/transport-hid.md)");
}

void HidLink::lock_node(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) fail_open(path, errno, "");
    struct flock lock {};
    lock.l_type = F_WRLCK;
    lock.l_whence = SEEK_SET;  // l_start = l_len = 0: the whole node
    if (::fcntl(fd, F_OFD_SETLK, &lock) != 0) {
        const int error = errno;
        ::close(fd);
        const std::string what = entry_ ? entry_->describe() : path;
        if (error == EAGAIN || error == EACCES) {
            throw std::runtime_error(
                "hid: " + what +
                " is in use: another hapticd has it open (one instance per device: give "
                "each its own [device.hid] serial or path, docs/transport-hid.md)");
        }
        throw std::runtime_error("hid: cannot lock " + path + " for " + what + ": " +
                                 std::strerror(error));
    }
    node_lock_fd_ = fd;
}

void HidLink::close() noexcept {
    if (device_ != nullptr) hid_close(device_);
    device_ = nullptr;
    if (node_lock_fd_ >= 0) ::close(node_lock_fd_);
    node_lock_fd_ = -1;
}

LinkResult HidLink::send(std::span<const std::byte> frame) noexcept {
    if (device_ == nullptr) return LinkResult::disconnected;
    const protocol::Encoded wrapped = report::wrap_report(report::kOutputReportId, frame, tx_);
    if (!wrapped.ok()) {
        counts_.send_errors.fetch_add(1, std::memory_order_relaxed);
        return LinkResult::error;
    }
    const auto* bytes = reinterpret_cast<const unsigned char*>(tx_.data());
    int written = -1;
    int error = 0;
    for (int attempt = 0; attempt < kWriteAttempts; ++attempt) {
        errno = 0;
        written = hid_write(device_, bytes, wrapped.size);
        error = errno;
        if (written >= 0 || error != EINTR) break;
    }
    if (written == static_cast<int>(wrapped.size)) {
        counts_.frames_sent.fetch_add(1, std::memory_order_relaxed);
        return LinkResult::ok;
    }
    counts_.send_errors.fetch_add(1, std::memory_order_relaxed);
    return written < 0 && device_gone(error) ? LinkResult::disconnected : LinkResult::error;
}

bool HidLink::accept_report(int bytes, std::span<std::byte> frame, std::size_t& size) noexcept {
    const std::span<const std::byte> received(rx_.data(), static_cast<std::size_t>(bytes));
    std::span<const std::byte> inner;
    if (report::unwrap_report(report::kInputReportId, received, inner) != protocol::Error::none ||
        inner.size() > frame.size()) {
        counts_.framing_errors.fetch_add(1, std::memory_order_relaxed);
        return false;
    }
    std::copy(inner.begin(), inner.end(), frame.begin());
    size = inner.size();
    return true;
}

LinkResult HidLink::receive(std::span<std::byte> frame, std::size_t& size,
                            std::int64_t deadline_ns) noexcept {
    if (device_ == nullptr) return LinkResult::disconnected;
    auto* buffer = reinterpret_cast<unsigned char*>(rx_.data());
    for (;;) {
        // hidapi waits in whole milliseconds: take the whole ones that are left, never more.
        const std::int64_t remaining_ns = deadline_ns - link::monotonic_now_ns();
        const int wait_ms = remaining_ns >= kNsPerMs
                                ? static_cast<int>(std::min(remaining_ns / kNsPerMs, kMaxWaitMs))
                                : 0;
        errno = 0;
        const int got = hid_read_timeout(device_, buffer, rx_.size(), wait_ms);
        if (got > 0) {
            if (accept_report(got, frame, size)) {
                counts_.frames_received.fetch_add(1, std::memory_order_relaxed);
                return LinkResult::ok;
            }
            continue;  // another report ID: not ours, wait on
        }
        if (got < 0) {
            if (errno == EINTR) continue;  // poll() interrupted by a signal
            // POLLHUP/POLLERR (hidapi leaves errno alone) or EIO: the node is gone.
            counts_.receive_errors.fetch_add(1, std::memory_order_relaxed);
            return LinkResult::disconnected;
        }
        const std::int64_t left_ns = deadline_ns - link::monotonic_now_ns();
        if (left_ns <= 0) return LinkResult::timeout;
        if (wait_ms == 0) {
            servo::sleep_until_monotonic_ns(link::monotonic_now_ns() +
                                            std::min(left_ns, kTailPollNs));
        }
    }
}

void HidLink::discard_input() noexcept {
    if (device_ == nullptr) return;
    auto* buffer = reinterpret_cast<unsigned char*>(rx_.data());
    for (int i = 0; i < kDiscardLimit; ++i) {
        if (hid_read_timeout(device_, buffer, rx_.size(), 0) <= 0) break;
    }
}

std::string HidLink::describe() const { return description_; }

link::LinkCounters HidLink::counters() const noexcept {
    link::LinkCounters c;
    c.frames_sent = counts_.frames_sent.load(std::memory_order_relaxed);
    c.frames_received = counts_.frames_received.load(std::memory_order_relaxed);
    c.send_errors = counts_.send_errors.load(std::memory_order_relaxed);
    c.receive_errors = counts_.receive_errors.load(std::memory_order_relaxed);
    c.framing_errors = counts_.framing_errors.load(std::memory_order_relaxed);
    c.reopens = counts_.reopens.load(std::memory_order_relaxed);
    return c;
}

std::unique_ptr<link::FrameLink> make_hid_link(TableReader& table,
                                               const link::LinkContext& context) {
    return std::make_unique<HidLink>(read_hid_settings(table, context));
}

}  // namespace hapticd::device::hid
