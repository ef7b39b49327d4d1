// A reference device: the firmware side of the protocol, playing the simulated device's
// physics (docs/protocol.md section 7). It answers host frames exactly as section 5 asks a
// firmware to, so that the USB, HID and serial plugins can be tested against it end to end,
// and so that a firmware author has a working model to compare with.
//
// Time is the simulated device's lockstep clock: virtual, advanced one period by each command
// (the command is held for that period, ZOH) and by advance_period() (a period in which no
// command arrived; the last force is still held). The watchdog counts in that time base. It
// stands still between requests: in its time a command arrives at the instant the sample it
// answers was latched, however long the host took.
//
// Processing delay: EmulatorConfig::sim.delay_s (the simulated device's loop delay) is the
// time from a command's arrival to its force taking effect; 0 applies it on arrival. It may
// exceed a period: the device still answers every command at once, and in protocol version 2
// each sample says which command is in effect and since when (applied_lag, applied_age_us),
// read from the simulated device's own record of what landed when. A version-1 session says
// nothing of it (and its command_sequence then names a command whose force may not act yet).
//
// There is no I/O inside: handle() takes one request frame and writes the reply frames into a
// buffer, so the same object serves
//   - a thread behind a pseudo-terminal (handle_stream(): bytes in, COBS bytes out),
//   - a umockdev ioctl handler answering USB URBs (handle(): one frame per transfer),
//   - a hidraw emulation (handle_hid_report(): 64-byte reports in and out).
// One thread at a time; instances are independent. handle(), advance_period() and the
// adapters do not allocate or throw.
//
// Fault knobs (faults()) make it misbehave in the ways a host must survive; each knob counts
// down as it fires. The simulated device's own faults (SimConfig::faults) also show through:
// stale and jumping encoders as status bits, dropped samples as missing replies, late samples
// as delayed replies, a disconnect as a device that answers nothing any more.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "hapticd/device/protocol/messages.hpp"
#include "hapticd/device/protocol/stream_framer.hpp"
#include "hapticd/device/sim/sim_config.hpp"
#include "hapticd/device/sim/sim_device.hpp"

namespace hapticd::device::protocol {

struct EmulatorConfig {
    /// The physics; the clock is forced to lockstep. force_limit_n must fit the wire
    /// (<= 2147.48 N) and 1e6 / rate_hz must be a whole number of microseconds.
    sim::SimConfig sim;
    std::string serial_number = "EMU-0001";  ///< 1..16 printable ASCII characters
    std::uint32_t firmware_version = 0x00010000;
    /// Versions it speaks (tests narrow them: max_version = 1 is a firmware from before the
    /// applied_* fields). It answers a hello with the highest version in common. Version 2 by
    /// default: it answers every request at once and never paces the loop, which is all that
    /// version 3 adds (the reference firmware does: docs/firmware.md).
    std::uint8_t min_version = kMinVersion;
    std::uint8_t max_version = kProtocolVersion2;
    std::uint32_t default_watchdog_timeout_us = kDefaultWatchdogTimeoutUs;  ///< section 5.4
    std::uint32_t max_watchdog_timeout_us = kMaxWatchdogTimeoutUs;          ///< <= 1 s
    /// A poll lets a period pass before it is answered (advance_period()), as a device whose
    /// clock runs while a host polls it once a period: what `haptic-tune conform` needs to
    /// see the watchdog trip (docs/conform.md). Off: a poll changes nothing, time included.
    bool poll_advances_period = false;
};

/// One-shot misbehaviour, for tests. Every counter is decremented as it fires.
struct EmulatorFaults {
    std::uint32_t corrupt_crc = 0;    ///< next n replies: last CRC byte flipped -> bad_crc
    std::uint32_t truncate = 0;       ///< next n replies: cut to half -> truncated
    std::uint32_t drop = 0;           ///< next n replies: processed but not sent -> timeout
    std::uint32_t wrong_session = 0;  ///< next n replies: another session id -> wrong_session
    std::uint32_t sequence_gap = 0;   ///< next sample skips this many sample_sequence values
    /// Next sample only: sample_sequence this far ahead, the count going on from where it was
    /// (a field corrupted past the CRC): the host is ahead of the device from then on.
    std::uint32_t sequence_ahead = 0;
    std::uint32_t delay = 0;          ///< next n replies: held back, sent before the next one
    std::uint32_t stall = 0;          ///< next n requests: ignored (a period passes for each)
    std::uint16_t device_faults = 0;  ///< fault bits raised (latched) at the next request
    // Version 2's acknowledgements, wrong in the ways a host must count and survive:
    std::uint32_t applied_unsent = 0;    ///< next n samples: name a command never sent
    std::uint32_t clock_back_us = 0;     ///< next sample: time_us this much in the past
    std::uint32_t applied_early_us = 0;  ///< next sample: its command took effect this much
                                         ///< earlier than it did (the moment moves back)
};

class DeviceEmulator {
  public:
    /// Room for what one handle() can write: a delayed reply, then the current one.
    static constexpr std::size_t kMaxReplyFrames = 2;
    static constexpr std::size_t kMaxReplySize = kMaxReplyFrames * kMaxFrameSize;

    /// The frames one request produced, back to back in the caller's buffer.
    struct Reply {
        std::size_t size = 0;  ///< total bytes
        std::size_t frames = 0;
        std::array<std::size_t, kMaxReplyFrames> frame_sizes{};
    };

    struct Counters {
        std::uint64_t requests = 0;          ///< frames handed to handle()
        std::uint64_t dropped_requests = 0;  ///< frame-level errors: no reply (section 3.4)
        std::uint64_t errors_sent = 0;       ///< error messages
        std::uint64_t commands_applied = 0;
        std::uint64_t samples_sent = 0;
        std::uint64_t watchdog_trips = 0;
    };

