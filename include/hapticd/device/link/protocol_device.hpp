// A Device (device.hpp) that speaks the open protocol (docs/protocol.md) over a FrameLink.
// The usb, hid and serial plugins are each this class plus their own FrameLink.
//
// Per tick (docs/protocol.md section 5.3):
//   write(command): a command frame with the next sequence number; the device applies it,
//                   holds it for one period (ZOH) and answers with a sample;
//   read(sample):   that answer (a poll first if no command is outstanding), waiting at most
//                   reply_timeout; ReplyTracker drops replies of another session, late and
//                   repeated ones, and turns sequence gaps into a jump in Sample::sequence.
//   Bad frames (CRC, truncated, wrong version) are counted and skipped; no valid reply by
//   the deadline is IoResult::timeout with kStatusDropped (the servo latches read_timeout
//   after [safety] read_timeouts_allowed of them and zeroes force in that tick). Three
//   timeouts in a row in which the device answered, but only with samples behind the host's
//   count (5.3, "Out of step"), end the session as a disconnect.
//
// Versions: the hello offers 1..2; the device's identity picks one and every later frame of
// the session is in it. In version 2 each sample says which command is in effect and since
// when; read() passes that on as Sample::applied_write (the write() call it came from) and
// Sample::applied_time_s, after ReplyTracker's checks (a command never sent, times going
// backwards: AppliedReport::bad_command / bad_time, counted, never used).
//
// Disconnects: when the link reports the device gone, read() and write() return
// IoResult::disconnected (the servo latches device_lost and zeroes force) and, with
// `reconnect = true`, a background thread closes the link and reopens it every
// reconnect_interval until the same device answers the handshake again (same serial number,
// axes and resolution: a different device is refused and logged). The next read() adopts the
// new session. The tick and the thread never use the link at the same time: ownership passes
// through one atomic state (connected -> lost -> ready -> connected).
//
// Real-time: read() and write() do not allocate, lock, log or throw; open() and close() do.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "hapticd/device/device.hpp"
#include "hapticd/device/link/frame_link.hpp"
#include "hapticd/device/link/protocol_settings.hpp"
#include "hapticd/device/plugin_table.hpp"
#include "hapticd/device/protocol/messages.hpp"
#include "hapticd/device/protocol/reply_tracker.hpp"
#include "hapticd/servo/seqlock.hpp"

namespace hapticd::device::link {

/// What a transport needs to know to build its link.
struct LinkContext {
    const DeviceConfig& config;
    const ProtocolSettings& settings;
};

/// Reads the transport's own keys from the plugin table (the same reader: keys it does not
/// read are rejected) and returns the unopened link.
using MakeLink =
    std::function<std::unique_ptr<FrameLink>(TableReader& table, const LinkContext& context)>;

/// Protocol-level counts (the link's own are in FrameLink::counters()).
struct ProtocolCounters {
    std::uint64_t commands_sent = 0;
    std::uint64_t polls_sent = 0;
    std::uint64_t samples_accepted = 0;
    std::uint64_t reply_timeouts = 0;  ///< reads that ended without a valid reply
    std::uint64_t bad_frames = 0;      ///< failed decode (CRC, size, version, field)
    std::uint64_t wrong_session = 0;   ///< ReplyTracker verdicts
    std::uint64_t unexpected = 0;
    std::uint64_t late = 0;
    std::uint64_t duplicate = 0;
    std::uint64_t missed_samples = 0;  ///< sequence gaps, summed
    std::uint64_t device_errors = 0;   ///< error messages from the device
    std::uint64_t disconnects = 0;
    std::uint64_t out_of_step = 0;  ///< sessions ended: the device's samples all behind ours
    std::uint64_t reconnects = 0;
    std::uint64_t refused_devices = 0;      ///< reconnect attempts answered by another device
    std::uint64_t applied_reported = 0;     ///< version-2 acknowledgements passed on
    std::uint64_t applied_bad_command = 0;  ///< ... naming a command never sent
    std::uint64_t applied_bad_time = 0;     ///< ... with device times going backwards
};

class ProtocolDevice final : public Device {
  public:
    /// `plugin` names the table ([device.<plugin>]) and DeviceInfo::name.
    ProtocolDevice(std::string plugin, MakeLink make_link);
    ~ProtocolDevice() override;

    ProtocolDevice(const ProtocolDevice&) = delete;
    ProtocolDevice& operator=(const ProtocolDevice&) = delete;

