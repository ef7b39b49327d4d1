// COBS framing for serial lines (docs/protocol.md section 6.3).
#include "hapticd/device/protocol/stream_framer.hpp"

namespace hapticd::device::protocol {

Encoded encode_stream(std::span<const std::byte> frame, std::span<std::byte> out) noexcept {
    const std::size_t size = stream_encoded_size(frame.size());
    if (out.size() < size) return {0, Error::no_space};
    // Each block: a code byte c, then c - 1 non-zero bytes; c < 0xFF means a 0x00 followed in
    // the data (dropped after the last block). A run of 254 non-zero bytes gives c = 0xFF.
    std::size_t code_at = 0;
    std::size_t write_at = 1;
    std::uint8_t code = 1;
    for (const std::byte b : frame) {
        if (b == std::byte{0}) {
            out[code_at] = std::byte{code};
            code_at = write_at++;
            code = 1;
            continue;
        }
        out[write_at++] = b;
        if (++code == 0xFF) {
            out[code_at] = std::byte{code};
            code_at = write_at++;
            code = 1;
        }
    }
    out[code_at] = std::byte{code};
    out[write_at++] = kStreamDelimiter;
    return {write_at, Error::none};
}

void StreamDecoder::start_frame() noexcept {
    size_ = 0;
    encoded_ = 0;
    remaining_ = 0;
    zero_pending_ = false;
    overflowed_ = false;
}

void StreamDecoder::reset() noexcept {
    start_frame();
    frame_size_ = 0;
}

void StreamDecoder::append(std::byte byte) noexcept {
    if (size_ == buffer_.size()) {
        overflowed_ = true;  // keep counting until the delimiter, store nothing more
        return;
    }
    buffer_[size_++] = byte;
}

StreamDecoder::Event StreamDecoder::push(std::byte byte) noexcept {
    if (byte == kStreamDelimiter) {
        // End of frame. The implicit zero of the last block is not data.
        const std::size_t encoded = encoded_;
        const bool overflowed = overflowed_;
        const bool cut_short = remaining_ != 0;
        const std::size_t size = size_;
        start_frame();
        if (encoded == 0) return Event::none;  // empty frame: a leading or doubled delimiter
        if (overflowed) {
            ++counters_.overflows;
            counters_.discarded_bytes += encoded;
            return Event::overflow;
        }
        if (cut_short) {
            ++counters_.cobs_errors;
            counters_.discarded_bytes += encoded;
            return Event::bad_cobs;
        }
        frame_size_ = size;
        ++counters_.frames;
        return Event::frame;
    }

    ++encoded_;
    if (overflowed_) return Event::none;
    if (remaining_ == 0) {
        // A code byte: first the zero that ended the previous block, if any.
        if (zero_pending_) append(std::byte{0});
        const auto code = static_cast<std::uint8_t>(byte);
        zero_pending_ = code != 0xFF;
        remaining_ = static_cast<std::uint8_t>(code - 1);
        return Event::none;
    }
    append(byte);
    --remaining_;
    return Event::none;
}

}  // namespace hapticd::device::protocol
