// The firmware's CRC-32C and COBS (firmware/core/hfw_crc32c.c, hfw_cobs.c) against the
// protocol's definitions and the host's own codec (docs/protocol.md sections 3.3 and 6.3).
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <random>
#include <span>
#include <vector>

#include "hapticd/device/protocol/crc32c.hpp"
#include "hapticd/device/protocol/stream_framer.hpp"
#include "hfw_cobs.h"
#include "hfw_crc32c.h"

namespace hapticd::testing {
namespace {

namespace protocol = device::protocol;

std::uint32_t bitwise_crc32c(const std::vector<std::uint8_t>& data) {
    // docs/protocol.md appendix A.1, bit by bit.
    std::uint32_t crc = 0xFFFFFFFFu;
    for (const std::uint8_t byte : data) {
        crc ^= byte;
        for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0x82F63B78u & (0u - (crc & 1u)));
    }
    return crc ^ 0xFFFFFFFFu;
}

std::span<const std::byte> as_bytes(const std::vector<std::uint8_t>& v) {
    return std::as_bytes(std::span<const std::uint8_t>(v));
}

TEST(FirmwareCrc32c, TheCheckValueOf123456789) {
    const std::vector<std::uint8_t> check = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
    EXPECT_EQ(hfw_crc32c(check.data(), check.size()), 0xE3069283u);
    EXPECT_EQ(hfw_crc32c(nullptr, 0), 0u);
}

TEST(FirmwareCrc32c, TableIsTheBitwiseDefinition) {
    // Each single byte's CRC exercises one table entry (and its init and xorout).
    for (int byte = 0; byte < 256; ++byte) {
        const std::vector<std::uint8_t> one = {static_cast<std::uint8_t>(byte)};
        ASSERT_EQ(hfw_crc32c(one.data(), 1), bitwise_crc32c(one)) << "byte " << byte;
    }
}

TEST(FirmwareCrc32c, AgreesWithTheHostOnRandomFrames) {
    std::mt19937 random(27);
    for (int trial = 0; trial < 2000; ++trial) {
        std::vector<std::uint8_t> data(random() % 61);
        for (auto& b : data) b = static_cast<std::uint8_t>(random());
        ASSERT_EQ(hfw_crc32c(data.data(), data.size()), protocol::crc32c(as_bytes(data)));
        ASSERT_EQ(hfw_crc32c(data.data(), data.size()), bitwise_crc32c(data));
    }
}

std::vector<std::uint8_t> random_frame(std::mt19937& random, std::size_t size, int zero_percent) {
    std::vector<std::uint8_t> frame(size);
    for (auto& b : frame) {
        b = static_cast<int>(random() % 100) < zero_percent
                ? 0
                : static_cast<std::uint8_t>(1 + random() % 255);
    }
    return frame;
}

/// The firmware's COBS of `frame`: its size + 2 bytes (one code byte below 254 bytes, and the
/// delimiter), also for the overlong frames the tests make on purpose.
std::vector<std::uint8_t> firmware_encode(const std::vector<std::uint8_t>& frame) {
    std::vector<std::uint8_t> out(frame.size() + 2);
    out.resize(hfw_cobs_encode(frame.data(), frame.size(), out.data()));
    return out;
}

/// Every frame the firmware decodes from `line`, fed byte by byte.
std::vector<std::vector<std::uint8_t>> firmware_decode(hfw_cobs_decoder& decoder,
                                                       const std::vector<std::uint8_t>& line) {
    std::vector<std::vector<std::uint8_t>> frames;
    for (const std::uint8_t byte : line) {
        if (hfw_cobs_push(&decoder, byte) != 0) {
            frames.emplace_back(decoder.frame, decoder.frame + decoder.size);
        }
    }
    return frames;
}

TEST(FirmwareCrc32c, InPartsIsTheWhole) {
    std::mt19937 random(31);
    for (int trial = 0; trial < 500; ++trial) {
        std::vector<std::uint8_t> data(1 + random() % 60);
        for (auto& b : data) b = static_cast<std::uint8_t>(random());
        const std::size_t cut = random() % (data.size() + 1);
        std::uint32_t state = hfw_crc32c_update(HFW_CRC32C_START, data.data(), cut);
        state = hfw_crc32c_update(state, data.data() + cut, data.size() - cut);
        ASSERT_EQ(state ^ HFW_CRC32C_START, hfw_crc32c(data.data(), data.size()));
    }
}

TEST(FirmwareCobs, InPartsIsTheWholeAndTheFinalBytesNeverChange) {
    // The board sends out[0 .. hfw_cobs_final()) while the rest of the frame is still to
    // come: those bytes must be the ones the whole encoding has.
    std::mt19937 random(32);
    for (int trial = 0; trial < 3000; ++trial) {
        const auto frame = random_frame(random, 1 + random() % HFW_MAX_FRAME_SIZE,
                                        static_cast<int>(random() % 101));
        const auto whole = firmware_encode(frame);
        std::vector<std::uint8_t> out(HFW_COBS_MAX_ENCODED, 0xEE);
        hfw_cobs_encoder encoder{};
        hfw_cobs_start(&encoder, out.data());
        const std::size_t cut = random() % (frame.size() + 1);
        hfw_cobs_put(&encoder, frame.data(), cut);
        const std::size_t final_bytes = hfw_cobs_final(&encoder);
        ASSERT_LE(final_bytes, whole.size());
        const std::vector<std::uint8_t> sent(out.begin(),
                                             out.begin() + static_cast<long>(final_bytes));
        hfw_cobs_put(&encoder, frame.data() + cut, frame.size() - cut);
        const std::size_t size = hfw_cobs_finish(&encoder);
        ASSERT_EQ(std::vector<std::uint8_t>(out.begin(), out.begin() + static_cast<long>(size)),
                  whole);
        ASSERT_EQ(std::vector<std::uint8_t>(whole.begin(),
                                            whole.begin() + static_cast<long>(final_bytes)),
                  sent);
        ASSERT_EQ(hfw_cobs_final(&encoder), size);
    }
}

TEST(FirmwareCobs, EncodesAsTheHostDoesAndRoundTrips) {
    std::mt19937 random(6);
    std::array<std::uint8_t, HFW_MAX_FRAME_SIZE> buffer{};
    hfw_cobs_decoder decoder{};
    hfw_cobs_init(&decoder, buffer.data());
    for (int trial = 0; trial < 3000; ++trial) {
        // Frames of every size the protocol has, from no zeros to nothing but zeros.
        const auto frame = random_frame(random, 1 + random() % HFW_MAX_FRAME_SIZE,
                                        static_cast<int>(random() % 101));
        const auto line = firmware_encode(frame);
        std::vector<std::byte> host(protocol::kMaxStreamFrameSize);
        const protocol::Encoded encoded = protocol::encode_stream(as_bytes(frame), host);
        ASSERT_TRUE(encoded.ok());
        ASSERT_EQ(std::vector<std::byte>(host.begin(), host.begin() + encoded.size),
                  std::vector<std::byte>(as_bytes(line).begin(), as_bytes(line).end()));
        ASSERT_EQ(line.size(), frame.size() + 2);
        for (std::size_t i = 0; i + 1 < line.size(); ++i) ASSERT_NE(line[i], 0) << i;
        const auto decoded = firmware_decode(decoder, line);
        ASSERT_EQ(decoded.size(), 1u);
        ASSERT_EQ(decoded[0], frame);
    }
    EXPECT_EQ(decoder.dropped, 0u);
}

TEST(FirmwareCobs, GarbageCostsOnlyTheFrameItRanInto) {
    std::mt19937 random(7);
    std::array<std::uint8_t, HFW_MAX_FRAME_SIZE> buffer{};
    hfw_cobs_decoder decoder{};
    hfw_cobs_init(&decoder, buffer.data());
    const auto good = random_frame(random, 44, 30);
    std::vector<std::uint8_t> line = {0x00};  // the host's opening delimiter
    for (int i = 0; i < 500; ++i) line.push_back(static_cast<std::uint8_t>(random()));
    const auto encoded = firmware_encode(good);
    line.push_back(0x00);
    for (int copy = 0; copy < 3; ++copy) line.insert(line.end(), encoded.begin(), encoded.end());
    const auto decoded = firmware_decode(decoder, line);
    // Whatever the garbage decoded to, the three good frames come through after it, whole.
    ASSERT_GE(decoded.size(), 3u);
    for (std::size_t i = decoded.size() - 3; i < decoded.size(); ++i) EXPECT_EQ(decoded[i], good);
}

TEST(FirmwareCobs, DropsAndCountsOverlongAndCutFrames) {
    std::array<std::uint8_t, HFW_MAX_FRAME_SIZE> buffer{};
    hfw_cobs_decoder decoder{};
    hfw_cobs_init(&decoder, buffer.data());
    // 61 non-zero bytes: one more than the largest frame.
    std::vector<std::uint8_t> overlong(HFW_MAX_FRAME_SIZE + 1, 0x55);
    std::vector<std::uint8_t> line = firmware_encode(overlong);
    EXPECT_TRUE(firmware_decode(decoder, line).empty());
    EXPECT_EQ(decoder.dropped, 1u);
    // A delimiter inside a block: the code byte promises 5 data bytes, 2 come.
    EXPECT_TRUE(firmware_decode(decoder, {0x06, 0x11, 0x22, 0x00}).empty());
    EXPECT_EQ(decoder.dropped, 2u);
    // Empty frames (delimiters in a row) are neither frames nor drops.
    EXPECT_TRUE(firmware_decode(decoder, {0x00, 0x00, 0x00}).empty());
    EXPECT_EQ(decoder.dropped, 2u);
    // And the next good frame decodes.
    const std::vector<std::uint8_t> frame = {0x48, 0x00, 0x01, 0x00};
    const auto decoded = firmware_decode(decoder, firmware_encode(frame));
    ASSERT_EQ(decoded.size(), 1u);
    EXPECT_EQ(decoded[0], frame);
}

TEST(FirmwareCobs, DecodesWhatTheHostEncodes) {
    std::mt19937 random(8);
    std::array<std::uint8_t, HFW_MAX_FRAME_SIZE> buffer{};
    hfw_cobs_decoder decoder{};
    hfw_cobs_init(&decoder, buffer.data());
    std::vector<std::uint8_t> line;
    std::vector<std::vector<std::uint8_t>> frames;
    for (int i = 0; i < 200; ++i) {
        frames.push_back(random_frame(random, 12 + random() % 49, 40));
        std::vector<std::byte> host(protocol::kMaxStreamFrameSize);
        const protocol::Encoded encoded = protocol::encode_stream(as_bytes(frames.back()), host);
        ASSERT_TRUE(encoded.ok());
        for (std::size_t j = 0; j < encoded.size; ++j) {
            line.push_back(std::to_integer<std::uint8_t>(host[j]));
        }
    }
    EXPECT_EQ(firmware_decode(decoder, line), frames);
}

}  // namespace
}  // namespace hapticd::testing