    /// What open() reads of `config` for the plugin `plugin` ([device.<plugin>]: the shared
    /// keys, then make_link's), with nothing opened: the plugin's check_config()
    /// (plugin_abi.hpp). Throws input::ConfigError with open()'s message.
    static void check_config(const DeviceConfig& config, const std::string& plugin,
                             const MakeLink& make_link);

    void open(const DeviceConfig& config) override;
    DeviceInfo info() const override;
    IoResult read(Sample& sample) noexcept override;
    IoResult write(const Command& command) noexcept override;
    void close() noexcept override;
    /// Any thread, from open()'s return until the next open() or the destructor: counters()
    /// and the link's FrameLink::counters() (relaxed atomics and a seqlock, never waiting for
    /// the tick), summed into the operator's view. bad_frames = failed decodes + the
    /// transport's framing errors; transfer_errors = its send and receive errors.
    LinkQuality link_quality() const noexcept override;

    /// Any thread; the counts may be a tick old.
    ProtocolCounters counters() const noexcept;
    const protocol::Identity& identity() const noexcept { return identity_; }
    const FrameLink* link() const noexcept { return link_.get(); }

    /// The settings and the unopened link, read from config and the table: open()'s first
    /// step, check_config()'s whole, and what `haptic-tune conform` talks to the device
    /// through. Throws input::ConfigError.
    struct Configured {
        ProtocolSettings settings;
        std::unique_ptr<FrameLink> link;
    };
    static Configured configure(const DeviceConfig& config, const std::string& plugin,
                                const MakeLink& make_link);

  private:
    enum class LinkState : std::uint8_t { closed, connected, lost, ready };

    /// hello -> identity, configure -> ack, a disabled command with clear_faults -> sample.
    /// Outside the tick; throws std::runtime_error on failure.
    void handshake();
    void check_identity(const protocol::Identity& identity) const;
    void reconnect_loop();
    bool adopt_if_ready() noexcept;
    IoResult lost() noexcept;
    /// Sample::applied* from the tracker's verdict on a version-2 acknowledgement.
    void pass_on_applied(const protocol::ReplyTracker::Result& verdict,
                         Sample& sample) const noexcept;
    IoResult send_frame(std::span<const std::byte> frame) noexcept;
    std::int64_t reply_deadline_ns() const noexcept;

    std::string plugin_;
    MakeLink make_link_;
    std::unique_ptr<FrameLink> link_;
    ProtocolSettings settings_;
    DeviceConfig config_;
    DeviceInfo info_;
    protocol::Identity identity_{};          ///< the first handshake's
    protocol::Identity pending_identity_{};  ///< the latest handshake's
    bool have_identity_ = false;

    std::atomic<LinkState> state_{LinkState::closed};
    std::atomic<bool> stop_{false};
    std::thread reconnect_thread_;

    // Tick state (the tick thread, or the reconnect thread while it owns the link).
    protocol::ReplyTracker tracker_;
    /// The tracker's counters as of its last check, for counters() on any thread (TSan
    /// caught it copying them while the reconnect thread's handshake wrote them).
    servo::Seqlock<protocol::ReplyTracker::Counters> tracker_counts_;
    std::uint32_t session_ = 0;
    std::uint8_t version_ = protocol::kProtocolVersion1;  ///< the session's
    std::uint32_t command_sequence_ = 0;
    /// write() calls since open(); and, by command sequence modulo the ring's size, the call
    /// each command of the session was sent by (enough for any applied_lag).
    std::uint64_t write_calls_ = 0;
    std::array<std::uint64_t, 256> write_of_sequence_{};
    bool reply_outstanding_ = false;  ///< a command or poll was sent and not yet answered
    bool device_faulted_ = false;     ///< the last sample reported latched device faults
    int behind_reads_ = 0;            ///< reads in a row answered only from behind (5.3)
    std::int64_t reply_timeout_ns_ = 0;
    std::array<std::byte, protocol::kMaxFrameSize> tx_{};
    std::array<std::byte, protocol::kMaxFrameSize> rx_{};

    /// Counters written by one thread at a time, read by any (relaxed atomics).
    struct Counts {
        std::atomic<std::uint64_t> commands_sent{0}, polls_sent{0}, samples_accepted{0},
            reply_timeouts{0}, bad_frames{0}, device_errors{0}, disconnects{0}, out_of_step{0},
            reconnects{0}, refused_devices{0};
    };
    Counts counts_;
};

}  // namespace hapticd::device::link
