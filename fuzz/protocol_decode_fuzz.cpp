// libFuzzer target for the device protocol's decoders (docs/protocol.md sections 3, 4, 6).
//
// Every input is used four ways:
//   1. as one frame: decode() must agree with decode_frame() and a typed decode(), and a frame
//      that decodes must re-encode to exactly the same bytes. Random bytes almost never carry
//      a valid CRC, so the input is also tried with its length byte and CRC repaired, which
//      takes the fuzzer straight to the payload checks of every message type;
//   2. as a HID report: unwrap, then as 1;
//   3. as a serial byte stream: every frame the StreamDecoder hands out is at most
//      kMaxFrameSize bytes, survives COBS re-encoding unchanged, and goes through 1; a sample
//      that decodes also goes through a ReplyTracker;
//   4. as frame content for the stream encoder: encode_stream() then StreamDecoder gives it
//      back unchanged.
// Out-of-bounds reads are the sanitizers' business (-fsanitize=fuzzer,address,undefined); the
// invariants abort with a message. The same entry point replays the seed corpus under GCC in
// ctest (tests/fuzz_replay/fuzz_replay_main.cpp).
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <span>
#include <variant>

#include "fuzz_check.hpp"
#include "hapticd/device/protocol/crc32c.hpp"
#include "hapticd/device/protocol/frame.hpp"
#include "hapticd/device/protocol/messages.hpp"
#include "hapticd/device/protocol/reply_tracker.hpp"
#include "hapticd/device/protocol/stream_framer.hpp"
#include "hapticd/device/protocol/transport.hpp"

namespace {

using namespace hapticd::device::protocol;

bool same_bytes(std::span<const std::byte> a, std::span<const std::byte> b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
        if (a[i] != b[i]) return false;
    }
    return true;
}

template <typename M>
void check_typed(std::span<const std::byte> bytes, const Message& decoded) {
    M typed;
    const Error error = decode(bytes, typed);
    if (std::holds_alternative<M>(decoded)) {
        FUZZ_CHECK(error == Error::none);
        FUZZ_CHECK(typed == std::get<M>(decoded));
    } else {
        FUZZ_CHECK(error == Error::wrong_type);
    }
}

ReplyTracker g_tracker;

void check_frame(std::span<const std::byte> bytes) {
    FrameView frame;
    const Error frame_error = decode_frame(bytes, frame);
    Message message;
    const Error error = decode(bytes, message);
    if (frame_error != Error::none) {
        FUZZ_CHECK(error == frame_error);
        return;
    }
    // The frame is sound: only the payload can be wrong.
    FUZZ_CHECK(error == Error::none || error == Error::bad_payload_size ||
               error == Error::bad_field);
    FUZZ_CHECK(frame_size(bytes) == bytes.size());
    FUZZ_CHECK(frame.payload.size() == frame.header.payload_size);
    FUZZ_CHECK(frame.payload.data() == bytes.data() + kHeaderSize);
    if (error != Error::none) return;

    FUZZ_CHECK(type_of(message) == frame.header.type);
    FUZZ_CHECK(session_of(message) == frame.header.session);
    std::array<std::byte, kMaxFrameSize> again{};
    const Encoded encoded = encode(message, again);
    FUZZ_CHECK(encoded.ok());
    FUZZ_CHECK(same_bytes(std::span<const std::byte>(again).first(encoded.size), bytes));

    check_typed<Hello>(bytes, message);
    check_typed<Identity>(bytes, message);
    check_typed<Configure>(bytes, message);
    check_typed<ConfigureAck>(bytes, message);
    check_typed<ForceCommand>(bytes, message);
    check_typed<EncoderSample>(bytes, message);
    check_typed<Poll>(bytes, message);
    check_typed<Bye>(bytes, message);
    check_typed<ByeAck>(bytes, message);
    check_typed<ErrorReport>(bytes, message);

    if (const auto* sample = std::get_if<EncoderSample>(&message)) {
        if (g_tracker.session() != sample->session || g_tracker.version() != sample->version) {
            g_tracker.start(sample->session, sample->version);
        }
        // As if the host had sent the command the sample answers (and a few before it), so
        // that the acknowledgement checks are reached.
        g_tracker.command_sent(sample->command_sequence);
        const ReplyTracker::Result result = g_tracker.check(*sample);
        if (result.verdict == ReplyTracker::Verdict::accept) {
            FUZZ_CHECK(result.missed < 0x80000000u);
            if (result.applied == ReplyTracker::Applied::reported) {
                FUZZ_CHECK(sample->version >= kProtocolVersion2);
                FUZZ_CHECK(result.applied_sequence == sample->applied_sequence());
                FUZZ_CHECK(result.applied_time_us <= sample->time_us);
            }
            if (sample->version == kProtocolVersion1) {
                FUZZ_CHECK(result.applied == ReplyTracker::Applied::unsupported ||
                           result.applied == ReplyTracker::Applied::bad_time);
            }
        }
    }
}

