// SerialLink (device/serial/serial_link.hpp) frame by frame against the reference device behind
// a pseudo-terminal: the handshake's frames round-trip; garbage between frames is dropped and
// the next frame decodes (docs/protocol.md 6.3, resynchronisation); a frame split across
// reads, and two frames in one read; the deadline; a hangup; no allocation per exchange.
#include "hapticd/device/serial/serial_link.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <iostream>
#include <thread>
#include <vector>

#include "alloc_guard.hpp"
#include "hapticd/device/protocol/messages.hpp"
#include "pty_device.hpp"
#include "serial_test_util.hpp"

namespace hapticd::testing {
namespace {

using device::link::LinkResult;
using device::serial::SerialLink;
using device::serial::SerialSettings;
namespace proto = device::protocol;

constexpr std::uint32_t kSession = 0x5E41A1u;
constexpr std::int64_t kGenerousNs = 5'000'000'000;  // a loaded 2-core VM

class SerialLinkTest : public ::testing::Test {
  protected:
    void SetUp() override {
        device_ = std::make_unique<PtyDevice>(emulator_config());
        link_ = std::make_unique<SerialLink>(settings_for(device_->port()));
        link_->open();
    }

    /// Sends `message`; expects the link to take it whole.
    template <typename M>
    void send(const M& message) {
        const Bytes frame = encoded(message);
        ASSERT_FALSE(frame.empty());
        ASSERT_EQ(link_->send(frame), LinkResult::ok);
    }

    /// The next frame, decoded; the test fails if none comes within the generous deadline.
    template <typename M>
    M receive() {
        std::array<std::byte, proto::kMaxFrameSize> frame{};
        std::size_t size = 0;
        M message{};
        const LinkResult result = link_->receive(frame, size, now_ns() + kGenerousNs);
        EXPECT_EQ(result, LinkResult::ok);
        if (result != LinkResult::ok) return message;
        EXPECT_EQ(proto::decode(std::span<const std::byte>(frame.data(), size), message),
                  proto::Error::none);
        return message;
    }

