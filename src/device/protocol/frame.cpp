// Frame header and CRC (docs/protocol.md section 3).
#include "hapticd/device/protocol/frame.hpp"

#include "hapticd/device/protocol/crc32c.hpp"
#include "hapticd/device/protocol/wire.hpp"

namespace hapticd::device::protocol {

std::string_view to_string(MessageType type) noexcept {
    switch (type) {
        case MessageType::hello:
            return "hello";
        case MessageType::configure:
            return "configure";
        case MessageType::command:
            return "command";
        case MessageType::poll:
            return "poll";
        case MessageType::bye:
            return "bye";
        case MessageType::identity:
            return "identity";
        case MessageType::configure_ack:
            return "configure_ack";
        case MessageType::sample:
            return "sample";
        case MessageType::bye_ack:
            return "bye_ack";
        case MessageType::error:
            return "error";
    }
    return "unknown";
}

std::string_view to_string(Error error) noexcept {
    switch (error) {
        case Error::none:
            return "none";
        case Error::truncated:
            return "truncated";
        case Error::bad_magic:
            return "bad_magic";
        case Error::bad_length:
            return "bad_length";
        case Error::bad_crc:
            return "bad_crc";
        case Error::bad_version:
            return "bad_version";
        case Error::unknown_type:
            return "unknown_type";
        case Error::bad_payload_size:
            return "bad_payload_size";
        case Error::bad_field:
            return "bad_field";
        case Error::wrong_type:
            return "wrong_type";
        case Error::no_space:
            return "no_space";
        case Error::bad_report_id:
            return "bad_report_id";
    }
    return "unknown";
}

std::string_view to_string(ErrorCode code) noexcept {
    switch (code) {
        case ErrorCode::unknown_type:
            return "unknown_type";
        case ErrorCode::unexpected_type:
            return "unexpected_type";
        case ErrorCode::bad_length:
            return "bad_length";
        case ErrorCode::bad_field:
            return "bad_field";
        case ErrorCode::bad_version:
            return "bad_version";
        case ErrorCode::unsupported_version:
            return "unsupported_version";
        case ErrorCode::no_session:
            return "no_session";
        case ErrorCode::wrong_session:
            return "wrong_session";
        case ErrorCode::wrong_axes:
            return "wrong_axes";
        case ErrorCode::out_of_range:
            return "out_of_range";
    }
    return "unknown";
}

Error decode_frame(std::span<const std::byte> bytes, FrameView& frame) noexcept {
    // Section 3.4: the checks and their order.
    if (bytes.size() < kMinFrameSize) return Error::truncated;
    if (wire::load_u8(bytes, kOffsetMagic) != kMagic) return Error::bad_magic;
    const std::size_t payload_size = wire::load_u8(bytes, kOffsetPayloadSize);
    if (payload_size > kMaxPayloadSize) return Error::bad_length;
    const std::size_t size = kMinFrameSize + payload_size;
    if (bytes.size() > size) return Error::bad_length;
    if (bytes.size() < size) return Error::truncated;

    const std::size_t crc_offset = kHeaderSize + payload_size;
    if (crc32c(bytes.first(crc_offset)) != wire::load_u32(bytes, crc_offset)) {
        return Error::bad_crc;
    }

    // The CRC vouches for the header: fill it in before the message-level checks, so that a
    // device can still answer a frame of a version or type it does not know.
    const std::uint8_t version = wire::load_u8(bytes, kOffsetVersion);
    const std::uint8_t type = wire::load_u8(bytes, kOffsetType);
    frame.header.version = version;
    frame.header.type = static_cast<MessageType>(type);
    frame.header.payload_size = static_cast<std::uint8_t>(payload_size);
    frame.header.session = wire::load_u32(bytes, kOffsetSession);
    frame.payload = bytes.subspan(kHeaderSize, payload_size);

    const bool frozen = type == static_cast<std::uint8_t>(MessageType::hello) ||
                        type == static_cast<std::uint8_t>(MessageType::error);
    if (frozen ? version != kFrozenVersion : (version < kMinVersion || version > kMaxVersion)) {
        return Error::bad_version;
    }
    if (!is_message_type(type)) return Error::unknown_type;
    return Error::none;
}

std::size_t frame_size(std::span<const std::byte> bytes) noexcept {
    if (bytes.size() < kOffsetPayloadSize + 1) return 0;
    if (wire::load_u8(bytes, kOffsetMagic) != kMagic) return 0;
    const std::size_t payload_size = wire::load_u8(bytes, kOffsetPayloadSize);
    if (payload_size > kMaxPayloadSize) return 0;
    return kMinFrameSize + payload_size;
}

Encoded finish_frame(const FrameHeader& header, std::span<std::byte> out) noexcept {
    if (header.payload_size > kMaxPayloadSize) return {0, Error::bad_length};
    const std::size_t crc_offset = kHeaderSize + header.payload_size;
    const std::size_t size = crc_offset + kCrcSize;
    if (out.size() < size) return {0, Error::no_space};
    wire::store_u8(out, kOffsetMagic, kMagic);
    wire::store_u8(out, kOffsetVersion, header.version);
    wire::store_u8(out, kOffsetType, static_cast<std::uint8_t>(header.type));
    wire::store_u8(out, kOffsetPayloadSize, header.payload_size);
    wire::store_u32(out, kOffsetSession, header.session);
    wire::store_u32(out, crc_offset, crc32c(out.first(crc_offset)));
    return {size, Error::none};
}

}  // namespace hapticd::device::protocol
