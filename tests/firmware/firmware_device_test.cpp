// The firmware's protocol core (firmware/core/hfw_device.c) driven by frames from the host's
// own encoder and judged by the host's own decoder (hapticd::protocol): docs/protocol.md
// sections 3.4, 4 and 5, item by item, as its section 9 checklist lists them.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <random>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "hapticd/device/protocol/crc32c.hpp"
#include "hapticd/device/protocol/messages.hpp"
#include "hapticd/device/protocol/wire.hpp"
#include "hfw_device.h"

namespace hapticd::testing {
namespace {

namespace protocol = device::protocol;
using Frame = std::vector<std::byte>;

constexpr std::uint32_t kSession = 0x5EC7A3B1u;
constexpr std::uint64_t kStartUs = 5'000'000;
constexpr std::uint32_t kPeriodUs = 1000;

/// The motor as the core drives it: every call, in order.
struct Motor {
    std::vector<std::array<std::int32_t, 3>> calls;
    std::array<std::int32_t, 3> force_un() const { return calls.back(); }
};

/// The board the core sees: the motor and the test's clock.
struct Board {
    Motor motor;
    std::uint64_t now_us = 0;
};

void record_force(void* context, const std::int32_t force_un[HFW_MAX_AXES]) {
    static_cast<Board*>(context)->motor.calls.push_back({force_un[0], force_un[1], force_un[2]});
}

std::uint64_t board_clock(void* context) { return static_cast<Board*>(context)->now_us; }

hfw_device_config make_config(std::uint8_t axes, std::uint8_t max_version = 2) {
    hfw_device_config config{};
    config.axes = axes;
    config.max_version = max_version;
    config.force_limit_un = 20'000'000;
    config.counts_per_meter_bits = std::bit_cast<std::uint64_t>(1e5);
    config.period_us = kPeriodUs;
    config.default_watchdog_timeout_us = 20'000;
    config.firmware_version = 0x00010203u;
    const std::string serial = "HD3-000042";
    std::memcpy(config.serial, serial.data(), serial.size());
    return config;
}

template <typename M>
Frame encoded(const M& message) {
    Frame frame(protocol::kMaxFrameSize);
    const protocol::Encoded e = protocol::encode(message, frame);
    EXPECT_TRUE(e.ok()) << protocol::to_string(e.error);
    frame.resize(e.size);
    return frame;
}

/// Recomputes the CRC of a frame changed by hand, so that only the change is wrong.
Frame with_crc(Frame frame) {
    const std::size_t crc_at = frame.size() - 4;
    protocol::wire::store_u32(frame, crc_at,
                              protocol::crc32c(std::span<const std::byte>(frame).first(crc_at)));
    return frame;
}

class FirmwareDevice : public ::testing::Test {
  protected:
    explicit FirmwareDevice(std::uint8_t axes = 1, std::uint8_t max_version = 2)
        : config_(make_config(axes, max_version)) {
        hfw_device_init(&device_, &config_, {record_force, board_clock, &board_});
    }

    struct Reply {
        hfw_reply kind = HFW_REPLY_NONE;
        Frame frame;
        protocol::Message message;
        protocol::Error error = protocol::Error::truncated;
    };

    /// One request at now_us; a sample is latched `latch_after_us` later with `counts`.
    Reply send(const Frame& request, std::array<std::int64_t, 3> counts = {},
               std::uint16_t sensor_status = 0, std::uint64_t latch_after_us = 3) {
        Reply reply;
        std::array<std::uint8_t, HFW_MAX_FRAME_SIZE> out{};
        std::size_t size = 0;
        board_.now_us = now_us_;  // the output is set at the arrival instant
        reply.kind =
            hfw_device_receive(&device_, reinterpret_cast<const std::uint8_t*>(request.data()),
                               request.size(), now_us_, out.data(), &size);
        if (reply.kind == HFW_REPLY_SAMPLE) {
            now_us_ += latch_after_us;
            size = hfw_device_sample(&device_, counts.data(), now_us_, sensor_status, out.data());
        }
        const auto* begin = reinterpret_cast<const std::byte*>(out.data());
        reply.frame.assign(begin, begin + size);
        if (size > 0) reply.error = protocol::decode(reply.frame, reply.message);
        return reply;
    }

