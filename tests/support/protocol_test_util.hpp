// Small helpers shared by the protocol tests.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "hapticd/device/protocol/messages.hpp"

namespace hapticd::device::protocol::testing {

using Bytes = std::vector<std::byte>;

inline Bytes bytes_of(std::initializer_list<int> values) {
    Bytes out;
    for (const int v : values) out.push_back(static_cast<std::byte>(v));
    return out;
}

inline Bytes bytes_of(std::string_view text) {
    Bytes out;
    for (const char c : text) out.push_back(static_cast<std::byte>(c));
    return out;
}

inline std::string hex(std::span<const std::byte> bytes) {
    static constexpr char kDigits[] = "0123456789abcdef";
    std::string out;
    for (const std::byte b : bytes) {
        if (!out.empty()) out += ' ';
        out += kDigits[static_cast<unsigned>(b) >> 4];
        out += kDigits[static_cast<unsigned>(b) & 0xFu];
    }
    return out;
}

/// Encodes or fails the test's expectations (returns an empty vector).
template <typename M>
Bytes encoded(const M& message) {
    std::array<std::byte, kMaxFrameSize> buffer{};
    const Encoded result = encode(message, buffer);
    if (!result.ok()) return {};
    return {buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(result.size)};
}

/// Deterministic pseudo-random bytes (xorshift64).
class Noise {
  public:
    explicit Noise(std::uint64_t seed) : state_(seed | 1u) {}
    std::uint64_t next() {
        state_ ^= state_ << 13;
        state_ ^= state_ >> 7;
        state_ ^= state_ << 17;
        return state_;
    }
    std::byte byte() { return static_cast<std::byte>(next() & 0xFFu); }
    Bytes bytes(std::size_t n) {
        Bytes out(n);
        for (std::byte& b : out) b = byte();
        return out;
    }

  private:
    std::uint64_t state_;
};

}  // namespace hapticd::device::protocol::testing