    /// Opens the session the way ProtocolDevice does (docs/protocol.md 5.1).
    void handshake() {
        send(proto::Hello{kSession, 1, 1});
        EXPECT_EQ(receive<proto::Identity>().session, kSession);
        send(proto::Configure{kSession, 50'000});
        EXPECT_EQ(receive<proto::ConfigureAck>().watchdog_timeout_us, 50'000u);
        send(proto::Poll{kSession});
        EXPECT_EQ(receive<proto::EncoderSample>().command_sequence, 0u);
    }

    /// A sample frame the device could have sent, for the resynchronisation tests.
    static Bytes sample_frame(std::uint32_t sample_sequence) {
        proto::EncoderSample sample;
        sample.session = kSession;
        sample.sample_sequence = sample_sequence;
        sample.time_us = std::uint64_t{1000} * sample_sequence;
        sample.axes = 1;
        sample.counts[0] = -12345;
        return encoded(sample);
    }

    std::unique_ptr<PtyDevice> device_;
    std::unique_ptr<SerialLink> link_;
};

TEST_F(SerialLinkTest, HandshakeFramesRoundTrip) {
    send(proto::Hello{kSession, 1, 1});
    const auto identity = receive<proto::Identity>();
    EXPECT_EQ(identity.session, kSession);
    EXPECT_EQ(identity.serial_number(), "EMU-SERIAL-1");
    EXPECT_EQ(identity.axes, 1);
    EXPECT_EQ(identity.period_us, 1000u);
    EXPECT_DOUBLE_EQ(identity.counts_per_meter, 1e5);

    send(proto::Configure{kSession, 50'000});
    EXPECT_EQ(receive<proto::ConfigureAck>().watchdog_timeout_us, 50'000u);

    send(proto::Poll{kSession});
    const auto first = receive<proto::EncoderSample>();
    EXPECT_EQ(first.session, kSession);
    EXPECT_EQ(first.sample_sequence, 0u);

    proto::ForceCommand command;
    command.session = kSession;
    command.sequence = 1;
    command.flags = proto::kCommandEnable;
    command.axes = 1;
    command.force_un[0] = 1'500'000;  // 1.5 N
    send(command);
    const auto answer = receive<proto::EncoderSample>();
    EXPECT_EQ(answer.command_sequence, 1u);
    EXPECT_EQ(answer.sample_sequence, 1u);
    EXPECT_EQ(answer.time_us, first.time_us + 1000);  // one period held (ZOH)
    EXPECT_NE(answer.status & proto::kSampleForceActive, 0u);
    device_->with_emulator([](proto::DeviceEmulator& e) {
        EXPECT_DOUBLE_EQ(e.output_force_n()[0], 1.5);
        EXPECT_EQ(e.counters().commands_applied, 1u);
        EXPECT_EQ(e.counters().dropped_requests, 0u);  // every frame arrived whole
    });

    const auto counters = link_->counters();
    EXPECT_EQ(counters.frames_sent, 4u);
    EXPECT_EQ(counters.frames_received, 4u);
    EXPECT_EQ(counters.framing_errors, 0u);
    EXPECT_EQ(counters.send_errors, 0u);
    EXPECT_EQ(counters.receive_errors, 0u);
    EXPECT_EQ(link_->describe(), "serial " + device_->port() + " at 2000000 baud");
}

TEST_F(SerialLinkTest, OpenSendsOneDelimiterFirst) {
    // docs/protocol.md 5.1 step 1: the device drops a partial frame it held before the host
    // opened the port. The emulator gets garbage, then the host's 0x00, then a hello.
    link_->close();
    device_->with_emulator([](proto::DeviceEmulator& e) {
        const Bytes garbage = bytes_of({0x05, 0x48, 0x01});  // a frame cut short
        std::array<std::byte, 64> out{};
        EXPECT_EQ(e.handle_stream(garbage, out), 0u);
    });
    link_->open();
    send(proto::Hello{kSession, 1, 1});
    EXPECT_EQ(receive<proto::Identity>().session, kSession);
    EXPECT_EQ(link_->counters().reopens, 1u);
}

struct Garbage {
    const char* name;
    Bytes bytes;
    /// What the decoder must count for it; -1: not known in advance (random bytes).
    int framing_errors;
    /// Whole COBS frames in it, which the link hands up and the CRC rejects; -1: not known.
    int junk_frames;
};

/// A frame that is whole on the line but was damaged on the way: one byte flipped.
Bytes damaged_frame() {
    proto::EncoderSample sample;
    sample.session = kSession;
    sample.axes = 1;
    Bytes frame = encoded(sample);
    frame[20] ^= std::byte{0x10};
    return stream_encoded(frame);
}

std::vector<Garbage> garbage_cases() {
    // Line noise: random bytes with a 0x00 every 16 bytes on average, so that it holds junk
    // "frames" of every length, not just one long overflow.
    Noise noise(0xC0B5);
    Bytes random = noise.bytes(600);
    for (std::byte& b : random) {
        if (noise.next() % 16 == 0) b = std::byte{0};
    }
    random.push_back(std::byte{0});  // ends on a delimiter, like noise between two frames
    Bytes overlong(300, std::byte{0x41});
    overlong.push_back(std::byte{0});
    return {
        // A lone delimiter is an empty frame: ignored, not an error.
        {"lone_delimiter", bytes_of({0x00}), 0, 0},
        {"two_delimiters", bytes_of({0x00, 0x00}), 0, 0},
        // More than 60 decoded bytes before the delimiter: dropped as an overflow.
        {"overlong_run", overlong, 1, 0},
        // A code byte that promises more data than comes before the delimiter.
        {"cut_block", bytes_of({0x20, 0x48, 0x01, 0x00}), 1, 0},
        // Valid COBS, bad CRC: the link only delimits, so it hands the frame up, and the
        // decoder (ProtocolDevice's) rejects it.
        {"bad_crc_frame", damaged_frame(), 0, 1},
        // Random bytes: every 0x00 in them ends a junk frame, which the link hands up or the
        // decoder drops (a framing error).
        {"random", random, -1, -1},
    };
}

TEST_F(SerialLinkTest, ResynchronisesAfterGarbage) {
    handshake();
    std::uint32_t sequence = 10;
    for (const Garbage& garbage : garbage_cases()) {
        SCOPED_TRACE(garbage.name);
        const auto before = link_->counters();
        const Bytes good = sample_frame(++sequence);
        Bytes line = garbage.bytes;
        const Bytes encoded_good = stream_encoded(good);
        line.insert(line.end(), encoded_good.begin(), encoded_good.end());
        device_->write_raw(line);

        // Frames until the good one: every junk frame before it must fail to decode.
        std::array<std::byte, proto::kMaxFrameSize> frame{};
        std::size_t size = 0;
        int junk = 0;
        for (;;) {
            ASSERT_EQ(link_->receive(frame, size, now_ns() + kGenerousNs), LinkResult::ok);
            const Bytes got(frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(size));
            if (got == good) break;
            proto::Message message;
            EXPECT_NE(proto::decode(got, message), proto::Error::none) << hex(got);
            ++junk;
            ASSERT_LT(junk, 200);
        }
        const auto errors =
            static_cast<int>(link_->counters().framing_errors - before.framing_errors);
        if (garbage.framing_errors >= 0) {
            EXPECT_EQ(errors, garbage.framing_errors);
            EXPECT_EQ(junk, garbage.junk_frames);
        } else {
            EXPECT_GT(junk + errors, 0);  // the noise was seen and dropped, one way or the other
            std::cout << "[serial] 601 bytes of noise: " << junk << " junk frames (bad CRC), "
                      << errors << " framing errors, then the good frame\n";
        }
    }
    // And the session goes on: the link is in step with the device.
    send(proto::Poll{kSession});
    EXPECT_EQ(receive<proto::EncoderSample>().session, kSession);
}

TEST_F(SerialLinkTest, GarbageWithoutDelimiterCostsTheFrameItRunsInto) {
    // docs/protocol.md 6.3: after garbage with no 0x00 in it, the receiver is in step again
    // at the next delimiter: the frame the garbage ran into is lost, the one after it is not.
    handshake();
    Bytes line = bytes_of({0x13, 0x37, 0x42, 0x99});
    const Bytes first = sample_frame(21);
    const Bytes second = sample_frame(22);
    for (const Bytes& frame : {first, second}) {
        const Bytes encoded_frame = stream_encoded(frame);
        line.insert(line.end(), encoded_frame.begin(), encoded_frame.end());
    }
    device_->write_raw(line);
    std::array<std::byte, proto::kMaxFrameSize> frame{};
    std::size_t size = 0;
    Bytes got;
    do {
        ASSERT_EQ(link_->receive(frame, size, now_ns() + kGenerousNs), LinkResult::ok);
        got.assign(frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(size));
        EXPECT_NE(got, first);  // merged with the garbage: never whole
    } while (got != second);
}

TEST_F(SerialLinkTest, KeepsAPartialFrameAcrossCalls) {
    handshake();
    const Bytes good = sample_frame(7);
    const Bytes line = stream_encoded(good);
    const std::size_t half = line.size() / 2;
    device_->write_raw(std::span<const std::byte>(line.data(), half));

    // Half a frame is not a frame: the deadline passes (100 ms), the bytes are kept.
    std::array<std::byte, proto::kMaxFrameSize> frame{};
    std::size_t size = 0;
    EXPECT_EQ(link_->receive(frame, size, now_ns() + 100'000'000), LinkResult::timeout);

    device_->write_raw(std::span<const std::byte>(line.data() + half, line.size() - half));
    ASSERT_EQ(link_->receive(frame, size, now_ns() + kGenerousNs), LinkResult::ok);
    EXPECT_EQ(Bytes(frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(size)), good);
    EXPECT_EQ(link_->counters().framing_errors, 0u);
}

TEST_F(SerialLinkTest, AssemblesAFrameDrippingInByteByByte) {
    handshake();
    const Bytes good = sample_frame(8);
    const Bytes line = stream_encoded(good);
    std::thread drip([&] {
        for (const std::byte b : line) {
            device_->write_raw(std::span<const std::byte>(&b, 1));
            std::this_thread::sleep_for(std::chrono::microseconds(300));
        }
    });
    std::array<std::byte, proto::kMaxFrameSize> frame{};
    std::size_t size = 0;
    const LinkResult result = link_->receive(frame, size, now_ns() + kGenerousNs);
    drip.join();
    ASSERT_EQ(result, LinkResult::ok);
    EXPECT_EQ(Bytes(frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(size)), good);
}

TEST_F(SerialLinkTest, TwoFramesInOneReadAreBothDelivered) {
    handshake();
    const Bytes first = sample_frame(30);
    const Bytes second = sample_frame(31);
    Bytes line = stream_encoded(first);
    const Bytes tail = stream_encoded(second);
    line.insert(line.end(), tail.begin(), tail.end());
    device_->write_raw(line);

    std::array<std::byte, proto::kMaxFrameSize> frame{};
    std::size_t size = 0;
    ASSERT_EQ(link_->receive(frame, size, now_ns() + kGenerousNs), LinkResult::ok);
    EXPECT_EQ(Bytes(frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(size)), first);
    // The second is already here: a deadline in the past still gets it.
    ASSERT_EQ(link_->receive(frame, size, now_ns() - 1), LinkResult::ok);
    EXPECT_EQ(Bytes(frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(size)), second);
}

TEST_F(SerialLinkTest, HonoursTheDeadlineWhenTheDeviceIsSilent) {
    handshake();
    device_->set_answering(false);
    send(proto::Poll{kSession});
    std::array<std::byte, proto::kMaxFrameSize> frame{};
    std::size_t size = 0;

    constexpr std::int64_t kWaitNs = 150'000'000;
    const std::int64_t start = now_ns();
    EXPECT_EQ(link_->receive(frame, size, start + kWaitNs), LinkResult::timeout);
    const std::int64_t waited = now_ns() - start;
    EXPECT_GE(waited, kWaitNs);                // not a moment early ...
    EXPECT_LT(waited, kWaitNs + 500'000'000);  // ... nor much late (generous for a loaded VM)

    const std::int64_t past = now_ns();
    EXPECT_EQ(link_->receive(frame, size, past - 1), LinkResult::timeout);
    EXPECT_LT(now_ns() - past, 100'000'000);  // a past deadline does not wait
}

TEST_F(SerialLinkTest, HangupIsADisconnect) {
    handshake();
    device_->hang_up();  // the master closes, as when a USB adapter is pulled out
    std::array<std::byte, proto::kMaxFrameSize> frame{};
    std::size_t size = 0;
    const std::int64_t start = now_ns();
    EXPECT_EQ(link_->receive(frame, size, start + kGenerousNs), LinkResult::disconnected);
    EXPECT_LT(now_ns() - start, 1'000'000'000);  // at once, not at the deadline
    EXPECT_EQ(link_->send(encoded(proto::Poll{kSession})), LinkResult::disconnected);
    link_->close();
    EXPECT_FALSE(link_->is_open());
    EXPECT_EQ(link_->send(encoded(proto::Poll{kSession})), LinkResult::disconnected);
}

TEST_F(SerialLinkTest, ExchangesDoNotAllocate) {
    handshake();
    std::array<std::byte, proto::kMaxFrameSize> tx{};
    std::array<std::byte, proto::kMaxFrameSize> rx{};
    proto::ForceCommand command;
    command.session = kSession;
    command.flags = proto::kCommandEnable;
    command.axes = 1;
    constexpr int kExchanges = 2000;
    int answered = 0;
    {
        AllocationGuard guard;
        for (int i = 1; i <= kExchanges; ++i) {
            command.sequence = static_cast<std::uint32_t>(i);
            command.force_un[0] = (i % 2 == 0 ? 1 : -1) * 100'000;
            const proto::Encoded frame = proto::encode(command, tx);
            if (link_->send(std::span<const std::byte>(tx.data(), frame.size)) != LinkResult::ok) {
                break;
            }
            std::size_t size = 0;
            if (link_->receive(rx, size, now_ns() + kGenerousNs) != LinkResult::ok) break;
            ++answered;
        }
        EXPECT_EQ(guard.allocations(), 0u);
    }
    EXPECT_EQ(answered, kExchanges);
    device_->with_emulator([](proto::DeviceEmulator& e) {
        EXPECT_EQ(e.counters().commands_applied, static_cast<std::uint64_t>(kExchanges));
    });
}

// The device stops reading (nobody on the master side): the port's output buffer fills, and
// send() gives up after write_timeout_ns instead of blocking the tick. A frame cut short by
// that is finished off by a 0x00 in front of the next one, so that the device loses only it.
TEST(SerialLinkBackpressure, SendGivesUpAfterTheWriteTimeoutAndLosesOnlyTheCutFrame) {
    PtyPair pair;  // no emulator: the master is not read until the test drains it
    ASSERT_EQ(fcntl(pair.master(), F_SETFL, O_NONBLOCK), 0);
    SerialLink link(settings_for(pair.slave_path()));
    link.open();
    ASSERT_EQ(link.settings().write_timeout_ns, 1'000'000);

    proto::EncoderSample sample;
    sample.session = kSession;
    sample.axes = 1;
    int sent = 0;
    LinkResult result = LinkResult::ok;
    std::int64_t failed_after_ns = 0;
    while (sent < 100'000) {
        sample.sample_sequence = static_cast<std::uint32_t>(sent + 1);
        const Bytes frame = encoded(sample);
        const std::int64_t start = now_ns();
        result = link.send(frame);
        if (result != LinkResult::ok) {
            failed_after_ns = now_ns() - start;
            break;
        }
        ++sent;
    }
    ASSERT_EQ(result, LinkResult::error) << "the pty never filled up";
    EXPECT_GE(failed_after_ns, 1'000'000);    // waited for room ...
    EXPECT_LT(failed_after_ns, 500'000'000);  // ... for about the timeout, not for ever
    EXPECT_EQ(link.counters().send_errors, 1u);
    EXPECT_EQ(link.counters().frames_sent, static_cast<std::uint64_t>(sent));

    const auto drain = [&pair] {
        Bytes bytes;
        std::array<std::byte, 4096> buffer{};
        for (ssize_t n; (n = ::read(pair.master(), buffer.data(), buffer.size())) > 0;) {
            bytes.insert(bytes.end(), buffer.begin(), buffer.begin() + n);
        }
        return bytes;
    };
    Bytes line = drain();
    const std::size_t frame_bytes = proto::stream_encoded_size(encoded(sample).size());
    const bool cut = (line.size() - 1) % frame_bytes != 0;  // 1: the delimiter of open()
    sample.sample_sequence = 999'999;
    const Bytes last = encoded(sample);
    ASSERT_EQ(link.send(last), LinkResult::ok);
    const Bytes tail = drain();
    line.insert(line.end(), tail.begin(), tail.end());

    // What the device would decode: every frame that send() said went, and the last one.
    proto::StreamDecoder decoder;
    int good = 0;
    Bytes last_good;
    decoder.feed(line, [&](std::span<const std::byte> frame) {
        proto::EncoderSample decoded;
        if (proto::decode(frame, decoded) == proto::Error::none) {
            ++good;
            last_good.assign(frame.begin(), frame.end());
        }
    });
    EXPECT_EQ(good, sent + 1);
    EXPECT_EQ(last_good, last);
    std::cout << "[serial] output buffer full after " << sent << " frames (" << sent * frame_bytes
              << " bytes); the last send gave up after " << failed_after_ns / 1000 << " us"
              << (cut ? ", mid-frame" : ", between frames") << "\n";
}

}  // namespace
}  // namespace hapticd::testing
