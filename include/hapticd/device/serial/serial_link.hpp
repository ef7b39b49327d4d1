// The serial transport (docs/protocol.md section 6.3, docs/transport-serial.md): protocol
// frames over a UART or USB CDC-ACM port, COBS-encoded with a 0x00 delimiter.
//
//   send():    encode_stream() into a buffer made at construction, then write() every byte;
//              if the port's output buffer is full, poll() for room for at most
//              SerialSettings::write_timeout_ns (one period). A frame cut short that way is
//              finished off by a 0x00 in front of the next one, so the device drops only it.
//   receive(): the bytes already read first, then read() what the port has, waiting in
//              ppoll() until the deadline; every byte goes through the StreamDecoder, which
//              resynchronises at the next 0x00 after garbage (counted in framing_errors).
//              Bytes after a whole frame stay in the buffer for the next call.
//   Hangup (the device unplugged, a pty's master closed), EIO, ENXIO, ENODEV:
//              LinkResult::disconnected; ProtocolDevice then close()s and open()s again.
//
// Real-time: send() and receive() do not allocate, lock, log or throw; their system calls
// are read, write, ppoll and clock_gettime.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "hapticd/device/link/frame_link.hpp"
#include "hapticd/device/link/protocol_device.hpp"
#include "hapticd/device/plugin_table.hpp"
#include "hapticd/device/protocol/stream_framer.hpp"
#include "hapticd/device/serial/serial_port.hpp"
#include "hapticd/device/serial/serial_settings.hpp"

namespace hapticd::device::serial {

class SerialLink final : public link::FrameLink {
  public:
    /// Bytes read from the port at a time: 4 kB is 10 ms at 4 Mbaud, far more than one
    /// period's worth of replies.
    static constexpr std::size_t kReadBufferSize = 4096;

    explicit SerialLink(SerialSettings settings);
    ~SerialLink() override;

    SerialLink(const SerialLink&) = delete;
    SerialLink& operator=(const SerialLink&) = delete;

    /// Opens and configures the port (open_serial_port()), then sends one 0x00 so that the
    /// device drops any partial frame (docs/protocol.md section 5.1, step 1).
    void open() override;
    void close() noexcept override;
    link::LinkResult send(std::span<const std::byte> frame) noexcept override;
    link::LinkResult receive(std::span<std::byte> frame, std::size_t& size,
                             std::int64_t deadline_ns) noexcept override;
    /// tcflush(TCIFLUSH), and forgets buffered bytes and a partial frame.
    void discard_input() noexcept override;
    /// "serial /dev/ttyACM0 at 2000000 baud", plus what open() found (low latency, FTDI
    /// latency timer).
    std::string describe() const override;
    link::LinkCounters counters() const noexcept override;

    const SerialSettings& settings() const noexcept { return settings_; }
    const PortReport& report() const noexcept { return report_; }
    bool is_open() const noexcept { return fd_ >= 0; }

  private:
    enum Count : std::size_t {
        kFramesSent,
        kFramesReceived,
        kSendErrors,
        kReceiveErrors,
        kFramingErrors,
        kReopens,
        kCountCount
    };
    void add(Count count) noexcept { counts_[count].fetch_add(1, std::memory_order_relaxed); }
    /// Writes tx_[begin, end), waiting for room at most write_timeout_ns.
    link::LinkResult write_all(std::size_t begin, std::size_t end) noexcept;
    enum class Wait : std::uint8_t { ready, timeout, hangup, error };
    /// Waits for `events` on the port until `deadline_ns` (one zero-timeout poll if it has
    /// passed). hangup: POLLHUP, POLLERR or POLLNVAL.
    Wait wait_for(short events, std::int64_t deadline_ns) noexcept;

    SerialSettings settings_;
    PortReport report_;
    int fd_ = -1;
    bool opened_before_ = false;
    bool cut_frame_ = false;  ///< the last send() gave up mid-frame: lead with a 0x00

    std::array<std::byte, 1 + protocol::kMaxStreamFrameSize> tx_{};
    std::array<std::byte, kReadBufferSize> rx_{};
    std::size_t rx_begin_ = 0;  ///< rx_[rx_begin_, rx_end_) are read and not yet decoded
    std::size_t rx_end_ = 0;
    protocol::StreamDecoder decoder_;
    std::array<std::atomic<std::uint64_t>, kCountCount> counts_{};
};

/// The `serial` plugin's link factory (ProtocolDevice's MakeLink): reads [device.serial]
/// (read_serial_settings()), sets the write timeout to one servo period (at least 1 ms).
std::unique_ptr<link::FrameLink> make_serial_link(TableReader& table,
                                                  const link::LinkContext& context);

}  // namespace hapticd::device::serial