    template <typename M>
    M expect(const Reply& reply) {
        EXPECT_EQ(reply.error, protocol::Error::none) << protocol::to_string(reply.error);
        const M* m = std::get_if<M>(&reply.message);
        EXPECT_NE(m, nullptr) << "reply type " << reply.message.index();
        return m != nullptr ? *m : M{};
    }

    protocol::ErrorReport expect_error(const Reply& reply, protocol::ErrorCode code) {
        const auto report = expect<protocol::ErrorReport>(reply);
        EXPECT_EQ(report.code, code) << protocol::to_string(report.code);
        return report;
    }

    protocol::Identity hello(std::uint32_t session = kSession, std::uint8_t min_version = 1,
                             std::uint8_t max_version = 2) {
        protocol::Hello h;
        h.session = session;
        h.min_version = min_version;
        h.max_version = max_version;
        h.session = session;
        return expect<protocol::Identity>(send(encoded(h)));
    }

    protocol::ForceCommand command(std::uint32_t sequence, std::int32_t force_un,
                                   std::uint8_t flags = protocol::kCommandEnable) const {
        protocol::ForceCommand c;
        c.session = kSession;
        c.version = version_;
        c.sequence = sequence;
        c.flags = flags;
        c.axes = config_.axes;
        for (int i = 0; i < config_.axes; ++i) c.force_un[i] = force_un;
        return c;
    }

    protocol::EncoderSample send_command(std::uint32_t sequence, std::int32_t force_un,
                                         std::uint8_t flags = protocol::kCommandEnable) {
        return expect<protocol::EncoderSample>(send(encoded(command(sequence, force_un, flags))));
    }

    template <typename M>
    M in_session(M m) const {
        m.session = kSession;
        m.version = version_;
        return m;
    }

