// CRC-32C (Castagnoli), the frame check of the device protocol (docs/protocol.md section 3.3).
//
// Parameters (Rocksoft model / reveng "CRC-32/ISCSI"): width 32, poly 0x1EDC6F41 (reflected
// 0x82F63B78), init 0xFFFFFFFF, refin = refout = true, xorout 0xFFFFFFFF;
// check = crc32c("123456789") = 0xE3069283.
//
// Table-driven, one byte at a time (a 1 KiB constexpr table); no allocation, no state beyond
// the running value.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace hapticd::device::protocol {

/// The reflected generator polynomial.
inline constexpr std::uint32_t kCrc32cPolynomialReflected = 0x82F63B78u;
/// crc32c of the ASCII bytes "123456789": the standard check value.
inline constexpr std::uint32_t kCrc32cCheck = 0xE3069283u;

/// Running state: start with kCrc32cInit, feed bytes with crc32c_update, finish with
/// crc32c_final. crc32c() does all three.
inline constexpr std::uint32_t kCrc32cInit = 0xFFFFFFFFu;

std::uint32_t crc32c_update(std::uint32_t state, std::span<const std::byte> bytes) noexcept;

inline constexpr std::uint32_t crc32c_final(std::uint32_t state) noexcept {
    return state ^ 0xFFFFFFFFu;
}

/// CRC-32C of `bytes`.
inline std::uint32_t crc32c(std::span<const std::byte> bytes) noexcept {
    return crc32c_final(crc32c_update(kCrc32cInit, bytes));
}

}  // namespace hapticd::device::protocol