void check_stream(std::span<const std::byte> bytes) {
    StreamDecoder decoder;
    std::size_t frames = 0;
    for (const std::byte b : bytes) {
        const StreamDecoder::Event event = decoder.push(b);
        if (event != StreamDecoder::Event::frame) {
            FUZZ_CHECK(event == StreamDecoder::Event::none || b == kStreamDelimiter);
            continue;
        }
        FUZZ_CHECK(b == kStreamDelimiter);
        ++frames;
        const std::span<const std::byte> frame = decoder.frame();
        FUZZ_CHECK(frame.size() <= kMaxFrameSize);
        check_frame(frame);

        // COBS round trip of what came out.
        std::array<std::byte, kMaxStreamFrameSize> encoded{};
        const Encoded result = encode_stream(frame, encoded);
        FUZZ_CHECK(result.ok());
        FUZZ_CHECK(result.size == stream_encoded_size(frame.size()));
        std::array<std::byte, kMaxFrameSize> copy{};
        for (std::size_t i = 0; i < frame.size(); ++i) copy[i] = frame[i];
        StreamDecoder again;
        std::size_t seen = 0;
        for (std::size_t i = 0; i < result.size; ++i) {
            FUZZ_CHECK(i + 1 == result.size || encoded[i] != kStreamDelimiter);
            if (again.push(encoded[i]) == StreamDecoder::Event::frame) {
                ++seen;
                FUZZ_CHECK(same_bytes(again.frame(),
                                      std::span<const std::byte>(copy).first(frame.size())));
            }
        }
        FUZZ_CHECK(seen == 1);
    }
    FUZZ_CHECK(decoder.counters().frames == frames);
}

void check_stream_encoder(std::span<const std::byte> bytes) {
    const std::span<const std::byte> frame = bytes.first(std::min(bytes.size(), kMaxFrameSize));
    std::array<std::byte, kMaxStreamFrameSize> encoded{};
    const Encoded result = encode_stream(frame, encoded);
    FUZZ_CHECK(result.ok());
    StreamDecoder decoder;
    std::size_t seen = 0;
    for (std::size_t i = 0; i < result.size; ++i) {
        if (decoder.push(encoded[i]) == StreamDecoder::Event::frame) {
            ++seen;
            FUZZ_CHECK(same_bytes(decoder.frame(), frame));
        }
    }
    FUZZ_CHECK(seen == 1);  // even an empty frame: COBS 0x01, then the delimiter
}

void check_hid(std::span<const std::byte> bytes) {
    std::span<const std::byte> frame;
    const Error error = hid::unwrap_report(hid::kInputReportId, bytes, frame);
    if (error != Error::none) {
        FUZZ_CHECK(error == Error::truncated || error == Error::bad_report_id);
        return;
    }
    FUZZ_CHECK(frame.data() == bytes.data() + 1);
    FUZZ_CHECK(frame.size() <= bytes.size() - 1);
    check_frame(frame);
}

/// The input as a frame with a consistent payload_size (when `fix_length`) and a good CRC.
void check_repaired_frame(std::span<const std::byte> bytes, bool fix_length) {
    if (bytes.size() < kMinFrameSize) return;
    std::array<std::byte, kMaxFrameSize> frame{};
    const std::size_t size = std::min(bytes.size(), kMaxFrameSize);
    for (std::size_t i = 0; i < size; ++i) frame[i] = bytes[i];
    if (fix_length) {
        frame[kOffsetMagic] = std::byte{kMagic};
        frame[kOffsetPayloadSize] = static_cast<std::byte>(size - kMinFrameSize);
    }
    const std::span<std::byte> view = std::span<std::byte>(frame).first(size);
    const std::uint32_t crc = crc32c(view.first(size - kCrcSize));
    for (std::size_t i = 0; i < kCrcSize; ++i) {
        view[size - kCrcSize + i] = static_cast<std::byte>((crc >> (8 * i)) & 0xFFu);
    }
    check_frame(view);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data), size);
    check_frame(bytes);
    check_repaired_frame(bytes, false);
    check_repaired_frame(bytes, true);
    check_hid(bytes);
    check_stream(bytes);
    check_stream_encoder(bytes);
    return 0;
}
