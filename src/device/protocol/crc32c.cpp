// CRC-32C, table-driven (docs/protocol.md section 3.3).
#include "hapticd/device/protocol/crc32c.hpp"

#include <array>

namespace hapticd::device::protocol {
namespace {

constexpr std::array<std::uint32_t, 256> make_table() noexcept {
    std::array<std::uint32_t, 256> table{};
    for (std::uint32_t byte = 0; byte < 256; ++byte) {
        std::uint32_t crc = byte;
        for (int bit = 0; bit < 8; ++bit) {
            crc = (crc & 1u) != 0u ? (crc >> 1) ^ kCrc32cPolynomialReflected : crc >> 1;
        }
        table[byte] = crc;
    }
    return table;
}

constexpr std::array<std::uint32_t, 256> kTable = make_table();

}  // namespace

std::uint32_t crc32c_update(std::uint32_t state, std::span<const std::byte> bytes) noexcept {
    for (const std::byte b : bytes) {
        state = (state >> 8) ^ kTable[(state ^ static_cast<std::uint32_t>(b)) & 0xFFu];
    }
    return state;
}

}  // namespace hapticd::device::protocol
