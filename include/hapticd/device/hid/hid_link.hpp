// The `hid` transport (docs/transport-hid.md): protocol frames in 64-byte HID reports
// through hidapi's hidraw backend (docs/protocol.md 6.2). Output report 1 carries a frame to
// the device, input report 2 one back, each zero-padded to 63 data bytes.
//
// Per tick (no allocation, lock, log or exception of ours):
//   send():    wrap_report() into a buffer allocated with the link, one hid_write() (on
//              hidraw a plain write(), synchronous: the kernel returns once the interrupt OUT
//              transfer, or SET_REPORT, is done);
//   receive(): hid_read_timeout() (poll() + read() of one report) until the deadline.
//              hidapi waits in whole milliseconds, so the wait is cut in two: whole
//              milliseconds in hid_read_timeout(), never past the deadline, then the rest
//              (under 1 ms) as non-blocking checks every kTailPollNs. A report with another
//              ID, or a frame that does not fit, is counted in framing_errors and skipped.
// hidapi's success paths allocate nothing (they free and set a null error string); its
// error paths calloc() an error message: once, when a device goes away.
//
// Disconnects: a read that fails for any reason but EINTR (hidapi reports POLLHUP/POLLERR
// from a removed hidraw node as -1, and read() says EIO), and a write that fails with ENODEV,
// EIO, ENXIO, EPIPE or ESHUTDOWN, are LinkResult::disconnected. open() enumerates again, so a
// device that comes back under another /dev/hidrawN is found by vid, pid and serial number.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "hapticd/device/hid/hid_enumeration.hpp"
#include "hapticd/device/hid/hid_settings.hpp"
#include "hapticd/device/link/frame_link.hpp"
#include "hapticd/device/link/protocol_device.hpp"
#include "hapticd/device/protocol/transport.hpp"

struct hid_device_;  // hidapi's device handle (hidapi.h: typedef struct hid_device_ hid_device)

namespace hapticd::device::hid {

/// receive()'s check interval for the part of a wait shorter than hidapi's 1 ms resolution.
inline constexpr std::int64_t kTailPollNs = 50'000;

class HidLink final : public link::FrameLink {
  public:
    explicit HidLink(HidSettings settings);
    ~HidLink() override;

    HidLink(const HidLink&) = delete;
    HidLink& operator=(const HidLink&) = delete;

    /// Enumerates (or takes device.hid.path) and opens the node. Throws std::runtime_error:
    /// not found (what was looked for and every hidraw device seen), several candidates,
    /// permission denied (the udev rule, config/udev/70-hapticd.rules), not a hidraw node.
    void open() override;
    void close() noexcept override;
    link::LinkResult send(std::span<const std::byte> frame) noexcept override;
    link::LinkResult receive(std::span<std::byte> frame, std::size_t& size,
                             std::int64_t deadline_ns) noexcept override;
    void discard_input() noexcept override;
    /// "hid 1209:4841 serial "HX-0001" at /dev/hidraw3 ("hapticd paddle")".
    std::string describe() const override;
    link::LinkCounters counters() const noexcept override;

    bool is_open() const noexcept { return device_ != nullptr; }
    /// The node open() chose (nullopt before the first open, or for an unlisted path).
    const std::optional<HidDeviceEntry>& entry() const noexcept { return entry_; }

  private:
    /// One report of `bytes` in rx_: the frame into `frame`, or a framing error.
    bool accept_report(int bytes, std::span<std::byte> frame, std::size_t& size) noexcept;
    [[noreturn]] void fail_open(const std::string& path, int error,
                                const std::string& hidapi_error) const;
    /// Takes the node for this link alone: an open file description locked for writing
    /// (an OFD lock, which flock() and other processes' POSIX locks do not disturb), so that
    /// a second hapticd on the same device is refused; hidraw itself lets any number open it.
    void lock_node(const std::string& path);

    int node_lock_fd_ = -1;  ///< holds the lock while the link is open

    HidSettings settings_;
    hid_device_* device_ = nullptr;
    std::optional<HidDeviceEntry> entry_;
    std::string description_;
    bool opened_once_ = false;

    std::array<std::byte, protocol::hid::kReportSize> tx_{};
    std::array<std::byte, protocol::hid::kReportSize> rx_{};

    struct Counts {
        std::atomic<std::uint64_t> frames_sent{0};
        std::atomic<std::uint64_t> frames_received{0};
        std::atomic<std::uint64_t> send_errors{0};
        std::atomic<std::uint64_t> receive_errors{0};
        std::atomic<std::uint64_t> framing_errors{0};
        std::atomic<std::uint64_t> reopens{0};
    };
    Counts counts_;
};

/// ProtocolDevice's MakeLink for "hid": reads the [device.hid] keys, returns an unopened link.
std::unique_ptr<link::FrameLink> make_hid_link(TableReader& table,
                                               const link::LinkContext& context);

}  // namespace hapticd::device::hid
