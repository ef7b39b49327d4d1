// The frame: an 8-byte header, a payload of up to kMaxPayloadSize bytes and a CRC-32C
// (docs/protocol.md section 3). Every transport carries exactly these bytes; only the way a
// frame is delimited differs (USB: one frame per transfer; HID: one per report; serial: COBS
// with a 0x00 delimiter, stream_framer.hpp).
//
//   offset  size  field
//   0       1     magic         0x48 ('H')
//   1       1     version       protocol version the payload is laid out in (hello, error: 1)
//   2       1     type          MessageType
//   3       1     payload_size  n, 0..kMaxPayloadSize
//   4       4     session       u32, chosen by the host in hello, echoed in every frame
//   8       n     payload       the message (messages.hpp)
//   8+n     4     crc           CRC-32C of bytes 0 .. 8+n-1, u32 little-endian
//
// decode_frame() checks the frame, in this order: size, magic, length, CRC, version, type.
// It does not look inside the payload; messages.hpp does.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "hapticd/device/protocol/error.hpp"

namespace hapticd::device::protocol {

inline constexpr std::uint8_t kMagic = 0x48;  ///< 'H'
/// The protocol versions this codec speaks (docs/protocol.md 3.2). Version 2 is version 1
/// with the sample's reserved bytes used to say which command is in effect and since when
/// (applied_lag, applied_age_us: section 4.6), so that the host can measure the loop delay.
/// Version 3 is version 2 with the identity's first reserved byte used for flags: a device
/// may say that it paces the loop (kIdentityPaced, section 5.8). Every other layout is the
/// same.
inline constexpr std::uint8_t kProtocolVersion1 = 1;
inline constexpr std::uint8_t kProtocolVersion2 = 2;
inline constexpr std::uint8_t kProtocolVersion3 = 3;
inline constexpr std::uint8_t kMinVersion = kProtocolVersion1;
inline constexpr std::uint8_t kMaxVersion = kProtocolVersion3;
/// The version of a message struct that does not say otherwise.
inline constexpr std::uint8_t kProtocolVersion = kProtocolVersion1;
/// The header version of hello and error frames, in every protocol version (section 3.2).
inline constexpr std::uint8_t kFrozenVersion = 1;

/// A version this codec speaks.
constexpr bool is_spoken_version(std::uint8_t version) noexcept {
    return version >= kMinVersion && version <= kMaxVersion;
}

inline constexpr std::size_t kHeaderSize = 8;
inline constexpr std::size_t kCrcSize = 4;
inline constexpr std::size_t kMaxPayloadSize = 48;                    ///< a 3-axis sample
inline constexpr std::size_t kMinFrameSize = kHeaderSize + kCrcSize;  // 12
inline constexpr std::size_t kMaxFrameSize = kHeaderSize + kMaxPayloadSize + kCrcSize;  // 60

/// Header field offsets.
inline constexpr std::size_t kOffsetMagic = 0;
inline constexpr std::size_t kOffsetVersion = 1;
inline constexpr std::size_t kOffsetType = 2;
inline constexpr std::size_t kOffsetPayloadSize = 3;
inline constexpr std::size_t kOffsetSession = 4;

/// Message types (docs/protocol.md section 4). Bit 7 set: device to host. Wire values:
/// never renumber.
enum class MessageType : std::uint8_t {
    hello = 0x01,          ///< host -> device: open a session, offer versions
    configure = 0x02,      ///< host -> device: set the watchdog timeout
    command = 0x03,        ///< host -> device: force command (one per period)
    poll = 0x04,           ///< host -> device: send a sample, change nothing
    bye = 0x05,            ///< host -> device: zero force, close the session
    identity = 0x81,       ///< device -> host: answer to hello
    configure_ack = 0x82,  ///< device -> host: answer to configure
    sample = 0x83,         ///< device -> host: answer to command and poll
    bye_ack = 0x85,        ///< device -> host: answer to bye
    error = 0xFF,          ///< device -> host: a request was refused
};

/// True for the ten values above.
constexpr bool is_message_type(std::uint8_t value) noexcept {
    switch (value) {
        case 0x01:
        case 0x02:
        case 0x03:
        case 0x04:
        case 0x05:
        case 0x81:
        case 0x82:
        case 0x83:
        case 0x85:
        case 0xFF:
            return true;
        default:
            return false;
    }
}

/// Host-to-device types have bit 7 clear.
constexpr bool is_host_to_device(MessageType type) noexcept {
    return (static_cast<std::uint8_t>(type) & 0x80u) == 0u;
}

/// hello and error keep the version-1 layout and header version 1 forever, so that two ends
/// with no version in common can still say so (section 3.2).
constexpr bool is_frozen_type(MessageType type) noexcept {
    return type == MessageType::hello || type == MessageType::error;
}

/// "hello", "sample", ...; "unknown" otherwise.
std::string_view to_string(MessageType type) noexcept;

struct FrameHeader {
    std::uint8_t version = kProtocolVersion;
    MessageType type = MessageType::poll;
    std::uint8_t payload_size = 0;
    std::uint32_t session = 0;
};

/// A checked frame: its header and a view of its payload inside the caller's buffer.
struct FrameView {
    FrameHeader header;
    std::span<const std::byte> payload;
};

/// The result of an encode: the frame's size in bytes when error == Error::none, else 0.
struct Encoded {
    std::size_t size = 0;
    Error error = Error::none;
    constexpr bool ok() const noexcept { return error == Error::none; }
};

/// Checks `bytes` as exactly one frame (no padding before or after) and fills `frame`.
/// Returns, in this order: truncated (< kMinFrameSize bytes), bad_magic, bad_length
/// (payload_size > kMaxPayloadSize, or more bytes than the header says), truncated (fewer),
/// bad_crc, bad_version, unknown_type; else none. Reads only inside `bytes`. After
/// bad_version and unknown_type the CRC was good and `frame` is filled in (its type may then be
/// a value outside MessageType), so that a device can answer with an error message.
Error decode_frame(std::span<const std::byte> bytes, FrameView& frame) noexcept;

/// The size of the frame that starts at bytes[0], from its header: kMinFrameSize +
/// payload_size; 0 when fewer than 4 bytes are given, byte 0 is not kMagic or payload_size is
/// above the maximum. For transports that pad a frame (HID reports): the frame is the first
/// frame_size() bytes. Checks nothing else.
std::size_t frame_size(std::span<const std::byte> bytes) noexcept;

/// Writes the header and the CRC around a payload that the caller has already written at
/// out[kHeaderSize .. kHeaderSize + header.payload_size). Returns the frame size, or
/// no_space if `out` is smaller than the frame, bad_length if payload_size is too large.
Encoded finish_frame(const FrameHeader& header, std::span<std::byte> out) noexcept;

}  // namespace hapticd::device::protocol