    hfw_device_config config_;
    hfw_device device_{};
    Board board_;
    Motor& motor_ = board_.motor;
    std::uint64_t now_us_ = kStartUs;
    std::uint8_t version_ = 2;
};

class FirmwareDevice3Axes : public FirmwareDevice {
  protected:
    FirmwareDevice3Axes() : FirmwareDevice(3) {}
};

class FirmwareDevicePaced : public FirmwareDevice {
  protected:
    FirmwareDevicePaced() : FirmwareDevice(1, 3) {
        config_.paced = 1;
        version_ = 3;
    }
};

class FirmwareDeviceVersion1 : public FirmwareDevice {
  protected:
    FirmwareDeviceVersion1() : FirmwareDevice(1, 1) { version_ = 1; }
};

TEST_F(FirmwareDevice, StartsWithZeroForceAndNoSession) {
    ASSERT_EQ(motor_.calls.size(), 1u);
    EXPECT_EQ(motor_.force_un(), (std::array<std::int32_t, 3>{}));
    expect_error(send(encoded(command(1, 1000))), protocol::ErrorCode::no_session);
    expect_error(send(encoded(in_session(protocol::Poll{}))), protocol::ErrorCode::no_session);
    EXPECT_EQ(motor_.force_un(), (std::array<std::int32_t, 3>{}));
}

TEST_F(FirmwareDevice3Axes, IdentityAndSampleAreTheProtocolsWorkedExamplesByteForByte) {
    // docs/protocol.md section 8: the identity and the 3-axis sample, which the host's
    // encoder writes there.
    protocol::Hello h;
    h.session = kSession;
    h.min_version = 1;
    h.max_version = 2;
    const Reply identity = send(encoded(h));
    protocol::Identity expected;
    expected.session = kSession;
    expected.version = 2;
    expected.axes = 3;
    expected.force_limit_un = 20'000'000;
    expected.counts_per_meter = 1e5;
    expected.period_us = 1000;
    expected.watchdog_timeout_us = 20'000;
    expected.firmware_version = 0x00010203u;
    ASSERT_TRUE(expected.set_serial_number("HD3-000042"));
    EXPECT_EQ(identity.frame, encoded(expected));

    protocol::EncoderSample poll_answer;
    poll_answer.session = kSession;
    poll_answer.version = 2;
    poll_answer.time_us = kStartUs;
    poll_answer.axes = 3;
    poll_answer.counts = {1000, -250, 0};
    poll_answer.status = 0;
    EXPECT_EQ(send(encoded(in_session(protocol::Poll{})), {1000, -250, 0}, 0, 0).frame,
              encoded(poll_answer));

    // Command 1 arrives 1 ms later and takes effect at once; its counts are latched 1 ms
    // after it (a device that latches at its period boundary): applied_lag 0, age 1000 us.
    now_us_ = kStartUs + 1000;
    protocol::ForceCommand c = command(1, 0);
    c.force_un = {1'500'000, -250'000, 0};
    const Reply sample = send(encoded(c), {1003, -251, 0}, 0, 1000);
    protocol::EncoderSample answer;
    answer.session = kSession;
    answer.version = 2;
    answer.command_sequence = 1;
    answer.sample_sequence = 1;
    answer.time_us = kStartUs + 2000;
    answer.status = protocol::kSampleForceActive;
    answer.axes = 3;
    answer.counts = {1003, -251, 0};
    answer.applied_lag = 0;
    answer.applied_age_us = 1000;
    EXPECT_EQ(sample.frame, encoded(answer));
    EXPECT_EQ(motor_.force_un(), (std::array<std::int32_t, 3>{1'500'000, -250'000, 0}));
}

TEST_F(FirmwareDevice, NegotiatesTheHighestCommonVersion) {
    EXPECT_EQ(hello(kSession, 1, 2).version, 2);
    EXPECT_EQ(hello(kSession + 1, 1, 1).version, 1);
    EXPECT_EQ(hello(kSession + 2, 2, 5).version, 2);
    protocol::Hello too_new;
    too_new.session = kSession + 3;
    too_new.min_version = 3;
    too_new.max_version = 4;
    const auto report =
        expect_error(send(encoded(too_new)), protocol::ErrorCode::unsupported_version);
    EXPECT_EQ(report.detail, 1u | (2u << 8));
    EXPECT_EQ(report.session, kSession + 3);
    // No session now: that hello ended the old one.
    expect_error(send(encoded(command(1, 0))), protocol::ErrorCode::no_session);
}

TEST_F(FirmwareDeviceVersion1, AVersion1FirmwareAnswersInVersion1AndSaysNothingOfTheCommand) {
    EXPECT_EQ(hello().version, 1);
    const auto sample = send_command(1, 1000);
    EXPECT_EQ(sample.version, 1);
    EXPECT_FALSE(sample.names_applied());
    // A frame in version 2 is a version this firmware does not speak.
    protocol::ForceCommand v2 = command(2, 1000);
    v2.version = 2;
    const auto report = expect_error(send(encoded(v2)), protocol::ErrorCode::bad_version);
    EXPECT_EQ(report.detail, 1u | (1u << 8));
}

TEST_F(FirmwareDevicePaced, AVersion3SessionSaysTheBoardPacesTheLoop) {
    const protocol::Identity identity = hello(kSession, 1, 3);
    EXPECT_EQ(identity.version, 3);
    EXPECT_TRUE(identity.paced());
    EXPECT_EQ(hfw_device_paced(&device_), 1);
    EXPECT_EQ(send_command(1, 1000).version, 3);
    // A host that speaks only up to version 2 gets a version-2 session, which cannot say it:
    // the board then answers at once.
    const protocol::Identity older = hello(kSession + 1, 1, 2);
    EXPECT_EQ(older.version, 2);
    EXPECT_FALSE(older.paced());
    EXPECT_EQ(hfw_device_paced(&device_), 0);
    // After bye there is no session to pace.
    hello(kSession, 1, 3);
    send(encoded(in_session(protocol::Bye{})));
    EXPECT_EQ(hfw_device_paced(&device_), 0);
}

TEST_F(FirmwareDevice, CommandsAreAppliedAtOnceHeldAndClampedToTheLimit) {
    hello();
    auto sample = send_command(1, 1'500'000);
    EXPECT_EQ(motor_.force_un()[0], 1'500'000);
    EXPECT_EQ(sample.command_sequence, 1u);
    EXPECT_EQ(sample.sample_sequence, 0u);
    EXPECT_EQ(sample.status, protocol::kSampleForceActive);
    now_us_ += kPeriodUs;
    sample = send_command(2, -25'000'000);
    EXPECT_EQ(motor_.force_un()[0], -20'000'000);
    EXPECT_EQ(sample.status, protocol::kSampleForceActive | protocol::kSampleForceClamped);
    EXPECT_EQ(sample.sample_sequence, 1u);
    now_us_ += kPeriodUs;
    sample = send_command(3, 7, 0);  // enable clear: zero force
    EXPECT_EQ(motor_.force_un()[0], 0);
    EXPECT_EQ(sample.status, 0u);
    // The most negative force clamps without overflow.
    now_us_ += kPeriodUs;
    sample = send_command(4, INT32_MIN);
    EXPECT_EQ(motor_.force_un()[0], -20'000'000);
}

TEST_F(FirmwareDevice, SaysWhenACommandCameLateOrAfterAGap) {
    constexpr std::uint16_t kHow = protocol::kSampleCommandLate | protocol::kSampleCommandGap;
    hello();
    const std::uint64_t first_us = now_us_;
    send_command(1, 0);
    now_us_ = first_us + 1500;  // 1.5 periods after the last: not yet late
    EXPECT_EQ(send_command(2, 0).status & kHow, 0u);
    now_us_ = first_us + 1500 + 1501;
    EXPECT_EQ(send_command(3, 0).status & kHow, protocol::kSampleCommandLate);
    now_us_ = first_us + 1500 + 1501 + kPeriodUs;
    EXPECT_EQ(send_command(5, 0).status & kHow, protocol::kSampleCommandGap);
    // A poll says nothing of how a command came.
    EXPECT_EQ(
        expect<protocol::EncoderSample>(send(encoded(in_session(protocol::Poll{})))).status & kHow,
        0u);
}

TEST_F(FirmwareDevice, NamesTheCommandInEffectAndWhenItTookEffect) {
    hello();
    auto sample = expect<protocol::EncoderSample>(send(encoded(in_session(protocol::Poll{}))));
    EXPECT_EQ(sample.applied_lag, protocol::kAppliedLagNone);
    EXPECT_EQ(sample.applied_age_us, protocol::kAppliedAgeUnknown);
    const std::uint64_t arrival_us = now_us_;
    sample = expect<protocol::EncoderSample>(send(encoded(command(1, 1000)), {}, 0, 420));
    EXPECT_EQ(sample.applied_lag, 0);
    EXPECT_EQ(sample.applied_age_us, 420);
    EXPECT_EQ(sample.time_us, arrival_us + 420);
    // A poll later names the same command, and the same moment.
    now_us_ += 300;
    sample = expect<protocol::EncoderSample>(send(encoded(in_session(protocol::Poll{}))));
    EXPECT_EQ(sample.applied_lag, 0);
    EXPECT_EQ(sample.time_us - sample.applied_age_us, arrival_us);
    // 70 ms later the age no longer fits: unknown, but the command is still named.
    now_us_ += 70'000;
    sample = expect<protocol::EncoderSample>(send(encoded(in_session(protocol::Poll{}))));
    EXPECT_EQ(sample.applied_lag, 0);
    EXPECT_EQ(sample.applied_age_us, protocol::kAppliedAgeUnknown);
}

TEST_F(FirmwareDevice, ASampleTakenBeforeTheLastCommandTookEffectNamesTheOneBefore) {
    // A reading sampled for the period boundary, answered after a later command took effect
    // (a command that came between the sample and its answer): the command in effect when
    // the counts were sampled was the one before, and the sample says so.
    hello();
    const std::uint64_t first_us = now_us_;
    send_command(1, 1000);
    now_us_ = first_us + 1000;
    const std::uint64_t second_us = now_us_;
    std::array<std::uint8_t, HFW_MAX_FRAME_SIZE> out{};
    std::size_t size = 0;
    const Frame second = encoded(command(2, 2000));
    board_.now_us = second_us;
    ASSERT_EQ(hfw_device_receive(&device_, reinterpret_cast<const std::uint8_t*>(second.data()),
                                 second.size(), second_us, out.data(), &size),
              HFW_REPLY_SAMPLE);
    const std::int64_t counts[3] = {7, 0, 0};
    size = hfw_device_sample(&device_, counts, second_us - 40, 0, out.data());
    const auto* begin = reinterpret_cast<const std::byte*>(out.data());
    protocol::EncoderSample sample;
    ASSERT_EQ(protocol::decode(std::span<const std::byte>(begin, size), sample),
              protocol::Error::none);
    EXPECT_EQ(sample.command_sequence, 2u);
    EXPECT_EQ(sample.applied_lag, 1);
    EXPECT_EQ(sample.time_us - sample.applied_age_us, first_us);
    // Before the session's first command took effect, none is named.
    hello(kSession);
    send_command(1, 1000);
    size = hfw_device_sample(&device_, counts, now_us_ - 100, 0, out.data());
    ASSERT_EQ(protocol::decode(std::span<const std::byte>(begin, size), sample),
              protocol::Error::none);
    EXPECT_EQ(sample.applied_lag, protocol::kAppliedLagNone);
    EXPECT_EQ(sample.applied_age_us, protocol::kAppliedAgeUnknown);
}

TEST_F(FirmwareDevice, ASampleBuiltInTwoPartsIsTheSampleAndItsFrontCanBeRebuilt) {
    // The paced board writes the front of the next sample before its counts are sampled,
    // and writes it again if a command comes meanwhile: begin changes nothing.
    hello();
    send_command(1, 1000);
    std::array<std::uint8_t, HFW_MAX_FRAME_SIZE> parts{}, whole{};
    const std::int64_t counts[3] = {-123456789, 0, 0};
    const std::uint64_t time_us = now_us_ + 100;
    (void)hfw_device_sample_begin(&device_, time_us - 50, 0, parts.data());
    const std::uint32_t state = hfw_device_sample_begin(&device_, time_us, 0, parts.data());
    const std::size_t size = hfw_device_sample_end(&device_, state, counts, parts.data());
    EXPECT_EQ(size, 44u);
    device_.sample_sequence -= 1;  // the same sample again, whole
    device_.command_status = 0;
    EXPECT_EQ(hfw_device_sample(&device_, counts, time_us, 0, whole.data()), size);
    EXPECT_EQ(parts, whole);
    protocol::EncoderSample sample;
    ASSERT_EQ(protocol::decode(std::span<const std::byte>(
                                   reinterpret_cast<const std::byte*>(parts.data()), size),
                               sample),
              protocol::Error::none);
    EXPECT_EQ(sample.counts[0], -123456789);
    EXPECT_EQ(sample.sample_sequence, 1u);
    EXPECT_EQ(HFW_SAMPLE_COUNTS_OFFSET, 32u);
}

TEST_F(FirmwareDevice, TheWatchdogTripsAtItsTimeoutAndNotBefore) {
    hello();
    EXPECT_EQ(hfw_device_check_watchdog(&device_, now_us_ + 1'000'000), 0) << "not armed yet";
    send_command(1, 2'000'000);
    const std::uint64_t last_us = now_us_;
    EXPECT_EQ(hfw_device_check_watchdog(&device_, last_us + 20'000 - 4), 0);
    EXPECT_EQ(motor_.force_un()[0], 2'000'000);
    EXPECT_EQ(hfw_device_check_watchdog(&device_, last_us + 20'000), 1);
    EXPECT_EQ(motor_.force_un()[0], 0);
    EXPECT_EQ(device_.watchdog_trips, 1u);
    now_us_ = last_us + 25'000;
    // A late command is accepted and echoed but holds zero force.
    auto sample = send_command(2, 2'000'000);
    EXPECT_EQ(sample.faults, protocol::kDeviceFaultWatchdog);
    EXPECT_EQ(sample.command_sequence, 2u);
    EXPECT_EQ(sample.status & protocol::kSampleForceActive, 0u);
    EXPECT_EQ(motor_.force_un()[0], 0);
    // clear_faults with enable set is ignored; with enable clear it clears.
    sample = send_command(3, 2'000'000, protocol::kCommandEnable | protocol::kCommandClearFaults);
    EXPECT_EQ(sample.faults, protocol::kDeviceFaultWatchdog);
    sample = send_command(4, 0, protocol::kCommandClearFaults);
    EXPECT_EQ(sample.faults, 0u);
    EXPECT_EQ(motor_.force_un()[0], 0);
    sample = send_command(5, 2'000'000);
    EXPECT_EQ(motor_.force_un()[0], 2'000'000);
}

TEST_F(FirmwareDevice, OnlyAcceptedCommandsFeedTheWatchdog) {
    hello();
    send_command(1, 1000);
    const std::uint64_t last_us = now_us_;
    now_us_ += 10'000;
    send(encoded(in_session(protocol::Poll{})));
    protocol::ForceCommand stale = command(2, 1000);
    stale.session = 0x0BADCAFE;
    expect_error(send(encoded(stale)), protocol::ErrorCode::wrong_session);
    EXPECT_EQ(hfw_device_check_watchdog(&device_, last_us + 20'000), 1);
}

TEST_F(FirmwareDevice, ConfigureSetsTheTimeoutWithinItsRange) {
    hello();
    protocol::Configure configure = in_session(protocol::Configure{});
    configure.watchdog_timeout_us = 1999;
    auto report = expect_error(send(encoded(configure)), protocol::ErrorCode::out_of_range);
    EXPECT_EQ(report.detail, 2000u);
    configure.watchdog_timeout_us = 1'000'001;
    report = expect_error(send(encoded(configure)), protocol::ErrorCode::out_of_range);
    EXPECT_EQ(report.detail, 1'000'000u);
    configure.watchdog_timeout_us = 5000;
    EXPECT_EQ(expect<protocol::ConfigureAck>(send(encoded(configure))).watchdog_timeout_us, 5000u);
    const std::uint64_t arrival_us = now_us_;
    send_command(1, 1000);
    EXPECT_EQ(hfw_device_check_watchdog(&device_, arrival_us + 4999), 0);
    EXPECT_EQ(hfw_device_check_watchdog(&device_, arrival_us + 5000), 1);
    // A new hello restores the default and clears the watchdog fault.
    const auto identity = hello(kSession);
    EXPECT_EQ(identity.watchdog_timeout_us, 20'000u);
    EXPECT_EQ(send_command(1, 1000).faults, 0u);
    EXPECT_EQ(motor_.force_un()[0], 1000);
}

TEST_F(FirmwareDevice, ByeAndANewHelloLeaveZeroForce) {
    hello();
    send_command(1, 3'000'000);
    ASSERT_EQ(motor_.force_un()[0], 3'000'000);
    hello(kSession + 1);
    EXPECT_EQ(motor_.force_un()[0], 0);
    protocol::ForceCommand c = command(1, 3'000'000);
    c.session = kSession + 1;
    expect<protocol::EncoderSample>(send(encoded(c)));
    ASSERT_EQ(motor_.force_un()[0], 3'000'000);
    protocol::Bye bye = in_session(protocol::Bye{});
    bye.session = kSession + 1;
    const auto ack = expect<protocol::ByeAck>(send(encoded(bye)));
    EXPECT_EQ(ack.session, kSession + 1);
    EXPECT_EQ(motor_.force_un()[0], 0);
    c.sequence = 2;
    expect_error(send(encoded(c)), protocol::ErrorCode::no_session);
    EXPECT_EQ(motor_.force_un()[0], 0);
}

TEST_F(FirmwareDevice, FrameLevelErrorsAreDroppedSilentlyAndChangeNothing) {
    hello();
    send_command(1, 1000);
    const std::size_t calls = motor_.calls.size();
    const Frame good = encoded(command(2, 5000));
    Frame bad_crc = good;
    bad_crc.back() ^= std::byte{0x01};
    Frame bad_magic = good;
    bad_magic[0] = std::byte{0x49};
    Frame longer = good;
    longer.push_back(std::byte{0});
    const Frame truncated(good.begin(), good.end() - 1);
    const Frame tiny(good.begin(), good.begin() + 11);
    for (const Frame& frame : {bad_crc, with_crc(bad_magic), longer, truncated, tiny}) {
        const Reply reply = send(frame);
        EXPECT_EQ(reply.kind, HFW_REPLY_NONE);
        EXPECT_TRUE(reply.frame.empty());
    }
    EXPECT_EQ(device_.dropped_frames, 5u);
    EXPECT_EQ(motor_.calls.size(), calls);
    EXPECT_EQ(motor_.force_un()[0], 1000);
}

TEST_F(FirmwareDevice, MessageLevelErrorsAreAnsweredAndApplyNothing) {
    hello();
    send_command(1, 1000);
    const std::size_t calls = motor_.calls.size();
    const Frame good = encoded(command(2, 5000));

    Frame reserved = good;  // the command's reserved u16
    reserved[14] = std::byte{1};
    auto report = expect_error(send(with_crc(reserved)), protocol::ErrorCode::bad_field);
    EXPECT_EQ(report.request_type, 0x03);
    EXPECT_EQ(report.session, kSession);

    Frame flags = good;
    flags[12] = std::byte{0x05};
    expect_error(send(with_crc(flags)), protocol::ErrorCode::bad_field);

    Frame axes_mismatch = good;  // axes 2 in a 1-axis payload
    axes_mismatch[13] = std::byte{2};
    expect_error(send(with_crc(axes_mismatch)), protocol::ErrorCode::bad_field);

    protocol::ForceCommand three = command(2, 5000);
    three.axes = 3;
    report = expect_error(send(encoded(three)), protocol::ErrorCode::wrong_axes);
    EXPECT_EQ(report.detail, 1u);

    Frame unknown = encoded(in_session(protocol::Poll{}));
    unknown[2] = std::byte{0x06};
    report = expect_error(send(with_crc(unknown)), protocol::ErrorCode::unknown_type);
    EXPECT_EQ(report.request_type, 0x06);

    protocol::ByeAck device_to_host;
    device_to_host.session = kSession;
    device_to_host.version = 2;
    expect_error(send(encoded(device_to_host)), protocol::ErrorCode::unexpected_type);

    Frame long_poll = encoded(in_session(protocol::Poll{}));  // a poll with a 4-byte payload
    long_poll[3] = std::byte{4};
    long_poll.insert(long_poll.begin() + 8, 4, std::byte{0});
    expect_error(send(with_crc(long_poll)), protocol::ErrorCode::bad_length);

    Frame version3 = good;
    version3[1] = std::byte{3};
    report = expect_error(send(with_crc(version3)), protocol::ErrorCode::bad_version);
    EXPECT_EQ(report.detail, 1u | (2u << 8));

    protocol::ForceCommand v1 = command(2, 5000);  // spoken, but not this session's version
    v1.version = 1;
    expect_error(send(encoded(v1)), protocol::ErrorCode::bad_version);

    Frame hello_v2 = encoded(protocol::Hello{.session = 7, .min_version = 1, .max_version = 2});
    hello_v2[1] = std::byte{2};  // hello is frozen at version 1
    expect_error(send(with_crc(hello_v2)), protocol::ErrorCode::bad_version);

    Frame hello_zero = encoded(protocol::Hello{.session = 7, .min_version = 1, .max_version = 2});
    protocol::wire::store_u32(hello_zero, 4, 0);  // session 0
    expect_error(send(with_crc(hello_zero)), protocol::ErrorCode::bad_field);

    protocol::Configure zero = in_session(protocol::Configure{});
    Frame zero_timeout = encoded(zero);
    protocol::wire::store_u32(zero_timeout, 8, 0);
    expect_error(send(with_crc(zero_timeout)), protocol::ErrorCode::bad_field);

    EXPECT_EQ(motor_.calls.size(), calls) << "an error applied something";
    EXPECT_EQ(motor_.force_un()[0], 1000);
    // The session is still open, and the sequence still the last accepted command's.
    EXPECT_EQ(send_command(2, 5000).status & protocol::kSampleCommandGap, 0u);
}

TEST_F(FirmwareDevice, BoardFaultsLatchZeroTheForceAndClearOnlyOnceGone) {
    hello();
    send_command(1, 1000);
    hfw_device_set_fault_causes(&device_, HFW_FAULT_ENCODER);
    EXPECT_EQ(motor_.force_un()[0], 0);
    auto sample = send_command(2, 0, protocol::kCommandClearFaults);
    EXPECT_EQ(sample.faults, protocol::kDeviceFaultEncoder) << "the cause is still there";
    hfw_device_set_fault_causes(&device_, 0);
    sample = send_command(3, 1000);
    EXPECT_EQ(sample.faults, protocol::kDeviceFaultEncoder) << "latched until cleared";
    EXPECT_EQ(motor_.force_un()[0], 0);
    sample = send_command(4, 0, protocol::kCommandClearFaults);
    EXPECT_EQ(sample.faults, 0u);
    send_command(5, 1000);
    EXPECT_EQ(motor_.force_un()[0], 1000);
}

TEST_F(FirmwareDevice, SensorStatusGoesIntoTheSample) {
    hello();
    const auto sample = expect<protocol::EncoderSample>(
        send(encoded(command(1, 0)), {-5'000'000'000LL}, HFW_STATUS_ENCODER_STALE | 0x8000u));
    EXPECT_EQ(sample.status, protocol::kSampleEncoderStale | protocol::kSampleForceActive);
    EXPECT_EQ(sample.counts[0], -5'000'000'000LL);
}

TEST_F(FirmwareDevice, AnyTrafficGetsOnlyWellFormedRepliesAndNeverExceedsTheLimit) {
    // Random frames, valid and damaged, in and out of a session: every reply decodes on the
    // host as a device-to-host message, and the motor never sees more than the limit.
    std::mt19937 random(29);
    const std::array<Frame, 6> seeds = {
        encoded(protocol::Hello{.session = kSession, .min_version = 1, .max_version = 2}),
        encoded(command(1, 30'000'000)),
        encoded(in_session(protocol::Poll{})),
        encoded(in_session(protocol::Bye{})),
        encoded(in_session(protocol::Configure{.session = 0, .watchdog_timeout_us = 3000})),
        encoded(command(2, -3000))};
    int replies = 0;
    for (int trial = 0; trial < 20'000; ++trial) {
        Frame frame = seeds[random() % seeds.size()];
        const int damage = static_cast<int>(random() % 4);
        for (int i = 0; i < damage; ++i) {
            frame[random() % frame.size()] = static_cast<std::byte>(random());
        }
        if (random() % 2 == 0) frame = with_crc(frame);
        if (random() % 8 == 0) frame.resize(random() % (frame.size() + 1));
        now_us_ += random() % 3000;
        const Reply reply = send(frame, {static_cast<std::int64_t>(random())});
        hfw_device_check_watchdog(&device_, now_us_);
        if (reply.kind == HFW_REPLY_NONE) continue;
        ++replies;
        ASSERT_EQ(reply.error, protocol::Error::none) << "trial " << trial;
        ASSERT_FALSE(protocol::is_host_to_device(protocol::type_of(reply.message)));
        for (const std::int32_t f : motor_.force_un()) ASSERT_LE(std::abs(f), 20'000'000);
    }
    EXPECT_GT(replies, 5000);
}

}  // namespace
}  // namespace hapticd::testing
