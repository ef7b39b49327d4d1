// CRC-32C: the standard check value, and the Hamming distance the protocol relies on
// (docs/protocol.md section 3.3).
#include "hapticd/device/protocol/crc32c.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <vector>

#include "hapticd/device/protocol/frame.hpp"
#include "protocol_test_util.hpp"

namespace hapticd::device::protocol {
namespace {

using testing::Bytes;
using testing::bytes_of;

TEST(ProtocolCrc, CheckValueOf123456789) {
    EXPECT_EQ(crc32c(bytes_of("123456789")), 0xE3069283u);
    EXPECT_EQ(crc32c(bytes_of("123456789")), kCrc32cCheck);
}

TEST(ProtocolCrc, KnownVectors) {
    // RFC 3720 (iSCSI) appendix B.4: 32 bytes of zeros, of 0xFF, and an ascending sequence.
    EXPECT_EQ(crc32c(Bytes(32, std::byte{0x00})), 0x8A9136AAu);
    EXPECT_EQ(crc32c(Bytes(32, std::byte{0xFF})), 0x62A8AB43u);
    Bytes ascending(32);
    for (int i = 0; i < 32; ++i) ascending[i] = static_cast<std::byte>(i);
    EXPECT_EQ(crc32c(ascending), 0x46DD794Eu);
    EXPECT_EQ(crc32c({}), 0x00000000u);
}

TEST(ProtocolCrc, IncrementalEqualsOneShot) {
    const Bytes data = bytes_of("The quick brown fox jumps over the lazy dog");
    for (std::size_t cut = 0; cut <= data.size(); ++cut) {
        std::uint32_t state = kCrc32cInit;
        state = crc32c_update(state, std::span<const std::byte>(data).first(cut));
        state = crc32c_update(state, std::span<const std::byte>(data).subspan(cut));
        EXPECT_EQ(crc32c_final(state), crc32c(data)) << cut;
    }
}

// The syndromes of single-bit errors in a frame of `frame_bytes` bytes (data + 32-bit CRC,
// little-endian): an error pattern goes undetected exactly when the XOR of its bits'
// syndromes is zero (the CRC is affine in the data).
template <typename Crc>
std::vector<std::uint32_t> single_bit_syndromes(std::size_t frame_bytes, std::size_t crc_bits,
                                                Crc crc) {
    const std::size_t data_bytes = frame_bytes - crc_bits / 8;
    const Bytes zeros(data_bytes);
    const std::uint32_t base = crc(zeros);
    std::vector<std::uint32_t> syndromes;
    for (std::size_t bit = 0; bit < data_bytes * 8; ++bit) {
        Bytes one = zeros;
        one[bit / 8] = static_cast<std::byte>(1u << (bit % 8));
        syndromes.push_back(crc(one) ^ base);
    }
    for (std::size_t bit = 0; bit < crc_bits; ++bit) syndromes.push_back(1u << bit);
    return syndromes;
}

/// True when some pair of distinct 2-bit error patterns has the same syndrome, i.e. an
/// undetected error of weight 4 (or, if a single syndrome repeats, of weight 2).
bool has_undetected_weight_2_or_4(const std::vector<std::uint32_t>& singles) {
    std::vector<std::uint32_t> pairs;
    pairs.reserve(singles.size() * (singles.size() - 1) / 2);
    for (std::size_t i = 0; i < singles.size(); ++i) {
        for (std::size_t j = i + 1; j < singles.size(); ++j)
            pairs.push_back(singles[i] ^ singles[j]);
    }
    std::sort(pairs.begin(), pairs.end());
    if (!pairs.empty() && pairs.front() == 0u) return true;  // weight 2
    return std::adjacent_find(pairs.begin(), pairs.end()) != pairs.end();
}

TEST(ProtocolCrc, HammingDistanceAtLeastSixOverTheLargestFrame) {
    // HD >= 6 means every error of 1..5 bits in a frame is detected. The generator
    // 0x1EDC6F41 (+ x^32) has an even number of terms, so (x + 1) divides it and every
    // odd-weight error is detected; what is left to show is that no 2- or 4-bit error is
    // undetected, which the pair syndromes decide exhaustively (114,960 pairs at 60 bytes).
    EXPECT_EQ((std::popcount(0x1EDC6F41u) + 1) % 2, 0);
    for (const std::size_t size : {kMinFrameSize, std::size_t{32}, kMaxFrameSize}) {
        const auto singles =
            single_bit_syndromes(size, 32, [](const Bytes& d) { return crc32c(d); });
        for (const std::uint32_t s : singles) ASSERT_NE(s, 0u) << size;
        EXPECT_FALSE(has_undetected_weight_2_or_4(singles)) << size << "-byte frames";
    }
}

// CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, xorout 0): check 0x29B1.
std::uint32_t crc16_ccitt_false(std::span<const std::byte> data) {
    std::uint16_t crc = 0xFFFF;
    for (const std::byte b : data) {
        crc ^= static_cast<std::uint16_t>(static_cast<unsigned>(b) << 8);
        for (int i = 0; i < 8; ++i) {
            crc = (crc & 0x8000u) != 0u ? static_cast<std::uint16_t>((crc << 1) ^ 0x1021u)
                                        : static_cast<std::uint16_t>(crc << 1);
        }
    }
    return crc;
}

TEST(ProtocolCrc, Crc16WouldMissFourBitErrorsAtOurFrameSizes) {
    // The alternative the protocol rejected: at a 60-byte frame, some 4-bit errors pass a
    // CRC-16 (HD = 4; by pigeonhole alone, 114,960 pairs cannot have distinct 16-bit
    // syndromes), where CRC-32C still has HD = 6.
    ASSERT_EQ(crc16_ccitt_false(bytes_of("123456789")), 0x29B1u);
    const auto singles = single_bit_syndromes(kMaxFrameSize, 16,
                                              [](const Bytes& d) { return crc16_ccitt_false(d); });
    EXPECT_TRUE(has_undetected_weight_2_or_4(singles));
}

}  // namespace
}  // namespace hapticd::device::protocol
