// Little-endian fixed-width fields at byte offsets (docs/protocol.md section 2, "Conventions").
//
// Every multi-byte field of the protocol is little-endian and read or written byte by byte
// here, never by casting a buffer to a struct: a frame may sit at any alignment (after a HID
// report ID, inside a COBS buffer), and the host's and the firmware's struct padding need not
// agree. The caller guarantees that `offset + sizeof(field)` lies inside the span; these
// functions do not check (the frame decoder checks the frame's size once, up front).
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>

namespace hapticd::device::protocol::wire {

inline constexpr std::uint8_t load_u8(std::span<const std::byte> bytes,
                                      std::size_t offset) noexcept {
    return static_cast<std::uint8_t>(bytes[offset]);
}

inline constexpr std::uint16_t load_u16(std::span<const std::byte> bytes,
                                        std::size_t offset) noexcept {
    return static_cast<std::uint16_t>(load_u8(bytes, offset) |
                                      (static_cast<unsigned>(load_u8(bytes, offset + 1)) << 8));
}

inline constexpr std::uint32_t load_u32(std::span<const std::byte> bytes,
                                        std::size_t offset) noexcept {
    std::uint32_t value = 0;
    for (std::size_t i = 0; i < 4; ++i) {
        value |= static_cast<std::uint32_t>(load_u8(bytes, offset + i)) << (8 * i);
    }
    return value;
}

inline constexpr std::uint64_t load_u64(std::span<const std::byte> bytes,
                                        std::size_t offset) noexcept {
    std::uint64_t value = 0;
    for (std::size_t i = 0; i < 8; ++i) {
        value |= static_cast<std::uint64_t>(load_u8(bytes, offset + i)) << (8 * i);
    }
    return value;
}

inline constexpr std::int32_t load_i32(std::span<const std::byte> bytes,
                                       std::size_t offset) noexcept {
    return static_cast<std::int32_t>(load_u32(bytes, offset));  // two's complement
}

inline constexpr std::int64_t load_i64(std::span<const std::byte> bytes,
                                       std::size_t offset) noexcept {
    return static_cast<std::int64_t>(load_u64(bytes, offset));  // two's complement
}

/// IEEE 754 binary64, little-endian (the bit pattern as a u64).
inline constexpr double load_f64(std::span<const std::byte> bytes, std::size_t offset) noexcept {
    return std::bit_cast<double>(load_u64(bytes, offset));
}

inline constexpr void store_u8(std::span<std::byte> bytes, std::size_t offset,
                               std::uint8_t value) noexcept {
    bytes[offset] = static_cast<std::byte>(value);
}

inline constexpr void store_u16(std::span<std::byte> bytes, std::size_t offset,
                                std::uint16_t value) noexcept {
    store_u8(bytes, offset, static_cast<std::uint8_t>(value & 0xFFu));
    store_u8(bytes, offset + 1, static_cast<std::uint8_t>(value >> 8));
}

inline constexpr void store_u32(std::span<std::byte> bytes, std::size_t offset,
                                std::uint32_t value) noexcept {
    for (std::size_t i = 0; i < 4; ++i) {
        store_u8(bytes, offset + i, static_cast<std::uint8_t>((value >> (8 * i)) & 0xFFu));
    }
}

inline constexpr void store_u64(std::span<std::byte> bytes, std::size_t offset,
                                std::uint64_t value) noexcept {
    for (std::size_t i = 0; i < 8; ++i) {
        store_u8(bytes, offset + i, static_cast<std::uint8_t>((value >> (8 * i)) & 0xFFu));
    }
}

inline constexpr void store_i32(std::span<std::byte> bytes, std::size_t offset,
                                std::int32_t value) noexcept {
    store_u32(bytes, offset, static_cast<std::uint32_t>(value));
}

inline constexpr void store_i64(std::span<std::byte> bytes, std::size_t offset,
                                std::int64_t value) noexcept {
    store_u64(bytes, offset, static_cast<std::uint64_t>(value));
}

inline constexpr void store_f64(std::span<std::byte> bytes, std::size_t offset,
                                double value) noexcept {
    store_u64(bytes, offset, std::bit_cast<std::uint64_t>(value));
}

}  // namespace hapticd::device::protocol::wire
