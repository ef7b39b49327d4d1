// The `usb` transport (docs/transport-usb.md): protocol frames over libusb-1.0, one frame per
// transfer on an interrupt or bulk endpoint pair (docs/protocol.md 6.1).
//
// open() (outside the tick) creates its own libusb context, finds the device by VID:PID and
// USB serial number (usb_discovery.hpp), claims the protocol interface (usb_endpoints.hpp),
// clears both endpoints' halts, allocates every transfer and buffer, and submits the IN
// transfer. close() cancels what is in flight, waits for the callbacks, and releases it all:
// ProtocolDevice's reconnect thread calls close() then open() until the device is back, so a
// failed open() leaves nothing behind and a successful one needs no state from before.
//
// The tick (send, receive) only submits preallocated transfers and runs libusb's event
// handling with a timeout; our code allocates nothing there. libusb's Linux backend itself
// calloc()s the URB array of every submitted transfer (linux_usbfs.c) and frees it when the
// transfer completes: that is malloc, not operator new, measured in docs/transport-usb.md.
//
//   send:    copies the frame into a free OUT transfer (a ring of kOutTransfers) and submits
//            it; completion is collected by later event handling.
//   receive: the one IN transfer is always submitted; runs libusb's events until it
//            completes or the deadline passes (a late reply then completes a later receive),
//            copies the frame out and resubmits.
//   Errors:  LIBUSB_ERROR_NO_DEVICE / LIBUSB_TRANSFER_NO_DEVICE -> disconnected. A STALL
//            (endpoint halt) also -> disconnected: clearing a halt is a synchronous control
//            request (libusb_clear_halt), device I/O that can block for the kernel's 5 s
//            control timeout, so it is not done in the tick; the reconnect path's open()
//            clears both halts. Any other failed transfer -> error (counted), link usable.
#pragma once

#include <libusb.h>

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>

#include "hapticd/device/link/frame_link.hpp"
#include "hapticd/device/protocol/transport.hpp"
#include "hapticd/device/usb/usb_endpoints.hpp"
#include "hapticd/device/usb/usb_settings.hpp"

namespace hapticd::device::usb {

class UsbLink final : public link::FrameLink {
  public:
    /// OUT transfers in flight at most: a command per period normally completes within the
    /// next 1 ms USB frame, so the ring only fills when the device stops taking commands.
    static constexpr std::size_t kOutTransfers = 4;
    /// An OUT transfer not taken by the device within this is cancelled (send_errors).
    static constexpr unsigned kOutTimeoutMs = 10;
    /// How long close() waits for cancelled transfers to come back.
    static constexpr std::int64_t kCancelWaitNs = 200'000'000;

    explicit UsbLink(UsbSettings settings);
    ~UsbLink() override;

    UsbLink(const UsbLink&) = delete;
    UsbLink& operator=(const UsbLink&) = delete;

    void open() override;
    void close() noexcept override;
    link::LinkResult send(std::span<const std::byte> frame) noexcept override;
    link::LinkResult receive(std::span<std::byte> frame, std::size_t& size,
                             std::int64_t deadline_ns) noexcept override;
    void discard_input() noexcept override;
    std::string describe() const override;
    link::LinkCounters counters() const noexcept override;

    // Inspection (outside the tick).
    bool is_open() const noexcept { return handle_ != nullptr; }
    const UsbEndpoints& endpoints() const noexcept { return endpoints_; }
    const UsbSettings& settings() const noexcept { return settings_; }

  private:
    using Buffer = std::array<unsigned char, protocol::usb::kMaxPacketSize>;

    struct OutSlot {
        libusb_transfer* transfer = nullptr;
        Buffer buffer{};
        bool busy = false;
    };

    static void LIBUSB_CALL on_in_complete(libusb_transfer* transfer);
    static void LIBUSB_CALL on_out_complete(libusb_transfer* transfer);

    void open_device();
    void allocate_transfers();
    void release() noexcept;
    bool submit_in() noexcept;
    /// One round of libusb event handling, at most `timeout_ns` (0: only what is ready); it
    /// returns early once `*completed` is set (nullptr: no such flag).
    int handle_events(std::int64_t timeout_ns, int* completed) noexcept;
    bool transfers_in_flight() const noexcept;
    void count(std::atomic<std::uint64_t>& counter) noexcept {
        counter.fetch_add(1, std::memory_order_relaxed);
    }

    UsbSettings settings_;
    libusb_context* context_ = nullptr;
    libusb_device_handle* handle_ = nullptr;
    bool claimed_ = false;
    int bus_ = 0;
    int address_ = 0;
    std::string usb_serial_;
    UsbEndpoints endpoints_;
    bool opened_before_ = false;

    // Tick state. The callbacks run inside libusb_handle_events_*() on the calling thread.
    libusb_transfer* in_transfer_ = nullptr;
    Buffer in_buffer_{};
    bool in_submitted_ = false;
    int in_completed_ = 0;  ///< set by on_in_complete (libusb's `completed` flag)
    libusb_transfer_status in_status_ = LIBUSB_TRANSFER_COMPLETED;
    int in_length_ = 0;
    std::array<OutSlot, kOutTransfers> out_{};
    bool gone_ = false;    ///< the device went away: reopen
    bool halted_ = false;  ///< an endpoint stalled: reopen (open() clears the halt)

    struct Counts {
        std::atomic<std::uint64_t> frames_sent{0};
        std::atomic<std::uint64_t> frames_received{0};
        std::atomic<std::uint64_t> send_errors{0};
        std::atomic<std::uint64_t> receive_errors{0};
        std::atomic<std::uint64_t> framing_errors{0};
        std::atomic<std::uint64_t> stalls{0};
        std::atomic<std::uint64_t> reopens{0};
    } counts_;
};

}  // namespace hapticd::device::usb
