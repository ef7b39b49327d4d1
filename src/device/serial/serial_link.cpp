// The serial FrameLink (serial_link.hpp; docs/protocol.md section 6.3).
#include "hapticd/device/serial/serial_link.hpp"

#include <poll.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <thread>
#include <utility>

namespace hapticd::device::serial {
namespace {

using link::LinkResult;
using protocol::StreamDecoder;

/// close() lets queued output (the last zero-force command, a bye) drain for this long, then
/// drops the rest: a device that stopped reading must not hold close() for the tty's
/// closing_wait (30 s by default).
constexpr auto kCloseDrainTime = std::chrono::milliseconds(100);

/// The errno values that mean the port is gone: a hung-up tty answers EIO, an unplugged
/// USB adapter ENODEV or ENXIO.
bool is_gone(int error) noexcept {
    return error == EIO || error == ENXIO || error == ENODEV || error == EPIPE;
}

}  // namespace

SerialLink::SerialLink(SerialSettings settings) : settings_(std::move(settings)) {}

SerialLink::~SerialLink() { close(); }

void SerialLink::open() {
    close();
    fd_ = open_serial_port(settings_, report_);
    rx_begin_ = rx_end_ = 0;
    decoder_.reset();
    cut_frame_ = false;
    // docs/protocol.md section 5.1, step 1: a lone delimiter, so that the device drops any
    // partial frame it holds (from line noise, or a host that died mid-frame).
    tx_[0] = protocol::kStreamDelimiter;
    if (write_all(0, 1) != LinkResult::ok) {
        close();
        throw std::runtime_error("serial port " + settings_.port + " (device.serial.port in " +
                                 settings_.source + "): opened, but writing to it failed");
    }
    if (opened_before_) add(kReopens);
    opened_before_ = true;
}

void SerialLink::close() noexcept {
    if (fd_ < 0) return;
    const auto give_up = std::chrono::steady_clock::now() + kCloseDrainTime;
    int queued = 0;
    while (::ioctl(fd_, TIOCOUTQ, &queued) == 0 && queued > 0 &&
           std::chrono::steady_clock::now() < give_up) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    (void)::tcflush(fd_, TCOFLUSH);
    if (settings_.exclusive) (void)::ioctl(fd_, TIOCNXCL);
    ::close(fd_);  // also releases the flock
    fd_ = -1;
}

SerialLink::Wait SerialLink::wait_for(short events, std::int64_t deadline_ns) noexcept {
    for (;;) {
        // At least one ppoll() with a zero timeout even past the deadline: it notices a hangup.
        const std::int64_t remaining_ns =
            std::max<std::int64_t>(0, deadline_ns - link::monotonic_now_ns());
        timespec timeout{static_cast<time_t>(remaining_ns / 1'000'000'000),
                         static_cast<long>(remaining_ns % 1'000'000'000)};
        pollfd port{fd_, events, 0};
        const int ready = ::ppoll(&port, 1, &timeout, nullptr);
        if (ready < 0) {
            if (errno == EINTR) continue;
            return Wait::error;
        }
        if (ready == 0) return Wait::timeout;
        if ((port.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0) {
            return Wait::hangup;
        }
        return Wait::ready;
    }
}

LinkResult SerialLink::write_all(std::size_t begin, std::size_t end) noexcept {
    const std::int64_t deadline_ns = link::monotonic_now_ns() + settings_.write_timeout_ns;
    std::size_t at = begin;
    while (at < end) {
        const ssize_t written = ::write(fd_, tx_.data() + at, end - at);
        if (written > 0) {
            at += static_cast<std::size_t>(written);
            continue;
        }
        if (written < 0 && errno == EINTR) continue;
        if (written < 0 && errno != EAGAIN) {
            if (is_gone(errno)) return LinkResult::disconnected;
            cut_frame_ = at > begin;
            return LinkResult::error;
        }
        // The output buffer is full (the device is not reading, or the line is too slow).
        switch (wait_for(POLLOUT, deadline_ns)) {
            case Wait::ready:
                continue;
            case Wait::hangup:
                return LinkResult::disconnected;
            case Wait::timeout:
            case Wait::error:
                cut_frame_ = at > begin;
                return LinkResult::error;
        }
    }
    return LinkResult::ok;
}

LinkResult SerialLink::send(std::span<const std::byte> frame) noexcept {
    if (fd_ < 0) return LinkResult::disconnected;
    // tx_[0] is room for the delimiter that finishes off a frame an earlier send() cut short.
    const protocol::Encoded encoded =
        protocol::encode_stream(frame, std::span<std::byte>(tx_).subspan(1));
    if (!encoded.ok()) {
        add(kSendErrors);
        return LinkResult::error;
    }
    const std::size_t begin = cut_frame_ ? 0 : 1;
    tx_[0] = protocol::kStreamDelimiter;
    cut_frame_ = false;
    const LinkResult result = write_all(begin, 1 + encoded.size);
    if (result == LinkResult::ok) {
        add(kFramesSent);
    } else {
        add(kSendErrors);
    }
    return result;
}

LinkResult SerialLink::receive(std::span<std::byte> frame, std::size_t& size,
                               std::int64_t deadline_ns) noexcept {
    if (fd_ < 0) return LinkResult::disconnected;
    bool hung_up = false;
    for (;;) {
        // Decode what is buffered; stop at the first whole frame and keep the rest.
        while (rx_begin_ < rx_end_) {
            const StreamDecoder::Event event = decoder_.push(rx_[rx_begin_++]);
            if (event == StreamDecoder::Event::frame) {
                const std::span<const std::byte> decoded = decoder_.frame();
                if (decoded.size() > frame.size()) {
                    add(kFramingErrors);
                    continue;
                }
                std::copy(decoded.begin(), decoded.end(), frame.begin());
                size = decoded.size();
                add(kFramesReceived);
                return LinkResult::ok;
            }
            // Garbage: the decoder dropped it and is in step again after this delimiter.
            if (event != StreamDecoder::Event::none) add(kFramingErrors);
        }
        rx_begin_ = rx_end_ = 0;

        const ssize_t got = ::read(fd_, rx_.data(), rx_.size());
        if (got > 0) {
            rx_end_ = static_cast<std::size_t>(got);
            continue;
        }
        if (got < 0 && errno == EINTR) continue;
        if (got < 0 && errno != EAGAIN) {
            if (is_gone(errno)) return LinkResult::disconnected;
            add(kReceiveErrors);
            return LinkResult::error;
        }
        // Nothing now. With VMIN = VTIME = 0 read() returns 0 both for "no bytes" and on a
        // hung-up tty; poll() tells the two apart (POLLHUP).
        if (hung_up) return LinkResult::disconnected;
        switch (wait_for(POLLIN, deadline_ns)) {
            case Wait::ready:
                continue;
            case Wait::hangup:
                hung_up = true;  // read what is left once more, then report it
                continue;
            case Wait::timeout:
                return LinkResult::timeout;
            case Wait::error:
                add(kReceiveErrors);
                return LinkResult::error;
        }
    }
}

void SerialLink::discard_input() noexcept {
    if (fd_ >= 0) (void)::tcflush(fd_, TCIFLUSH);
    rx_begin_ = rx_end_ = 0;
    decoder_.reset();
}

std::string SerialLink::describe() const {
    std::string text =
        "serial " + settings_.port + " at " + std::to_string(settings_.baud) + " baud";
    if (report_.low_latency) text += ", low latency";
    if (report_.latency_timer_ms > 1) {
        text += ", FTDI latency timer " + std::to_string(report_.latency_timer_ms) +
                " ms: replies will be late at 1 kHz (docs/transport-serial.md)";
    }
    return text;
}

link::LinkCounters SerialLink::counters() const noexcept {
    const auto get = [this](Count count) { return counts_[count].load(std::memory_order_relaxed); };
    link::LinkCounters counters;
    counters.frames_sent = get(kFramesSent);
    counters.frames_received = get(kFramesReceived);
    counters.send_errors = get(kSendErrors);
    counters.receive_errors = get(kReceiveErrors);
    counters.framing_errors = get(kFramingErrors);
    counters.reopens = get(kReopens);
    return counters;
}

std::unique_ptr<link::FrameLink> make_serial_link(TableReader& table,
                                                  const link::LinkContext& context) {
    SerialSettings settings = read_serial_settings(table);
    settings.source = context.config.source;
    // send() waits for room in the output buffer for at most one period (at least 1 ms).
    const double period_ns = 1e9 / context.config.rate_hz;
    settings.write_timeout_ns = std::max<std::int64_t>(1'000'000, std::llround(period_ns));
    return std::make_unique<SerialLink>(std::move(settings));
}

}  // namespace hapticd::device::serial
