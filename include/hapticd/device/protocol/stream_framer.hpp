// Serial byte-stream framing: COBS with a 0x00 delimiter (docs/protocol.md section 6.3).
//
// On the wire every frame is COBS-encoded (Cheshire and Baker, "Consistent Overhead Byte
// Stuffing", 1999), which removes every 0x00 from it at a cost of one byte per 254, and is
// followed by a single 0x00. A 0x00 therefore always means "end of frame" and can never occur
// inside one: after any garbage, the receiver is back in step at the next 0x00, without
// searching or buffering (section 6.3 compares this with sync bytes + length).
//
// StreamDecoder takes bytes one at a time (or a span at a time) and decodes COBS on the fly
// into a fixed buffer of kMaxFrameSize bytes; it never allocates. It only delimits: each frame
// it hands out is then checked by decode() like a frame from any other transport.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "hapticd/device/protocol/frame.hpp"

namespace hapticd::device::protocol {

inline constexpr std::byte kStreamDelimiter{0x00};

/// Bytes on the wire for a frame of `frame_size` bytes: COBS overhead plus the delimiter.
constexpr std::size_t stream_encoded_size(std::size_t frame_size) noexcept {
    return frame_size + frame_size / 254 + 2;
}
/// The largest frame on a serial line: 62 bytes.
inline constexpr std::size_t kMaxStreamFrameSize = stream_encoded_size(kMaxFrameSize);

/// COBS-encodes `frame` into `out` and appends the 0x00 delimiter. Returns the bytes written
/// (stream_encoded_size(frame.size())), or no_space.
Encoded encode_stream(std::span<const std::byte> frame, std::span<std::byte> out) noexcept;

class StreamDecoder {
  public:
    enum class Event : std::uint8_t {
        none,      ///< need more bytes (also after an empty frame: two delimiters in a row)
        frame,     ///< a delimiter ended a frame: frame() holds it
        overflow,  ///< a delimiter ended more than kMaxFrameSize decoded bytes: dropped
        bad_cobs,  ///< a delimiter came inside a COBS block: dropped
    };

    struct Counters {
        std::uint64_t frames = 0;           ///< Event::frame
        std::uint64_t overflows = 0;        ///< Event::overflow
        std::uint64_t cobs_errors = 0;      ///< Event::bad_cobs
        std::uint64_t discarded_bytes = 0;  ///< bytes in dropped frames, delimiters excluded
    };

    /// One byte in. After Event::frame, frame() is valid until the next push() or reset().
    Event push(std::byte byte) noexcept;

    /// Every byte of `bytes`; calls on_frame(std::span<const std::byte>) for each frame.
    /// Returns the number of frames.
    template <typename OnFrame>
    std::size_t feed(std::span<const std::byte> bytes, OnFrame&& on_frame) {
        std::size_t frames = 0;
        for (const std::byte b : bytes) {
            if (push(b) == Event::frame) {
                ++frames;
                on_frame(frame());
            }
        }
        return frames;
    }

    /// The last frame completed (COBS-decoded, delimiter removed).
    std::span<const std::byte> frame() const noexcept { return {buffer_.data(), frame_size_}; }

    /// Forgets a partial frame (e.g. after reopening the port); counters are kept.
    void reset() noexcept;

    const Counters& counters() const noexcept { return counters_; }

  private:
    void start_frame() noexcept;
    void append(std::byte byte) noexcept;

    std::array<std::byte, kMaxFrameSize> buffer_{};
    std::size_t size_ = 0;        ///< decoded bytes of the frame in progress
    std::size_t frame_size_ = 0;  ///< of the last completed frame
    std::size_t encoded_ = 0;     ///< encoded bytes of the frame in progress
    std::uint8_t remaining_ = 0;  ///< data bytes left in the current COBS block
    bool zero_pending_ = false;   ///< the current block (code < 0xFF) ends with an implicit 0
    bool overflowed_ = false;
    Counters counters_;
};

}  // namespace hapticd::device::protocol
