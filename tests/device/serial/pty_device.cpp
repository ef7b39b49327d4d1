// The reference device behind a pseudo-terminal (pty_device.hpp).
#include "pty_device.hpp"

#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace hapticd::testing {
namespace {

[[noreturn]] void fail(const std::string& what) {
    throw std::runtime_error("pty: " + what + ": " + std::strerror(errno));
}

}  // namespace

PtyPair::PtyPair() {
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (master_ < 0) fail("posix_openpt");
    if (::grantpt(master_) != 0) fail("grantpt");
    if (::unlockpt(master_) != 0) fail("unlockpt");
    char name[128] = {};
    if (::ptsname_r(master_, name, sizeof name) != 0) fail("ptsname_r");
    slave_path_ = name;
    slave_ = ::open(name, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (slave_ < 0) fail("open " + slave_path_);
    // Raw from the start: a pty slave echoes by default, and the device's replies would come
    // back to it as requests before the host has set the line up.
    termios line{};
    if (::tcgetattr(slave_, &line) != 0) fail("tcgetattr");
    ::cfmakeraw(&line);
    if (::tcsetattr(slave_, TCSANOW, &line) != 0) fail("tcsetattr");
}

PtyPair::~PtyPair() {
    close_master();
    if (slave_ >= 0) ::close(slave_);
}

void PtyPair::close_master() noexcept {
    if (master_ >= 0) ::close(master_);
    master_ = -1;
}

void point_symlink(const std::string& link, const std::string& target) {
    const std::string temporary = link + ".new";
    ::unlink(temporary.c_str());
    if (::symlink(target.c_str(), temporary.c_str()) != 0) fail("symlink " + temporary);
    if (::rename(temporary.c_str(), link.c_str()) != 0) fail("rename to " + link);
}

PtyDevice::PtyDevice(const device::protocol::EmulatorConfig& config, std::string stable_path)
    : emulator_(config), stable_path_(std::move(stable_path)) {
    reply_.resize(4 * device::protocol::DeviceEmulator::kMaxReplySize);
    start();
}

PtyDevice::~PtyDevice() {
    // The link goes first, as udev removes /dev/serial/by-id/... on unplug: a host that keeps
    // reconnecting must not follow it to a /dev/pts/N that another test's pty reuses.
    if (!stable_path_.empty()) ::unlink(stable_path_.c_str());
    stop();
}

std::string PtyDevice::port() const { return stable_path_.empty() ? slave_path() : stable_path_; }

std::string PtyDevice::slave_path() const { return pair_ ? pair_->slave_path() : std::string(); }

void PtyDevice::start() {
    pair_ = std::make_unique<PtyPair>();
    if (!stable_path_.empty()) point_symlink(stable_path_, pair_->slave_path());
    int wake[2];
    if (::pipe2(wake, O_CLOEXEC | O_NONBLOCK) != 0) fail("pipe2");
    wake_read_ = wake[0];
    wake_write_ = wake[1];
    stop_ = false;
    thread_ = std::thread([this] { serve(); });
}

void PtyDevice::stop() {
    if (thread_.joinable()) {
        stop_ = true;
        const char byte = 1;
        (void)!::write(wake_write_, &byte, 1);
        thread_.join();
    }
    if (wake_read_ >= 0) ::close(wake_read_);
    if (wake_write_ >= 0) ::close(wake_write_);
    wake_read_ = wake_write_ = -1;
    pair_.reset();  // closes the master: the host's descriptor hangs up
}

void PtyDevice::hang_up() {
    if (!stable_path_.empty()) ::unlink(stable_path_.c_str());  // see the destructor
    stop();
}

void PtyDevice::plug_in() {
    stop();
    start();
}

void PtyDevice::set_request_hook(RequestHook hook) {
    std::lock_guard<std::mutex> lock(mutex_);
    hook_ = std::move(hook);
}

void PtyDevice::set_line_tap(LineTap tap) {
    std::lock_guard<std::mutex> lock(mutex_);
    tap_ = std::move(tap);
}

void PtyDevice::set_answering(bool answering) {
    std::lock_guard<std::mutex> lock(mutex_);
    answering_ = answering;
}

void PtyDevice::write_raw(std::span<const std::byte> bytes) {
    std::lock_guard<std::mutex> lock(mutex_);
    write_all(bytes);
}

bool PtyDevice::wait_for_requests(std::uint64_t n, int timeout_ms) {
    std::unique_lock<std::mutex> lock(mutex_);
    return served_.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                            [&] { return requests_.load() >= n; });
}

void PtyDevice::write_all(std::span<const std::byte> bytes) {
    std::size_t at = 0;
    while (at < bytes.size() && pair_ && pair_->master() >= 0) {
        const ssize_t n = ::write(pair_->master(), bytes.data() + at, bytes.size() - at);
        if (n > 0) {
            at += static_cast<std::size_t>(n);
        } else if (n < 0 && errno != EINTR && errno != EAGAIN) {
            return;  // the host is gone; nothing to tell it
        }
    }
}

void PtyDevice::handle(std::span<const std::byte> bytes) {
    std::lock_guard<std::mutex> lock(mutex_);
    bytes_received_ += bytes.size();
    if (!answering_) return;
    const bool ends_frame = !bytes.empty() && bytes.back() == std::byte{0};
    if (ends_frame && hook_) hook_(emulator_, emulator_.counters().requests);
    std::span<const std::byte> request = bytes;
    if (tap_.to_device) {
        tapped_.assign(bytes.begin(), bytes.end());
        tap_.to_device(tapped_);
        request = tapped_;
    }
    const std::size_t size = emulator_.handle_stream(request, reply_);
    std::span<const std::byte> answer(reply_.data(), size);
    if (tap_.to_host) {
        tapped_.assign(answer.begin(), answer.end());
        tap_.to_host(tapped_);
        answer = tapped_;
    }
    write_all(answer);
    requests_ = emulator_.counters().requests;
}

void PtyDevice::serve() {
    std::vector<std::byte> buffer(4096);
    while (!stop_) {
        pollfd fds[2] = {{pair_->master(), POLLIN, 0}, {wake_read_, POLLIN, 0}};
        if (::poll(fds, 2, -1) < 0) {
            if (errno == EINTR) continue;
            return;
        }
        if ((fds[1].revents & POLLIN) != 0) return;
        if ((fds[0].revents & POLLIN) == 0) {
            // POLLHUP without data: no slave open (our own keeps one open, so only briefly).
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
            continue;
        }
        const ssize_t n = ::read(pair_->master(), buffer.data(), buffer.size());
        if (n <= 0) {
            if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
            continue;
        }
        // Request by request, so that the hook sees each one before it is handled.
        std::size_t begin = 0;
        for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i) {
            if (buffer[i] == std::byte{0}) {
                handle(std::span<const std::byte>(buffer.data() + begin, i + 1 - begin));
                begin = i + 1;
            }
        }
        if (begin < static_cast<std::size_t>(n)) {
            handle(std::span<const std::byte>(buffer.data() + begin,
                                              static_cast<std::size_t>(n) - begin));
        }
        served_.notify_all();
    }
}

}  // namespace hapticd::testing
