// A transport that carries whole protocol frames (docs/protocol.md section 6): the one thing
// the usb, hid and serial plugins differ in. ProtocolDevice (protocol_device.hpp) speaks the
// protocol over any FrameLink: handshake, commands, samples, reconnection.
//
// Threads and real-time: send() and receive() are called from the servo tick and must not
// allocate, lock (beyond a library's own uncontended internal mutex), log or throw; every
// buffer they use is allocated by open(). open(), close() and discard_input() run outside the
// tick: in Device::open(), in Device::close(), or on ProtocolDevice's reconnect thread while
// the tick is not using the link (ProtocolDevice guarantees that the two never overlap).
// counters() alone may be called from any thread at any time while the link exists.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "hapticd/servo/monotonic_clock.hpp"

namespace hapticd::device::link {

enum class LinkResult : std::uint8_t {
    ok,
    timeout,       ///< nothing (whole) arrived before the deadline
    disconnected,  ///< gone (ENODEV, EIO on a tty, hangup) or unusable until reopened (a
                   ///< halted USB endpoint: clearing it is a blocking control request)
    error,         ///< this transfer failed (overflow, protocol error); the link stays usable
};

/// What the transport itself saw; ProtocolDevice adds the protocol-level counts.
struct LinkCounters {
    std::uint64_t frames_sent = 0;
    std::uint64_t frames_received = 0;  ///< handed to receive()'s caller
    std::uint64_t send_errors = 0;
    std::uint64_t receive_errors = 0;  ///< failed transfers and reads
    std::uint64_t framing_errors = 0;  ///< transport-level garbage dropped (bad COBS, wrong
                                       ///< report ID, oversize frame)
    std::uint64_t stalls = 0;          ///< USB: endpoint halts seen (cleared by reopening)
    std::uint64_t reopens = 0;         ///< successful open() calls after the first
};

class FrameLink {
  public:
    virtual ~FrameLink() = default;

    /// Outside the tick. Opens the transport; throws std::runtime_error saying what failed
    /// and what to do about it (not found: what was looked for; access denied: the udev rule
    /// in config/udev/; busy: who holds it). Called again after close() to reconnect.
    virtual void open() = 0;

    /// Outside the tick. Releases the transport; idempotent; never throws.
    virtual void close() noexcept = 0;

    /// Tick. One whole frame out; the transport adds its own framing (COBS and delimiter,
    /// report ID and padding, one USB transfer).
    virtual LinkResult send(std::span<const std::byte> frame) noexcept = 0;

    /// Tick. The next whole frame in, as the transport delimited it (its header and CRC are
    /// not checked yet: ProtocolDevice decodes it), waiting at most until CLOCK_MONOTONIC
    /// reaches `deadline_ns`; a deadline in the past means "only what is already here".
    /// `frame` holds protocol::kMaxFrameSize bytes; `size` is set on ok. A frame that does not
    /// fit is counted in framing_errors and skipped.
    virtual LinkResult receive(std::span<std::byte> frame, std::size_t& size,
                               std::int64_t deadline_ns) noexcept = 0;

    /// Outside the tick. Drops everything received and not yet read (before a handshake).
    virtual void discard_input() noexcept = 0;

    /// One line for messages: "usb 1209:4841 serial HX-0001 (bus 1 device 4)",
    /// "serial /dev/ttyACM0 at 1000000 baud".
    virtual std::string describe() const = 0;

    /// Any thread, also while the tick is in send() or receive() (ProtocolDevice::link_quality
    /// reads it from the control socket's thread): the counts are kept in relaxed atomics,
    /// each read on its own, and may be a transfer old. Never blocks.
    virtual LinkCounters counters() const noexcept = 0;
};

/// The clock of receive()'s deadline.
using servo::monotonic_now_ns;

}  // namespace hapticd::device::link
