// The frame layer: header layout, every frame-level decode error in its documented order,
// frame_size() and finish_frame() (docs/protocol.md section 3).
#include "hapticd/device/protocol/frame.hpp"

#include <gtest/gtest.h>

#include "hapticd/device/protocol/crc32c.hpp"
#include "hapticd/device/protocol/messages.hpp"
#include "hapticd/device/protocol/wire.hpp"
#include "protocol_test_util.hpp"

namespace hapticd::device::protocol {
namespace {

using testing::Bytes;
using testing::encoded;

/// A valid 3-axis command frame to break.
Bytes command_frame() {
    ForceCommand command;
    command.session = 0x01020304;
    command.sequence = 7;
    command.flags = kCommandEnable;
    command.axes = 3;
    command.force_un = {1, -2, 3};
    return encoded(command);
}

/// Recomputes the CRC after editing a frame, so that a later check is what fails.
void fix_crc(Bytes& frame) {
    const std::size_t crc_at = frame.size() - kCrcSize;
    wire::store_u32(frame, crc_at, crc32c(std::span<const std::byte>(frame).first(crc_at)));
}

TEST(ProtocolFrame, HeaderLayout) {
    const Bytes frame = command_frame();
    ASSERT_EQ(frame.size(), 32u);  // 8 + (8 + 3 * 4) + 4
    EXPECT_EQ(frame[0], std::byte{0x48});
    EXPECT_EQ(frame[1], std::byte{1});     // version
    EXPECT_EQ(frame[2], std::byte{0x03});  // command
    EXPECT_EQ(frame[3], std::byte{20});    // payload_size
    EXPECT_EQ(wire::load_u32(frame, 4), 0x01020304u);
    EXPECT_EQ(wire::load_u32(frame, 28), crc32c(std::span<const std::byte>(frame).first(28)));

    FrameView view;
    ASSERT_EQ(decode_frame(frame, view), Error::none);
    EXPECT_EQ(view.header.version, 1);
    EXPECT_EQ(view.header.type, MessageType::command);
    EXPECT_EQ(view.header.payload_size, 20);
    EXPECT_EQ(view.header.session, 0x01020304u);
    EXPECT_EQ(view.payload.data(), frame.data() + 8);
    EXPECT_EQ(view.payload.size(), 20u);
}

TEST(ProtocolFrame, SizesFitEveryTransport) {
    EXPECT_EQ(kMinFrameSize, 12u);
    EXPECT_EQ(kMaxFrameSize, 60u);
    EXPECT_LT(kMaxFrameSize, 64u);  // one short USB full-speed packet
    EXPECT_LE(kMaxFrameSize, 63u);  // one HID report after its ID
}

TEST(ProtocolFrame, TruncatedBelowTheSmallestFrame) {
    const Bytes frame = command_frame();
    FrameView view;
    for (std::size_t n = 0; n < kMinFrameSize; ++n) {
        EXPECT_EQ(decode_frame(std::span<const std::byte>(frame).first(n), view), Error::truncated)
            << n;
    }
}

TEST(ProtocolFrame, TruncatedBelowTheHeadersLength) {
    const Bytes frame = command_frame();
    FrameView view;
    for (std::size_t n = kMinFrameSize; n < frame.size(); ++n) {
        EXPECT_EQ(decode_frame(std::span<const std::byte>(frame).first(n), view), Error::truncated)
            << n;
    }
}

TEST(ProtocolFrame, BadMagic) {
    Bytes frame = command_frame();
    frame[0] = std::byte{0x49};
    fix_crc(frame);
    FrameView view;
    EXPECT_EQ(decode_frame(frame, view), Error::bad_magic);
}

TEST(ProtocolFrame, BadLengthAbovePayloadMaximum) {
    Bytes frame(kMaxFrameSize + 1);
    frame[0] = std::byte{kMagic};
    frame[1] = std::byte{1};
    frame[2] = std::byte{0x83};
    frame[3] = std::byte{kMaxPayloadSize + 1};
    fix_crc(frame);
    FrameView view;
    EXPECT_EQ(decode_frame(frame, view), Error::bad_length);
    EXPECT_EQ(frame_size(frame), 0u);
}

TEST(ProtocolFrame, BadLengthWithTrailingBytes) {
    Bytes frame = command_frame();
    frame.push_back(std::byte{0});
    FrameView view;
    EXPECT_EQ(decode_frame(frame, view), Error::bad_length);
}

TEST(ProtocolFrame, BadCrcOnAnySingleBitFlip) {
    const Bytes frame = command_frame();
    FrameView view;
    // Every bit after the length byte (flipping magic or length is caught earlier).
    for (std::size_t bit = std::size_t{8} * 4; bit < frame.size() * 8; ++bit) {
        Bytes broken = frame;
        broken[bit / 8] ^= static_cast<std::byte>(1u << (bit % 8));
        EXPECT_EQ(decode_frame(broken, view), Error::bad_crc) << "bit " << bit;
    }
    // The version and type bytes are covered too.
    Bytes broken = frame;
    broken[1] ^= std::byte{0x02};
    EXPECT_EQ(decode_frame(broken, view), Error::bad_crc);
}

TEST(ProtocolFrame, BadVersion) {
    FrameView view;
    for (const int version : {0, 4, 255}) {
        Bytes frame = command_frame();
        frame[1] = static_cast<std::byte>(version);
        fix_crc(frame);
        EXPECT_EQ(decode_frame(frame, view), Error::bad_version) << version;
        // The CRC was good, so the header is there for an error reply.
        EXPECT_EQ(view.header.session, 0x01020304u);
        EXPECT_EQ(view.header.type, MessageType::command);
    }
}

TEST(ProtocolFrame, VersionsOneToThreeAreSpoken) {
    FrameView view;
    for (const int version : {1, 2, 3}) {
        Bytes frame = command_frame();
        frame[1] = static_cast<std::byte>(version);
        fix_crc(frame);
        EXPECT_EQ(decode_frame(frame, view), Error::none) << version;
        EXPECT_EQ(view.header.version, version);
    }
    EXPECT_TRUE(is_spoken_version(1));
    EXPECT_TRUE(is_spoken_version(2));
    EXPECT_TRUE(is_spoken_version(3));
    EXPECT_FALSE(is_spoken_version(0));
    EXPECT_FALSE(is_spoken_version(4));
}

TEST(ProtocolFrame, HelloAndErrorAreFrozenAtVersionOne) {
    Hello hello;
    hello.session = 9;
    hello.min_version = 1;
    hello.max_version = 7;  // a host offering newer versions still sends a version-1 hello
    Bytes frame = encoded(hello);
    ASSERT_FALSE(frame.empty());
    EXPECT_EQ(frame[1], std::byte{1});
    FrameView view;
    EXPECT_EQ(decode_frame(frame, view), Error::none);
    frame[1] = std::byte{2};
    fix_crc(frame);
    EXPECT_EQ(decode_frame(frame, view), Error::bad_version);
}

TEST(ProtocolFrame, UnknownType) {
    FrameView view;
    for (const int type : {0x00, 0x06, 0x7F, 0x80, 0x84, 0x86, 0xFE}) {
        Bytes frame = command_frame();
        frame[2] = static_cast<std::byte>(type);
        fix_crc(frame);
        EXPECT_EQ(decode_frame(frame, view), Error::unknown_type) << type;
        EXPECT_EQ(static_cast<int>(view.header.type), type);
    }
}

TEST(ProtocolFrame, ChecksRunInTheDocumentedOrder) {
    // Bad magic and bad CRC together: bad_magic. Bad CRC and bad version: bad_crc.
    Bytes frame = command_frame();
    frame[0] = std::byte{0};
    frame[10] ^= std::byte{1};
    FrameView view;
    EXPECT_EQ(decode_frame(frame, view), Error::bad_magic);
    frame = command_frame();
    frame[1] = std::byte{9};
    EXPECT_EQ(decode_frame(frame, view), Error::bad_crc);
}

TEST(ProtocolFrame, FrameSizeFromTheHeader) {
    const Bytes frame = command_frame();
    EXPECT_EQ(frame_size(frame), frame.size());
    EXPECT_EQ(frame_size(std::span<const std::byte>(frame).first(4)), frame.size());
    EXPECT_EQ(frame_size(std::span<const std::byte>(frame).first(3)), 0u);
    Bytes bad = frame;
    bad[0] = std::byte{0};
    EXPECT_EQ(frame_size(bad), 0u);
}

TEST(ProtocolFrame, FinishFrameNeedsRoom) {
    std::array<std::byte, kMaxFrameSize> buffer{};
    FrameHeader header;
    header.type = MessageType::poll;
    header.payload_size = 0;
    EXPECT_EQ(finish_frame(header, std::span<std::byte>(buffer).first(11)).error, Error::no_space);
    EXPECT_EQ(finish_frame(header, std::span<std::byte>(buffer).first(12)).size, 12u);
    header.payload_size = kMaxPayloadSize + 1;
    EXPECT_EQ(finish_frame(header, buffer).error, Error::bad_length);
}

TEST(ProtocolFrame, TypeDirectionsAndNames) {
    EXPECT_TRUE(is_host_to_device(MessageType::hello));
    EXPECT_TRUE(is_host_to_device(MessageType::command));
    EXPECT_FALSE(is_host_to_device(MessageType::sample));
    EXPECT_FALSE(is_host_to_device(MessageType::error));
    EXPECT_EQ(to_string(MessageType::configure_ack), "configure_ack");
    EXPECT_EQ(to_string(static_cast<MessageType>(0x42)), "unknown");
    EXPECT_EQ(to_string(Error::bad_crc), "bad_crc");
    EXPECT_EQ(to_string(ErrorCode::wrong_session), "wrong_session");
    int known = 0;
    for (int t = 0; t < 256; ++t) known += is_message_type(static_cast<std::uint8_t>(t)) ? 1 : 0;
    EXPECT_EQ(known, 10);
}

}  // namespace
}  // namespace hapticd::device::protocol
