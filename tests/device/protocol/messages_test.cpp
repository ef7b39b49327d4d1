// Every message: round trips with boundary values, the exact byte layout of section 4, every
// payload-level decode error, typed decoding, and encode/decode without allocation.
#include "hapticd/device/protocol/messages.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "alloc_guard.hpp"
#include "hapticd/device/protocol/crc32c.hpp"
#include "hapticd/device/protocol/wire.hpp"
#include "protocol_test_util.hpp"

namespace hapticd::device::protocol {
namespace {

using testing::Bytes;
using testing::encoded;

constexpr std::uint32_t kU32Max = std::numeric_limits<std::uint32_t>::max();
constexpr std::int32_t kI32Max = std::numeric_limits<std::int32_t>::max();
constexpr std::int32_t kI32Min = std::numeric_limits<std::int32_t>::min();
constexpr std::int64_t kI64Max = std::numeric_limits<std::int64_t>::max();
constexpr std::int64_t kI64Min = std::numeric_limits<std::int64_t>::min();

void fix_crc(Bytes& frame) {
    const std::size_t crc_at = frame.size() - kCrcSize;
    wire::store_u32(frame, crc_at, crc32c(std::span<const std::byte>(frame).first(crc_at)));
}

/// encode -> typed decode and variant decode -> equal; returns the frame.
template <typename M>
Bytes round_trip(const M& message, std::size_t expected_size) {
    Bytes frame = encoded(message);
    EXPECT_EQ(frame.size(), expected_size);
    M typed;
    EXPECT_EQ(decode(frame, typed), Error::none);
    EXPECT_TRUE(typed == message);
    Message any;
    EXPECT_EQ(decode(frame, any), Error::none);
    EXPECT_TRUE(std::holds_alternative<M>(any));
    if (std::holds_alternative<M>(any)) {
        EXPECT_TRUE(std::get<M>(any) == message);
    }
    EXPECT_EQ(session_of(any), message.session);
    // And the variant encoder gives the same bytes.
    std::array<std::byte, kMaxFrameSize> again{};
    const Encoded e = encode(Message{message}, again);
    EXPECT_TRUE(e.ok());
    EXPECT_EQ(Bytes(again.begin(), again.begin() + static_cast<std::ptrdiff_t>(e.size)), frame);
    return frame;
}

Identity an_identity() {
    Identity m;
    m.session = 0xDEADBEEF;
    m.axes = 3;
    m.force_limit_un = 20'000'000;
    m.counts_per_meter = 1e5;
    m.period_us = 1000;
    m.watchdog_timeout_us = 20'000;
    m.firmware_version = 0x01020304;
    EXPECT_TRUE(m.set_serial_number("SN-1"));
    return m;
}

ForceCommand a_command(int axes) {
    ForceCommand m;
    m.session = 1;
    m.sequence = 5;
    m.flags = kCommandEnable;
    m.axes = static_cast<std::uint8_t>(axes);
    for (int i = 0; i < axes; ++i) m.force_un[i] = 1000 * (i + 1);
    return m;
}

EncoderSample a_sample(int axes) {
    EncoderSample m;
    m.session = 1;
    m.command_sequence = 5;
    m.sample_sequence = 6;
    m.time_us = 123456;
    m.status = kSampleForceActive;
    m.axes = static_cast<std::uint8_t>(axes);
    for (int i = 0; i < axes; ++i) m.counts[i] = -100L * (i + 1);
    return m;
}

// ---- round trips ----

TEST(ProtocolMessages, HelloRoundTrip) {
    Hello m;
    for (const std::uint32_t session : {1u, 0x80000000u, kU32Max}) {
        m.session = session;
        m.min_version = 1;
        m.max_version = 255;
        const Bytes frame = round_trip(m, 16);
        EXPECT_EQ(frame[8], std::byte{1});
        EXPECT_EQ(frame[9], std::byte{255});
    }
}

TEST(ProtocolMessages, IdentityRoundTripAndLayout) {
    Identity m = an_identity();
    const Bytes frame = round_trip(m, 56);
    EXPECT_EQ(wire::load_u8(frame, 8), 3);
    EXPECT_EQ(wire::load_i32(frame, 12), 20'000'000);
    EXPECT_EQ(wire::load_f64(frame, 16), 1e5);
    EXPECT_EQ(wire::load_u32(frame, 24), 1000u);
    EXPECT_EQ(wire::load_u32(frame, 28), 20'000u);
    EXPECT_EQ(wire::load_u32(frame, 32), 0x01020304u);
    EXPECT_EQ(frame[36], std::byte{'S'});
    EXPECT_EQ(frame[40], std::byte{0});

    // Boundaries: 1 axis, the smallest and largest positive values, a 16-character serial.
    m.axes = 1;
    m.force_limit_un = kI32Max;
    m.counts_per_meter = std::numeric_limits<double>::denorm_min();
    m.period_us = kU32Max;
    m.watchdog_timeout_us = 1;
    m.firmware_version = kU32Max;
    ASSERT_TRUE(m.set_serial_number("0123456789ABCDEF"));
    round_trip(m, 56);
    m.force_limit_un = 1;
    m.counts_per_meter = std::numeric_limits<double>::max();
    ASSERT_TRUE(m.set_serial_number(" ~"));
    round_trip(m, 56);
    EXPECT_EQ(m.serial_number(), " ~");
}

TEST(ProtocolMessages, Version3IdentitySaysWhetherTheDevicePacesTheLoop) {
    Identity m = an_identity();
    m.version = kProtocolVersion3;
    m.flags = kIdentityPaced;
    const Bytes frame = round_trip(m, 56);
    EXPECT_EQ(wire::load_u8(frame, 9), 0x01);
    Identity decoded;
    ASSERT_EQ(decode(frame, decoded), Error::none);
    EXPECT_TRUE(decoded.paced());
    // Bits the version does not define, and any flag before version 3, are refused by the
    // encoder and the decoder alike, naming the field.
    m.flags = 0x02;
    Bytes out(kMaxFrameSize);
    EXPECT_EQ(encode(m, out).error, Error::bad_field);
    EXPECT_EQ(out_of_range_field(m), "flags = 2: allowed bit 0 (paced) only");
    m.version = kProtocolVersion2;
    m.flags = kIdentityPaced;
    EXPECT_EQ(encode(m, out).error, Error::bad_field);
    EXPECT_EQ(out_of_range_field(m), "flags = 1: allowed 0 before version 3");
    Bytes v2 = frame;
    wire::store_u8(v2, 1, kProtocolVersion2);
    wire::store_u32(v2, 52, crc32c(std::span<const std::byte>(v2).first(52)));
    EXPECT_EQ(decode(v2, decoded), Error::bad_field);
}

TEST(ProtocolMessages, SerialNumberRules) {
    Identity m;
    EXPECT_FALSE(m.set_serial_number(""));
    EXPECT_FALSE(m.set_serial_number("0123456789ABCDEFG"));  // 17
    EXPECT_FALSE(m.set_serial_number("tab\there"));
    EXPECT_FALSE(m.set_serial_number("\x7f"));
    EXPECT_TRUE(m.set_serial_number("A"));
    EXPECT_EQ(m.serial_number(), "A");
}

TEST(ProtocolMessages, ConfigureAndAckRoundTrip) {
    for (const std::uint32_t timeout : {1u, 20'000u, kU32Max}) {
        Configure c;
        c.session = 3;
        c.watchdog_timeout_us = timeout;
        const Bytes frame = round_trip(c, 16);
        EXPECT_EQ(wire::load_u32(frame, 8), timeout);
        ConfigureAck a;
        a.session = 3;
        a.watchdog_timeout_us = timeout;
        EXPECT_EQ(round_trip(a, 16)[2], std::byte{0x82});
    }
}

TEST(ProtocolMessages, CommandRoundTripEveryAxisCount) {
    for (int axes = 1; axes <= 3; ++axes) {
        ForceCommand m = a_command(axes);
        m.sequence = kU32Max;
        m.flags = kCommandEnable | kCommandClearFaults;
        for (int i = 0; i < axes; ++i) m.force_un[i] = i % 2 == 0 ? kI32Min : kI32Max;
        const Bytes frame = round_trip(m, 8 + command_payload_size(axes) + 4);
        EXPECT_EQ(wire::load_u32(frame, 8), kU32Max);
        EXPECT_EQ(wire::load_u8(frame, 12), 3);
        EXPECT_EQ(wire::load_u8(frame, 13), axes);
        EXPECT_EQ(wire::load_i32(frame, 16), kI32Min);
        m.flags = 0;
        m.force_un.fill(0);
        m.sequence = 0;
        round_trip(m, 8 + command_payload_size(axes) + 4);
    }
    EXPECT_EQ(encoded(a_command(3)).size(), 32u);
}

TEST(ProtocolMessages, SampleRoundTripEveryAxisCount) {
    for (int axes = 1; axes <= 3; ++axes) {
        EncoderSample m = a_sample(axes);
        m.command_sequence = kU32Max;
        m.sample_sequence = kU32Max;
        m.time_us = std::numeric_limits<std::uint64_t>::max();
        m.status = kSampleStatusMask;
        m.faults = kDeviceFaultAllowedMask;
        for (int i = 0; i < axes; ++i) m.counts[i] = i % 2 == 0 ? kI64Min : kI64Max;
        const Bytes frame = round_trip(m, 8 + sample_payload_size(axes) + 4);
        EXPECT_EQ(wire::load_u64(frame, 16), std::numeric_limits<std::uint64_t>::max());
        EXPECT_EQ(wire::load_u16(frame, 24), kSampleStatusMask);
        EXPECT_EQ(wire::load_u16(frame, 26), kDeviceFaultAllowedMask);
        EXPECT_EQ(wire::load_u8(frame, 28), axes);
        EXPECT_EQ(wire::load_i64(frame, 32), kI64Min);
        m = a_sample(axes);
        m.time_us = 0;
        m.status = 0;
        round_trip(m, 8 + sample_payload_size(axes) + 4);
    }
    EXPECT_EQ(encoded(a_sample(3)).size(), 60u);  // the largest frame
}

TEST(ProtocolMessages, Version2SampleNamesTheCommandInEffect) {
    for (int axes = 1; axes <= 3; ++axes) {
        EncoderSample m = a_sample(axes);
        m.version = kProtocolVersion2;
        m.applied_lag = 1;
        m.applied_age_us = 500;
        Bytes frame = round_trip(m, 8 + sample_payload_size(axes) + 4);
        EXPECT_EQ(frame[1], std::byte{2});  // the header says version 2
        EXPECT_EQ(wire::load_u8(frame, 29), 1);
        EXPECT_EQ(wire::load_u16(frame, 30), 500u);
        EXPECT_EQ(m.applied_sequence(), 4u);  // command 5 answered, command 4 in effect
        // Boundaries: the largest lag and age, an age equal to the clock, nothing named.
        m.applied_lag = kMaxAppliedLag;
        m.applied_age_us = kAppliedAgeUnknown - 1;
        m.time_us = kAppliedAgeUnknown - 1;
        frame = round_trip(m, 8 + sample_payload_size(axes) + 4);
        EXPECT_EQ(wire::load_u8(frame, 29), 0xFE);
        m.applied_age_us = kAppliedAgeUnknown;  // named, but too long ago to say
        round_trip(m, 8 + sample_payload_size(axes) + 4);
        m.applied_lag = kAppliedLagNone;
        frame = round_trip(m, 8 + sample_payload_size(axes) + 4);
        EXPECT_EQ(wire::load_u8(frame, 29), 0xFF);
        EXPECT_EQ(wire::load_u16(frame, 30), 0xFFFFu);
        EXPECT_FALSE(m.names_applied());
    }
    // The applied command wraps with the sequences.
    EncoderSample m = a_sample(1);
    m.version = kProtocolVersion2;
    m.command_sequence = 2;
    m.applied_lag = 3;
    m.applied_age_us = 0;
    EXPECT_EQ(m.applied_sequence(), 0xFFFFFFFFu);
    round_trip(m, 44);
    // Version 1 has no such fields: its struct says "nothing", its bytes are zero.
    EncoderSample v1 = a_sample(1);
    const Bytes frame = round_trip(v1, 44);
    EXPECT_EQ(frame[1], std::byte{1});
    EXPECT_EQ(wire::load_u8(frame, 29), 0);
    EXPECT_EQ(wire::load_u16(frame, 30), 0u);
    EncoderSample decoded;
    ASSERT_EQ(decode(frame, decoded), Error::none);
    EXPECT_EQ(decoded.applied_lag, kAppliedLagNone);
    EXPECT_EQ(decoded.applied_age_us, kAppliedAgeUnknown);
}

TEST(ProtocolMessages, EveryVersionedMessageRoundTripsInVersion2) {
    // The layouts do not change; the header carries the session's version.
    Identity identity = an_identity();
    identity.version = kProtocolVersion2;
    EXPECT_EQ(round_trip(identity, 56)[1], std::byte{2});
    Configure configure;
    configure.session = 3;
    configure.version = kProtocolVersion2;
    EXPECT_EQ(round_trip(configure, 16)[1], std::byte{2});
    ConfigureAck ack;
    ack.session = 3;
    ack.version = kProtocolVersion2;
    EXPECT_EQ(round_trip(ack, 16)[1], std::byte{2});
    ForceCommand command = a_command(3);
    command.version = kProtocolVersion2;
    EXPECT_EQ(round_trip(command, 32)[1], std::byte{2});
    Poll poll;
    poll.version = kProtocolVersion2;
    EXPECT_EQ(round_trip(poll, 12)[1], std::byte{2});
    Bye bye;
    bye.version = kProtocolVersion2;
    EXPECT_EQ(round_trip(bye, 12)[1], std::byte{2});
    ByeAck bye_ack;
    bye_ack.version = kProtocolVersion2;
    EXPECT_EQ(round_trip(bye_ack, 12)[1], std::byte{2});
    // A version-2 command frame is the version-1 frame but for the version byte (and CRC).
    const Bytes v2 = encoded(command);
    command.version = kProtocolVersion1;
    const Bytes v1 = encoded(command);
    ASSERT_EQ(v1.size(), v2.size());
    for (std::size_t i = 0; i + kCrcSize < v1.size(); ++i) {
        if (i != kOffsetVersion) {
            EXPECT_EQ(v1[i], v2[i]) << i;
        }
    }
}

TEST(ProtocolMessages, EmptyMessagesRoundTrip) {
    Poll p;
    p.session = 77;
    EXPECT_EQ(round_trip(p, 12)[2], std::byte{0x04});
    Bye b;
    b.session = 77;
    EXPECT_EQ(round_trip(b, 12)[2], std::byte{0x05});
    ByeAck a;
    a.session = 77;
    EXPECT_EQ(round_trip(a, 12)[2], std::byte{0x85});
}

TEST(ProtocolMessages, ErrorRoundTripIncludingFutureCodes) {
    ErrorReport m;
    m.session = 0;  // an error may answer a frame that carried no session
    m.code = ErrorCode::unsupported_version;
    m.request_type = 0x01;
    m.detail = 0x0302;
    const Bytes frame = round_trip(m, 20);
    EXPECT_EQ(frame[1], std::byte{1});  // frozen version
    EXPECT_EQ(frame[8], std::byte{6});
    EXPECT_EQ(frame[9], std::byte{0x01});
    EXPECT_EQ(wire::load_u32(frame, 12), 0x0302u);
    m.code = static_cast<ErrorCode>(200);  // a newer device's code passes through
    m.request_type = 0xEE;
    m.detail = kU32Max;
    round_trip(m, 20);
}

// ---- encoder refusals ----

TEST(ProtocolMessages, EncoderRefusesWhatTheDecoderWouldRefuse) {
    std::array<std::byte, kMaxFrameSize> out{};
    Hello hello;
    EXPECT_EQ(encode(hello, out).error, Error::bad_field);  // session 0
    hello.session = 1;
    hello.min_version = 2;
    hello.max_version = 1;
    EXPECT_EQ(encode(hello, out).error, Error::bad_field);
    hello.min_version = 0;
    hello.max_version = 0;
    EXPECT_EQ(encode(hello, out).error, Error::bad_field);

    Identity identity = an_identity();
    identity.axes = 4;
    EXPECT_EQ(encode(identity, out).error, Error::bad_field);
    identity = an_identity();
    identity.counts_per_meter = std::nan("");
    EXPECT_EQ(encode(identity, out).error, Error::bad_field);
    identity.counts_per_meter = -1.0;
    EXPECT_EQ(encode(identity, out).error, Error::bad_field);
    identity.counts_per_meter = std::numeric_limits<double>::infinity();
    EXPECT_EQ(encode(identity, out).error, Error::bad_field);
    identity = an_identity();
    identity.force_limit_un = 0;
    EXPECT_EQ(encode(identity, out).error, Error::bad_field);
    identity = an_identity();
    identity.serial.fill('\0');
    EXPECT_EQ(encode(identity, out).error, Error::bad_field);
    identity = an_identity();
    identity.serial[5] = 'x';  // text after the NUL padding
    EXPECT_EQ(encode(identity, out).error, Error::bad_field);

    ForceCommand command = a_command(1);
    command.force_un[2] = 1;  // an unused axis must be zero
    EXPECT_EQ(encode(command, out).error, Error::bad_field);
    command = a_command(1);
    command.flags = 0x04;
    EXPECT_EQ(encode(command, out).error, Error::bad_field);
    command = a_command(1);
    command.axes = 0;
    EXPECT_EQ(encode(command, out).error, Error::bad_field);

    EncoderSample sample = a_sample(2);
    sample.counts[2] = 1;
    EXPECT_EQ(encode(sample, out).error, Error::bad_field);
    sample = a_sample(2);
    sample.status = 0x0040;
    EXPECT_EQ(encode(sample, out).error, Error::bad_field);
    sample = a_sample(2);
    sample.faults = 0x0100;  // reserved
    EXPECT_EQ(encode(sample, out).error, Error::bad_field);

    // Version 1 cannot name an applied command; version 2 names none without an age, and
    // no command took effect before the device's clock started.
    sample = a_sample(2);
    sample.applied_lag = 0;
    EXPECT_EQ(encode(sample, out).error, Error::bad_field);
    sample = a_sample(2);
    sample.applied_age_us = 0;
    EXPECT_EQ(encode(sample, out).error, Error::bad_field);
    sample = a_sample(2);
    sample.version = kProtocolVersion2;
    sample.applied_age_us = 10;  // lag: none
    EXPECT_EQ(encode(sample, out).error, Error::bad_field);
    sample.applied_lag = 0;
    sample.time_us = 9;
    EXPECT_EQ(encode(sample, out).error, Error::bad_field);
    sample.time_us = 10;
    EXPECT_EQ(encode(sample, out).error, Error::none);
    // A version this codec does not speak.
    for (const std::uint8_t version : {0, 4, 255}) {
        sample.version = version;
        EXPECT_EQ(encode(sample, out).error, Error::bad_version) << int{version};
        ForceCommand c = a_command(1);
        c.version = version;
        EXPECT_EQ(encode(c, out).error, Error::bad_version) << int{version};
    }

    Configure configure;
    configure.watchdog_timeout_us = 0;
    EXPECT_EQ(encode(configure, out).error, Error::bad_field);
    ErrorReport report;
    report.code = static_cast<ErrorCode>(0);
    EXPECT_EQ(encode(report, out).error, Error::bad_field);
}

TEST(ProtocolMessages, EncoderNeedsRoomForTheWholeFrame) {
    std::array<std::byte, kMaxFrameSize> out{};
    const EncoderSample sample = a_sample(3);
    EXPECT_EQ(encode(sample, std::span<std::byte>(out).first(59)).error, Error::no_space);
    EXPECT_EQ(encode(sample, std::span<std::byte>(out).first(59)).size, 0u);
    EXPECT_EQ(encode(sample, out).size, 60u);
    Poll poll;
    EXPECT_EQ(encode(poll, std::span<std::byte>(out).first(11)).error, Error::no_space);
}

// ---- decoder errors in the payload ----

/// Edits a frame's byte and fixes the CRC, so that the payload check is what fails.
Bytes edited(Bytes frame, std::size_t offset, int value) {
    frame[offset] = static_cast<std::byte>(value);
    fix_crc(frame);
    return frame;
}

/// Changes the payload size of a frame (re-framing it), keeping the type.
Bytes resized(const Bytes& frame, std::size_t payload_size) {
    Bytes out(frame.begin(), frame.begin() + 8);
    for (std::size_t i = 0; i < payload_size; ++i) {
        out.push_back(8 + i < frame.size() - 4 ? frame[8 + i] : std::byte{0});
    }
    out[3] = static_cast<std::byte>(payload_size);
    out.resize(out.size() + 4);
    fix_crc(out);
    return out;
}

TEST(ProtocolMessages, BadPayloadSizeForEveryType) {
    Hello hello;
    hello.session = 1;
    Configure configure;
    configure.session = 1;
    ConfigureAck ack;
    ack.session = 1;
    ack.watchdog_timeout_us = 5;
    ErrorReport report;
    Poll poll;
    Bye bye;
    ByeAck bye_ack;
    struct Case {
        Bytes frame;
        std::vector<std::size_t> wrong_sizes;
    };
    const std::vector<Case> cases = {
        {encoded(hello), {0, 3, 5, 48}},
        {encoded(an_identity()), {0, 43, 45}},
        {encoded(configure), {0, 3, 8}},
        {encoded(ack), {0, 5}},
        {encoded(a_command(1)), {0, 8, 11, 13, 24}},
        {encoded(a_sample(1)), {0, 24, 31, 33, 39, 41, 47}},
        {encoded(poll), {1, 4}},
        {encoded(bye), {1}},
        {encoded(bye_ack), {48}},
        {encoded(report), {0, 7, 9}},
    };
    for (const Case& c : cases) {
        for (const std::size_t size : c.wrong_sizes) {
            Message m;
            EXPECT_EQ(decode(resized(c.frame, size), m), Error::bad_payload_size)
                << "type " << static_cast<int>(c.frame[2]) << " size " << size;
        }
    }
}

TEST(ProtocolMessages, BadFieldForEveryFieldRule) {
    Hello hello;
    hello.session = 1;
    const Bytes hello_frame = encoded(hello);
    Message m;
    EXPECT_EQ(decode(edited(hello_frame, 8, 0), m), Error::bad_field);   // min_version 0
    EXPECT_EQ(decode(edited(hello_frame, 8, 2), m), Error::bad_field);   // min > max
    EXPECT_EQ(decode(edited(hello_frame, 10, 1), m), Error::bad_field);  // reserved
    Bytes zero_session = hello_frame;
    wire::store_u32(zero_session, 4, 0);
    fix_crc(zero_session);
    EXPECT_EQ(decode(zero_session, m), Error::bad_field);

    const Bytes identity = encoded(an_identity());
    EXPECT_EQ(decode(edited(identity, 8, 0), m), Error::bad_field);      // axes 0
    EXPECT_EQ(decode(edited(identity, 8, 4), m), Error::bad_field);      // axes 4
    EXPECT_EQ(decode(edited(identity, 9, 1), m), Error::bad_field);      // reserved
    EXPECT_EQ(decode(edited(identity, 11, 1), m), Error::bad_field);     // reserved
    EXPECT_EQ(decode(edited(identity, 15, 0x80), m), Error::bad_field);  // force limit < 0
    EXPECT_EQ(decode(edited(identity, 23, 0xFF), m), Error::bad_field);  // cpm NaN/negative
    EXPECT_EQ(decode(edited(identity, 36, 0), m), Error::bad_field);     // empty serial
    EXPECT_EQ(decode(edited(identity, 37, 0x01), m), Error::bad_field);  // control character
    EXPECT_EQ(decode(edited(identity, 51, 'x'), m), Error::bad_field);   // text after NUL
    Bytes zero_period = identity;
    wire::store_u32(zero_period, 24, 0);
    fix_crc(zero_period);
    EXPECT_EQ(decode(zero_period, m), Error::bad_field);
    Bytes zero_watchdog = identity;
    wire::store_u32(zero_watchdog, 28, 0);
    fix_crc(zero_watchdog);
    EXPECT_EQ(decode(zero_watchdog, m), Error::bad_field);

    Configure configure;
    configure.session = 1;
    Bytes zero_timeout = encoded(configure);
    wire::store_u32(zero_timeout, 8, 0);
    fix_crc(zero_timeout);
    EXPECT_EQ(decode(zero_timeout, m), Error::bad_field);

    const Bytes command = encoded(a_command(2));                        // payload 16
    EXPECT_EQ(decode(edited(command, 12, 0x04), m), Error::bad_field);  // unknown flag
    EXPECT_EQ(decode(edited(command, 13, 3), m), Error::bad_field);     // axes vs payload size
    EXPECT_EQ(decode(edited(command, 13, 0), m), Error::bad_field);
    EXPECT_EQ(decode(edited(command, 13, 9), m), Error::bad_field);
    EXPECT_EQ(decode(edited(command, 15, 1), m), Error::bad_field);  // reserved

    const Bytes sample = encoded(a_sample(2));                         // payload 40
    EXPECT_EQ(decode(edited(sample, 24, 0x40), m), Error::bad_field);  // reserved status bit
    EXPECT_EQ(decode(edited(sample, 27, 0x01), m), Error::bad_field);  // reserved fault bit 8
    EXPECT_EQ(decode(edited(sample, 27, 0x10), m), Error::none);       // vendor bit 12: fine
    EXPECT_EQ(decode(edited(sample, 28, 1), m), Error::bad_field);     // axes vs payload size
    EXPECT_EQ(decode(edited(sample, 29, 1), m), Error::bad_field);     // reserved
    EXPECT_EQ(decode(edited(sample, 31, 1), m), Error::bad_field);     // reserved

    // Version 2's applied_lag and applied_age_us (frame 29, 30..31).
    EncoderSample v2 = a_sample(2);
    v2.version = kProtocolVersion2;
    v2.applied_lag = 0;
    v2.applied_age_us = 500;
    const Bytes named = encoded(v2);
    EXPECT_EQ(decode(edited(named, 29, 0xFE), m), Error::none);
    EXPECT_EQ(decode(edited(named, 29, 0xFF), m), Error::bad_field);  // none, with an age
    Bytes old_age = named;  // took effect before the clock started: age > time_us
    wire::store_u16(old_age, 30, 0xFFFE);
    wire::store_u64(old_age, 16, 0xFFFD);
    fix_crc(old_age);
    EXPECT_EQ(decode(old_age, m), Error::bad_field);
    wire::store_u64(old_age, 16, 0xFFFE);
    fix_crc(old_age);
    EXPECT_EQ(decode(old_age, m), Error::none);
    Bytes unknown_age = named;  // 0xFFFF: unknown, whatever the clock says
    wire::store_u16(unknown_age, 30, 0xFFFF);
    wire::store_u64(unknown_age, 16, 3);
    fix_crc(unknown_age);
    EXPECT_EQ(decode(unknown_age, m), Error::none);

    ErrorReport report;
    report.session = 1;
    const Bytes error = encoded(report);
    EXPECT_EQ(decode(edited(error, 8, 0), m), Error::bad_field);   // code 0
    EXPECT_EQ(decode(edited(error, 11, 1), m), Error::bad_field);  // reserved
}

// Each identity field out of range is named with its value and range (the host's message),
// and one in range names nothing.
TEST(ProtocolMessages, AnIdentityOutOfRangeNamesItsFirstBadField) {
    EXPECT_EQ(out_of_range_field(an_identity()), "");
    const auto named = [](auto edit) {
        Identity m = an_identity();
        edit(m);
        std::array<std::byte, kMaxFrameSize> frame{};
        EXPECT_EQ(encode(m, frame).error, Error::bad_field);  // the codec refuses it too
        return out_of_range_field(m);
    };
    EXPECT_EQ(named([](Identity& m) { m.axes = 4; }), "axes = 4: allowed 1..3");
    EXPECT_EQ(named([](Identity& m) { m.force_limit_un = -5; }),
              "force_limit_un = -5: allowed > 0 (micronewtons)");
    EXPECT_EQ(named([](Identity& m) { m.counts_per_meter = std::nan(""); }),
              "counts_per_meter = nan: allowed finite and > 0 (encoder counts per metre)");
    EXPECT_EQ(named([](Identity& m) { m.counts_per_meter = -2.5; }),
              "counts_per_meter = -2.5: allowed finite and > 0 (encoder counts per metre)");
    EXPECT_EQ(named([](Identity& m) { m.period_us = 0; }),
              "period_us = 0: allowed > 0 (the device's servo period, us)");
    EXPECT_EQ(named([](Identity& m) { m.watchdog_timeout_us = 0; }),
              "watchdog_timeout_us = 0: allowed > 0 (us)");
    EXPECT_EQ(named([](Identity& m) { m.serial[0] = '\0'; }),
              "serial: allowed 1 to 16 printable ASCII characters, then NUL padding");
    // The first in the frame's order is named.
    EXPECT_EQ(named([](Identity& m) {
                  m.axes = 0;
                  m.period_us = 0;
              }),
              "axes = 0: allowed 1..3");
}

TEST(ProtocolMessages, TypedDecodeRejectsOtherTypes) {
    const Bytes sample = encoded(a_sample(1));
    ForceCommand command;
    EXPECT_EQ(decode(sample, command), Error::wrong_type);
    Identity identity;
    EXPECT_EQ(decode(sample, identity), Error::wrong_type);
    EncoderSample ok;
    EXPECT_EQ(decode(sample, ok), Error::none);
    // Frame errors come before the type check.
    EXPECT_EQ(decode(std::span<const std::byte>(sample).first(20), command), Error::truncated);
}

TEST(ProtocolMessages, TypeOfEveryAlternative) {
    EXPECT_EQ(type_of(Message{Hello{}}), MessageType::hello);
    EXPECT_EQ(type_of(Message{Identity{}}), MessageType::identity);
    EXPECT_EQ(type_of(Message{Configure{}}), MessageType::configure);
    EXPECT_EQ(type_of(Message{ConfigureAck{}}), MessageType::configure_ack);
    EXPECT_EQ(type_of(Message{ForceCommand{}}), MessageType::command);
    EXPECT_EQ(type_of(Message{EncoderSample{}}), MessageType::sample);
    EXPECT_EQ(type_of(Message{Poll{}}), MessageType::poll);
    EXPECT_EQ(type_of(Message{Bye{}}), MessageType::bye);
    EXPECT_EQ(type_of(Message{ByeAck{}}), MessageType::bye_ack);
    EXPECT_EQ(type_of(Message{ErrorReport{}}), MessageType::error);
}

TEST(ProtocolMessages, EncodeAndDecodeAllocateNothing) {
    const Identity identity = an_identity();
    const ForceCommand command = a_command(3);
    const EncoderSample sample = a_sample(3);
    std::array<std::byte, kMaxFrameSize> buffer{};
    hapticd::testing::AllocationGuard guard;
    for (int i = 0; i < 1000; ++i) {
        Encoded e = encode(command, buffer);
        ForceCommand c;
        EXPECT_EQ(decode(std::span<const std::byte>(buffer).first(e.size), c), Error::none);
        e = encode(sample, buffer);
        EncoderSample s;
        EXPECT_EQ(decode(std::span<const std::byte>(buffer).first(e.size), s), Error::none);
        Message any;
        EXPECT_EQ(decode(std::span<const std::byte>(buffer).first(e.size), any), Error::none);
        e = encode(identity, buffer);
        EXPECT_EQ(decode(std::span<const std::byte>(buffer).first(e.size), any), Error::none);
        EXPECT_EQ(decode(std::span<const std::byte>(buffer).first(e.size - 1), any),
                  Error::truncated);
        e = encode(Message{command}, buffer);
        EXPECT_TRUE(e.ok());
    }
    EXPECT_EQ(guard.allocations(), 0u);
}

}  // namespace
}  // namespace hapticd::device::protocol
