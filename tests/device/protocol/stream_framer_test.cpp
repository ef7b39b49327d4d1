// Serial framing: COBS vectors, resynchronisation after garbage, split and merged reads,
// frames full of delimiter-like bytes, overflow and broken COBS (docs/protocol.md 6.3).
#include "hapticd/device/protocol/stream_framer.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "alloc_guard.hpp"
#include "hapticd/device/protocol/messages.hpp"
#include "protocol_test_util.hpp"

namespace hapticd::device::protocol {
namespace {

using testing::Bytes;
using testing::bytes_of;
using testing::encoded;
using testing::hex;
using testing::Noise;

Bytes stream_of(const Bytes& frame) {
    Bytes out(stream_encoded_size(frame.size()));
    const Encoded e = encode_stream(frame, out);
    EXPECT_TRUE(e.ok());
    out.resize(e.size);
    return out;
}

/// Every frame the decoder hands out for `bytes`, fed in chunks of `chunk` bytes.
std::vector<Bytes> frames_in(StreamDecoder& decoder, const Bytes& bytes, std::size_t chunk) {
    std::vector<Bytes> frames;
    for (std::size_t at = 0; at < bytes.size(); at += chunk) {
        const std::size_t n = std::min(chunk, bytes.size() - at);
        decoder.feed(
            std::span<const std::byte>(bytes).subspan(at, n),
            [&frames](std::span<const std::byte> f) { frames.emplace_back(f.begin(), f.end()); });
    }
    return frames;
}

ForceCommand command(std::uint32_t sequence) {
    ForceCommand m;
    m.session = 0x00000100;  // zero bytes in the header on purpose
    m.sequence = sequence;
    m.flags = kCommandEnable;
    m.axes = 3;
    m.force_un = {0, 0x00000100, -1};
    return m;
}

TEST(ProtocolStream, CobsVectors) {
    // Cheshire & Baker's examples (as tabulated on the COBS Wikipedia page), with our delimiter.
    EXPECT_EQ(hex(stream_of(bytes_of({0x00}))), "01 01 00");
    EXPECT_EQ(hex(stream_of(bytes_of({0x00, 0x00}))), "01 01 01 00");
    EXPECT_EQ(hex(stream_of(bytes_of({0x00, 0x11, 0x00}))), "01 02 11 01 00");
    EXPECT_EQ(hex(stream_of(bytes_of({0x11, 0x22, 0x00, 0x33}))), "03 11 22 02 33 00");
    EXPECT_EQ(hex(stream_of(bytes_of({0x11, 0x22, 0x33, 0x44}))), "05 11 22 33 44 00");
    EXPECT_EQ(hex(stream_of(bytes_of({0x11, 0x00, 0x00, 0x00}))), "02 11 01 01 01 00");
    EXPECT_EQ(hex(stream_of({})), "01 00");
    Bytes run(254);
    for (std::size_t i = 0; i < run.size(); ++i) run[i] = static_cast<std::byte>(i + 1);
    const Bytes encoded_run = stream_of(run);
    ASSERT_EQ(encoded_run.size(), 257u);
    EXPECT_EQ(encoded_run[0], std::byte{0xFF});
    EXPECT_EQ(encoded_run[255], std::byte{0x01});
    EXPECT_EQ(encoded_run[256], std::byte{0x00});
}

TEST(ProtocolStream, SizesOnTheWire) {
    EXPECT_EQ(kMaxStreamFrameSize, 62u);
    EXPECT_EQ(stream_encoded_size(12), 14u);
    std::array<std::byte, 13> small{};
    EXPECT_EQ(encode_stream(Bytes(12), small).error, Error::no_space);
}

TEST(ProtocolStream, RoundTripsRandomFrames) {
    Noise noise(1);
    StreamDecoder decoder;
    for (int i = 0; i < 2000; ++i) {
        const Bytes frame = noise.bytes(1 + noise.next() % kMaxFrameSize);
        const std::vector<Bytes> out = frames_in(decoder, stream_of(frame), 64);
        ASSERT_EQ(out.size(), 1u);
        EXPECT_EQ(out[0], frame);
    }
    EXPECT_EQ(decoder.counters().frames, 2000u);
}

TEST(ProtocolStream, FramesFullOfDelimiterLikeBytes) {
    // A frame whose fields are mostly 0x00 (and 0x01, COBS's smallest code) still arrives
    // whole: no 0x00 survives encoding.
    ForceCommand m = command(0x01000000);
    m.force_un = {0, 1, 0x01000100};
    const Bytes frame = encoded(m);
    int zeros = 0;
    for (const std::byte b : frame) zeros += b == std::byte{0} ? 1 : 0;
    EXPECT_GT(zeros, 10);
    const Bytes wire = stream_of(frame);
    for (std::size_t i = 0; i + 1 < wire.size(); ++i) EXPECT_NE(wire[i], std::byte{0}) << i;
    StreamDecoder decoder;
    const std::vector<Bytes> out = frames_in(decoder, wire, 1);
    ASSERT_EQ(out.size(), 1u);
    ForceCommand back;
    EXPECT_EQ(decode(out[0], back), Error::none);
    EXPECT_TRUE(back == m);
}

TEST(ProtocolStream, SplitAndMergedReads) {
    Bytes wire;
    std::vector<Bytes> sent;
    for (std::uint32_t s = 1; s <= 50; ++s) {
        sent.push_back(encoded(command(s)));
        const Bytes w = stream_of(sent.back());
        wire.insert(wire.end(), w.begin(), w.end());
    }
    // One byte at a time, odd chunks that split every frame somewhere, and all at once.
    for (const std::size_t chunk :
         {std::size_t{1}, std::size_t{7}, std::size_t{33}, std::size_t{61}, wire.size()}) {
        StreamDecoder decoder;
        EXPECT_EQ(frames_in(decoder, wire, chunk), sent) << "chunk " << chunk;
    }
}

TEST(ProtocolStream, ResynchronisesAfterRandomGarbage) {
    // Garbage (which may contain 0x00 and may look like frame starts) between valid frames:
    // every frame after a delimiter is recovered; garbage never decodes as a valid message.
    Noise noise(42);
    for (int trial = 0; trial < 200; ++trial) {
        Bytes wire = noise.bytes(noise.next() % 300);
        wire.push_back(std::byte{0});  // a sender's leading delimiter ends the garbage
        std::vector<Bytes> sent;
        for (std::uint32_t s = 0; s < 5; ++s) {
            sent.push_back(encoded(command(s + 1)));
            const Bytes w = stream_of(sent.back());
            wire.insert(wire.end(), w.begin(), w.end());
            if (s == 2) {
                // More garbage between frames, then a delimiter.
                const Bytes g = noise.bytes(1 + noise.next() % 100);
                wire.insert(wire.end(), g.begin(), g.end());
                wire.push_back(std::byte{0});
            }
        }
        StreamDecoder decoder;
        std::vector<Bytes> valid;
        for (const Bytes& f : frames_in(decoder, wire, 1 + noise.next() % 20)) {
            Message m;
            if (decode(f, m) == Error::none) valid.push_back(f);
        }
        EXPECT_EQ(valid, sent) << "trial " << trial;
    }
}

TEST(ProtocolStream, GarbageWithoutDelimiterCostsOnlyTheNextFrame) {
    // Without a leading delimiter, garbage runs into the first frame, which is lost (bad CRC,
    // bad COBS or overflow); the frame after it is back in step.
    Noise noise(5);
    Bytes wire = noise.bytes(17);
    for (std::byte& b : wire) {
        if (b == std::byte{0}) b = std::byte{0x5A};
    }
    const Bytes first = encoded(command(1));
    const Bytes second = encoded(command(2));
    for (const Bytes& f : {first, second}) {
        const Bytes w = stream_of(f);
        wire.insert(wire.end(), w.begin(), w.end());
    }
    StreamDecoder decoder;
    std::vector<Bytes> valid;
    for (const Bytes& f : frames_in(decoder, wire, 5)) {
        Message m;
        if (decode(f, m) == Error::none) valid.push_back(f);
    }
    ASSERT_EQ(valid.size(), 1u);
    EXPECT_EQ(valid[0], second);
}

TEST(ProtocolStream, OverflowIsDroppedAndCounted) {
    StreamDecoder decoder;
    Bytes wire(200, std::byte{0x11});  // one endless COBS run: more than a frame holds
    for (const std::byte b : wire) EXPECT_EQ(decoder.push(b), StreamDecoder::Event::none);
    EXPECT_EQ(decoder.push(std::byte{0}), StreamDecoder::Event::overflow);
    EXPECT_EQ(decoder.counters().overflows, 1u);
    EXPECT_EQ(decoder.counters().discarded_bytes, 200u);
    // And the next frame is fine.
    const Bytes frame = encoded(command(3));
    EXPECT_EQ(frames_in(decoder, stream_of(frame), 1), std::vector<Bytes>{frame});
}

TEST(ProtocolStream, LargestFrameFitsAndOneMoreByteDoesNot) {
    StreamDecoder decoder;
    Noise noise(9);
    const Bytes largest = noise.bytes(kMaxFrameSize);
    EXPECT_EQ(frames_in(decoder, stream_of(largest), 3), std::vector<Bytes>{largest});
    const Bytes too_large = noise.bytes(kMaxFrameSize + 1);
    EXPECT_TRUE(frames_in(decoder, stream_of(too_large), 3).empty());
    EXPECT_EQ(decoder.counters().overflows, 1u);
}

TEST(ProtocolStream, DelimiterInsideABlockIsBadCobs) {
    StreamDecoder decoder;
    // Code 0x05 promises four data bytes; the delimiter comes after two.
    for (const int b : {0x05, 0x11, 0x22})
        EXPECT_EQ(decoder.push(std::byte(b)), StreamDecoder::Event::none);
    EXPECT_EQ(decoder.push(std::byte{0}), StreamDecoder::Event::bad_cobs);
    EXPECT_EQ(decoder.counters().cobs_errors, 1u);
}

TEST(ProtocolStream, EmptyFramesAreIgnored) {
    StreamDecoder decoder;
    for (int i = 0; i < 5; ++i) EXPECT_EQ(decoder.push(std::byte{0}), StreamDecoder::Event::none);
    EXPECT_EQ(decoder.counters().frames, 0u);
    // 0x01 then the delimiter is a COBS-encoded empty frame: handed out, zero bytes long, and
    // the frame decoder calls it truncated.
    EXPECT_EQ(decoder.push(std::byte{1}), StreamDecoder::Event::none);
    EXPECT_EQ(decoder.push(std::byte{0}), StreamDecoder::Event::frame);
    EXPECT_TRUE(decoder.frame().empty());
}

TEST(ProtocolStream, ResetForgetsAPartialFrame) {
    StreamDecoder decoder;
    const Bytes wire = stream_of(encoded(command(4)));
    for (std::size_t i = 0; i < 10; ++i) decoder.push(wire[i]);
    decoder.reset();
    const std::vector<Bytes> out = frames_in(decoder, wire, 1);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(out[0], encoded(command(4)));
}

TEST(ProtocolStream, FramingAllocatesNothing) {
    const Bytes frame = encoded(command(7));
    std::array<std::byte, kMaxStreamFrameSize> wire{};
    StreamDecoder decoder;
    std::size_t frames = 0;
    hapticd::testing::AllocationGuard guard;
    for (int i = 0; i < 1000; ++i) {
        const Encoded e = encode_stream(frame, wire);
        frames += decoder.feed(std::span<const std::byte>(wire).first(e.size),
                               [](std::span<const std::byte>) {});
    }
    EXPECT_EQ(guard.allocations(), 0u);
    EXPECT_EQ(frames, 1000u);
}

}  // namespace
}  // namespace hapticd::device::protocol