    /// Opens the simulated device. Throws std::invalid_argument naming the field on a bad
    /// configuration.
    explicit DeviceEmulator(const EmulatorConfig& config);

    /// One request frame (exactly one, as a transport delimited it) in; the replies out.
    /// `out` should hold kMaxReplySize bytes; a reply that does not fit is not sent.
    Reply handle(std::span<const std::byte> request, std::span<std::byte> out) noexcept;

    /// One period passes with no request: the device holds its force (ZOH) and its watchdog
    /// counts. A transport server calls it when a period goes by without a command.
    void advance_period() noexcept;

    /// Serial: any bytes in (partial frames are kept for the next call); the COBS-encoded
    /// replies out. Returns the bytes written; replies that do not fit are not sent.
    std::size_t handle_stream(std::span<const std::byte> bytes, std::span<std::byte> out) noexcept;

    /// HID: one output report (report ID first) in; input reports of hid::kReportSize bytes
    /// out. Returns the bytes written (a multiple of hid::kReportSize).
    std::size_t handle_hid_report(std::span<const std::byte> report,
                                  std::span<std::byte> out) noexcept;

    EmulatorFaults& faults() noexcept { return faults_; }

    // Inspection.
    const sim::SimDevice& sim() const noexcept { return sim_; }
    const Identity& identity() const noexcept { return identity_; }
    std::uint64_t time_us() const noexcept;
    bool session_open() const noexcept { return session_open_; }
    std::uint32_t session() const noexcept { return session_; }
    /// The version the current (or last) session speaks.
    std::uint8_t version() const noexcept { return version_; }
    std::uint32_t watchdog_timeout_us() const noexcept { return watchdog_timeout_us_; }
    std::uint16_t latched_faults() const noexcept { return latched_faults_; }
    /// The force the device holds from now on, N per axis (zero when disabled or faulted).
    std::array<double, kMaxProtocolAxes> output_force_n() const noexcept;
    /// True while a reply held back by the `delay` knob (or a late simulated sample) waits to
    /// go out in front of the next reply.
    bool delayed_reply_pending() const noexcept { return delayed_size_ > 0; }
    /// True once the simulated device has disconnected: nothing is answered any more.
    bool gone() const noexcept { return gone_; }
    const Counters& counters() const noexcept { return counters_; }

  private:
    /// Where the current request's replies go.
    struct Outbox {
        std::span<std::byte> out;
        Reply reply;
    };

    void dispatch(std::span<const std::byte> request, Outbox& outbox) noexcept;
    void on_hello(const FrameView& frame, const Hello& hello, Outbox& outbox) noexcept;
    void on_configure(const Configure& configure, Outbox& outbox) noexcept;
    void on_command(const ForceCommand& command, Outbox& outbox) noexcept;
    void on_poll(Outbox& outbox) noexcept;
    void on_bye(const Bye& bye, Outbox& outbox) noexcept;
    void send_error(const FrameHeader& request, ErrorCode code, std::uint32_t detail,
                    Outbox& outbox) noexcept;
    /// Reads the simulated device and sends a sample with these extra status bits.
    void send_sample(std::uint16_t status, Outbox& outbox) noexcept;
    /// Version 2: applied_lag and applied_age_us from what the simulated device says landed.
    void fill_applied(const servo::Sample& sample, EncoderSample& message) const noexcept;
    /// The fault knobs on a sample's time and acknowledgement.
    void damage_sample(EncoderSample& message) noexcept;
    /// Encodes a reply, applies the knobs, and puts it in the outbox.
    template <typename M>
    void send(M message, Outbox& outbox) noexcept;
    void emit(std::span<const std::byte> frame, Outbox& outbox) noexcept;

    /// One period of the simulated device under held_, then the watchdog check.
    void step_period() noexcept;
    void check_watchdog() noexcept;
    void zero_force() noexcept;
    void close_session() noexcept;

    sim::SimDevice sim_;
    Identity identity_;
    std::uint8_t min_version_;
    std::uint8_t max_version_;
    std::uint32_t default_watchdog_timeout_us_;
    std::uint32_t max_watchdog_timeout_us_;
    bool poll_advances_period_ = false;
    std::int32_t force_limit_un_;

    bool session_open_ = false;
    std::uint32_t session_ = 0;
    std::uint8_t version_ = kProtocolVersion1;  ///< the session's (the last hello's)
    std::uint32_t session_epoch_ = 0;           ///< +1 per session
    /// What the device writes into the simulated device each period: (session_epoch_ << 32)
    /// | the sequence of the command it holds; 0 before the session's first command.
    std::uint64_t current_tag_ = 0;
    std::uint64_t commands_in_session_ = 0;
    std::uint32_t watchdog_timeout_us_ = 0;
    servo::Command held_;        ///< what the device outputs (ZOH)
    bool command_seen_ = false;  ///< a command arrived in this session
    std::uint32_t last_command_sequence_ = 0;
    std::uint64_t last_command_us_ = 0;  ///< device time the last command arrived
    std::uint32_t periods_since_command_ = 0;
    bool last_clamped_ = false;
    std::uint16_t latched_faults_ = 0;
    std::uint32_t sample_sequence_ = 0;
    bool gone_ = false;

    EmulatorFaults faults_;
    std::array<std::byte, kMaxFrameSize> delayed_{};
    std::size_t delayed_size_ = 0;
    StreamDecoder stream_;
    Counters counters_;
};

}  // namespace hapticd::device::protocol
