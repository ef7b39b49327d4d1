// What a host plugin builds on: status bits mapped onto servo::StatusBit, unit conversions,
// the reply tracker's session and sequence checks, and HID report wrapping
// (docs/protocol.md sections 4.6, 5.3 and 6.2).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "alloc_guard.hpp"
#include "hapticd/device/protocol/reply_tracker.hpp"
#include "hapticd/device/protocol/servo_convert.hpp"
#include "hapticd/device/protocol/status_map.hpp"
#include "hapticd/device/protocol/transport.hpp"
#include "protocol_test_util.hpp"

namespace hapticd::device::protocol {
namespace {

using servo::kStatusDeviceFault;
using servo::kStatusDisconnected;
using servo::kStatusDropped;
using servo::kStatusJump;
using servo::kStatusLate;
using servo::kStatusStale;
using testing::Bytes;
using testing::encoded;

// ---- status mapping ----

TEST(ProtocolStatusMap, EachDeviceBitMapsToItsServoBit) {
    EXPECT_EQ(to_servo_status(0, 0), 0u);
    EXPECT_EQ(to_servo_status(kSampleEncoderStale, 0), kStatusStale);
    EXPECT_EQ(to_servo_status(kSampleEncoderJump, 0), kStatusJump);
    EXPECT_EQ(to_servo_status(kSampleCommandLate, 0), kStatusLate);
    EXPECT_EQ(to_servo_status(kSampleCommandGap, 0), kStatusLate);
    EXPECT_EQ(to_servo_status(kSampleForceActive | kSampleForceClamped, 0), 0u);
    for (int bit = 0; bit < 16; ++bit) {
        const auto fault = static_cast<std::uint16_t>(1u << bit);
        EXPECT_EQ(to_servo_status(0, fault), kStatusDeviceFault) << bit;
    }
    EXPECT_EQ(
        to_servo_status(kSampleStatusMask, kDeviceFaultOverTemperature | kDeviceFaultAmplifier),
        kStatusStale | kStatusJump | kStatusLate | kStatusDeviceFault);
}

TEST(ProtocolStatusMap, HostOnlyBitsNeverComeFromTheDevice) {
    for (std::uint32_t status = 0; status <= 0xFFFF; ++status) {
        const std::uint32_t servo =
            to_servo_status(static_cast<std::uint16_t>(status), static_cast<std::uint16_t>(status));
        ASSERT_EQ(servo & (kStatusDisconnected | kStatusDropped), 0u) << status;
    }
}

TEST(ProtocolStatusMap, ServoEncoderFaultsBackToDeviceBits) {
    EXPECT_EQ(sample_status_from_servo(kStatusStale), kSampleEncoderStale);
    EXPECT_EQ(sample_status_from_servo(kStatusJump), kSampleEncoderJump);
    EXPECT_EQ(sample_status_from_servo(kStatusLate | kStatusDropped | kStatusDisconnected), 0u);
    EXPECT_EQ(to_servo_status(sample_status_from_servo(kStatusStale | kStatusJump), 0),
              kStatusStale | kStatusJump);
}

// ---- units ----

TEST(ProtocolConvert, ForceRoundsToTheNearestMicronewtonAndSaturates) {
    EXPECT_EQ(force_to_micronewtons(0.0), 0);
    EXPECT_EQ(force_to_micronewtons(1.5), 1'500'000);
    EXPECT_EQ(force_to_micronewtons(-0.25), -250'000);
    EXPECT_EQ(force_to_micronewtons(1.4e-6), 1);
    EXPECT_EQ(force_to_micronewtons(-1.6e-6), -2);
    EXPECT_EQ(force_to_micronewtons(2147.483647), 2147483647);
    EXPECT_EQ(force_to_micronewtons(1e9), std::numeric_limits<std::int32_t>::max());
    EXPECT_EQ(force_to_micronewtons(-1e9), std::numeric_limits<std::int32_t>::min());
    EXPECT_EQ(force_to_micronewtons(std::numeric_limits<double>::infinity()),
              std::numeric_limits<std::int32_t>::max());
    EXPECT_EQ(force_to_micronewtons(std::nan("")), 0);
    for (const double f : {-20.0, -3.3, 0.001, 7.77, 20.0}) {
        EXPECT_NEAR(force_from_micronewtons(force_to_micronewtons(f)), f, 0.5e-6) << f;
    }
    EXPECT_DOUBLE_EQ(time_from_microseconds(1'500'000), 1.5);
}

TEST(ProtocolConvert, ServoCommandToFrameAndBack) {
    servo::Command command;
    command.enable = true;
    command.force_n = {1.0, -2.0, 3.0};
    ForceCommand frame;
    ASSERT_TRUE(make_force_command(command, 2, 0xAA, 9, frame));
    EXPECT_EQ(frame.session, 0xAAu);
    EXPECT_EQ(frame.sequence, 9u);
    EXPECT_EQ(frame.flags, kCommandEnable);
    EXPECT_EQ(frame.axes, 2);
    EXPECT_EQ(frame.force_un, (std::array<std::int32_t, 3>{1'000'000, -2'000'000, 0}));
    EXPECT_FALSE(encoded(frame).empty());  // the unused third axis is zeroed
    const servo::Command back = to_servo_command(frame);
    EXPECT_TRUE(back.enable);
    EXPECT_EQ(back.force_n, (std::array<double, 3>{1.0, -2.0, 0.0}));
}

TEST(ProtocolConvert, NonFiniteForceSendsADisabledZeroCommand) {
    servo::Command command;
    command.enable = true;
    command.force_n = {1.0, std::numeric_limits<double>::infinity(), 0.0};
    ForceCommand frame;
    EXPECT_FALSE(make_force_command(command, 3, 1, 2, frame));
    EXPECT_FALSE(frame.enable());
    EXPECT_EQ(frame.force_un, (std::array<std::int32_t, 3>{}));
    EXPECT_FALSE(encoded(frame).empty());
    // An unused axis may hold anything.
    command.force_n = {1.0, std::nan(""), 0.0};
    EXPECT_TRUE(make_force_command(command, 1, 1, 2, frame));
}

TEST(ProtocolConvert, SampleFrameToServoSample) {
    EncoderSample sample;
    sample.axes = 2;
    sample.counts = {-7, 1ll << 40, 0};
    sample.time_us = 2'500'000;
    sample.status = kSampleEncoderStale;
    sample.faults = kDeviceFaultAmplifier;
    const servo::Sample out = to_servo_sample(sample, 1ull << 33, kStatusLate);
    EXPECT_EQ(out.encoder_counts, (std::array<std::int64_t, 3>{-7, 1ll << 40, 0}));
    EXPECT_DOUBLE_EQ(out.device_time_s, 2.5);
    EXPECT_EQ(out.sequence, 1ull << 33);
    EXPECT_EQ(out.status, kStatusStale | kStatusDeviceFault | kStatusLate);
}

// ---- reply tracker ----

EncoderSample reply(std::uint32_t session, std::uint32_t command, std::uint32_t sample) {
    EncoderSample s;
    s.session = session;
    s.command_sequence = command;
    s.sample_sequence = sample;
    s.axes = 1;
    return s;
}

using Verdict = ReplyTracker::Verdict;

TEST(ProtocolReplyTracker, SequenceDistanceWraps) {
    EXPECT_EQ(sequence_distance(1, 2), 1);
    EXPECT_EQ(sequence_distance(2, 1), -1);
    EXPECT_EQ(sequence_distance(0xFFFFFFFFu, 0), 1);
    EXPECT_EQ(sequence_distance(0, 0xFFFFFFFFu), -1);
    EXPECT_EQ(sequence_distance(0, 0x7FFFFFFFu), 0x7FFFFFFF);
}

TEST(ProtocolReplyTracker, AcceptsTheAwaitedReplies) {
    ReplyTracker tracker;
    tracker.start(7);
    // The answer to poll, before any command: command_sequence 0.
    ReplyTracker::Result r = tracker.check(reply(7, 0, 100));
    EXPECT_EQ(r.verdict, Verdict::accept);
    EXPECT_EQ(r.sequence, 100u);
    for (std::uint32_t n = 1; n <= 5; ++n) {
        tracker.command_sent(n);
        r = tracker.check(reply(7, n, 100 + n));
        EXPECT_EQ(r.verdict, Verdict::accept);
        EXPECT_EQ(r.sequence, 100u + n);
        EXPECT_EQ(r.missed, 0u);
        EXPECT_EQ(r.host_status, 0u);
    }
    EXPECT_EQ(tracker.counters().accepted, 6u);
}

TEST(ProtocolReplyTracker, RejectsAnotherSessionOrDevice) {
    ReplyTracker tracker;
    tracker.start(7);
    tracker.command_sent(1);
    EXPECT_EQ(tracker.check(reply(8, 1, 0)).verdict, Verdict::wrong_session);
    // Same session id by chance, but it answers a command this host never sent.
    EXPECT_EQ(tracker.check(reply(7, 2, 0)).verdict, Verdict::unexpected);
    tracker.start(9);
    EXPECT_EQ(tracker.check(reply(9, 5, 0)).verdict, Verdict::unexpected);  // nothing sent yet
    EXPECT_EQ(tracker.counters().wrong_session, 1u);
    EXPECT_EQ(tracker.counters().unexpected, 2u);
}

TEST(ProtocolReplyTracker, LateReplyIsSkippedAndFlagsTheNextSample) {
    ReplyTracker tracker;
    tracker.start(1);
    tracker.command_sent(10);
    ASSERT_EQ(tracker.check(reply(1, 10, 50)).verdict, Verdict::accept);
    tracker.command_sent(11);  // its reply misses the deadline: the host times out
    tracker.command_sent(12);
    EXPECT_EQ(tracker.check(reply(1, 11, 51)).verdict, Verdict::late);
    const ReplyTracker::Result r = tracker.check(reply(1, 12, 52));
    EXPECT_EQ(r.verdict, Verdict::accept);
    EXPECT_EQ(r.host_status, kStatusLate);
    EXPECT_EQ(r.missed, 1u);  // sample 51 was not used
    EXPECT_EQ(r.sequence, 52u);
    tracker.command_sent(13);
    EXPECT_EQ(tracker.check(reply(1, 13, 53)).host_status, 0u);
}

TEST(ProtocolReplyTracker, GapsDuplicatesAndWrap) {
    ReplyTracker tracker;
    tracker.start(1);
    tracker.command_sent(0xFFFFFFFEu);
    ASSERT_EQ(tracker.check(reply(1, 0xFFFFFFFEu, 0xFFFFFFFEu)).verdict, Verdict::accept);
    tracker.command_sent(0xFFFFFFFFu);
    EXPECT_EQ(tracker.check(reply(1, 0xFFFFFFFFu, 0xFFFFFFFEu)).verdict, Verdict::duplicate);
    ReplyTracker::Result r = tracker.check(reply(1, 0xFFFFFFFFu, 0xFFFFFFFFu));
    EXPECT_EQ(r.verdict, Verdict::accept);
    EXPECT_EQ(r.sequence, 0xFFFFFFFFull);
    tracker.command_sent(0);            // the command sequence wraps too
    r = tracker.check(reply(1, 0, 3));  // 0xFFFFFFFF -> 3: four ahead, three lost
    EXPECT_EQ(r.verdict, Verdict::accept);
    EXPECT_EQ(r.missed, 3u);
    EXPECT_EQ(r.sequence, 0x100000003ull);  // unwrapped past 2^32
    EXPECT_EQ(tracker.counters().missed, 3u);
    EXPECT_EQ(tracker.counters().duplicate, 1u);
}

/// A version-2 reply at `time_us` naming command `command - lag`, in effect `age_us`.
EncoderSample reply2(std::uint32_t command, std::uint32_t sample, std::uint64_t time_us,
                     std::uint8_t lag, std::uint16_t age_us) {
    EncoderSample s = reply(1, command, sample);
    s.version = kProtocolVersion2;
    s.time_us = time_us;
    s.applied_lag = lag;
    s.applied_age_us = age_us;
    return s;
}

using Applied = ReplyTracker::Applied;

TEST(ProtocolReplyTracker, Version1SamplesSayNothingAboutTheCommandInEffect) {
    ReplyTracker tracker;
    tracker.start(1);  // version 1
    tracker.command_sent(1);
    EncoderSample s = reply(1, 1, 1);
    s.time_us = 1000;
    const ReplyTracker::Result r = tracker.check(s);
    EXPECT_EQ(r.verdict, Verdict::accept);
    EXPECT_EQ(r.applied, Applied::unsupported);
}

TEST(ProtocolReplyTracker, Version2AcknowledgementsGiveWhenEachCommandTookEffect) {
    ReplyTracker tracker;
    tracker.start(1, kProtocolVersion2);
    EXPECT_EQ(tracker.version(), kProtocolVersion2);
    // Before any command: nothing in effect.
    ReplyTracker::Result r = tracker.check(reply2(0, 0, 5000, kAppliedLagNone, kAppliedAgeUnknown));
    EXPECT_EQ(r.verdict, Verdict::accept);
    EXPECT_EQ(r.applied, Applied::none);
    // A device 1.5 periods behind: the answer to command 1 names none yet, that to command 2
    // names command 1 (in effect 500 us), and so on.
    tracker.command_sent(1);
    r = tracker.check(reply2(1, 1, 6000, kAppliedLagNone, kAppliedAgeUnknown));
    EXPECT_EQ(r.applied, Applied::none);
    for (std::uint32_t n = 2; n <= 5; ++n) {
        tracker.command_sent(n);
        r = tracker.check(reply2(n, n, 5000 + 1000 * n, 1, 500));
        EXPECT_EQ(r.verdict, Verdict::accept);
        ASSERT_EQ(r.applied, Applied::reported) << n;
        EXPECT_EQ(r.applied_sequence, n - 1);
        EXPECT_EQ(r.applied_time_us, 4500u + 1000 * n);
    }
    // The same command named again (a poll): the same moment is fine.
    r = tracker.check(reply2(5, 6, 10'200, 1, 700));
    EXPECT_EQ(r.applied, Applied::reported);
    EXPECT_EQ(r.applied_sequence, 4u);
    EXPECT_EQ(r.applied_time_us, 9500u);
    // Too long ago to say: none, not bad.
    r = tracker.check(reply2(5, 7, 80'000, 1, kAppliedAgeUnknown));
    EXPECT_EQ(r.applied, Applied::none);
    EXPECT_EQ(tracker.counters().applied_reported, 5u);  // 4 answers and the poll
    EXPECT_EQ(tracker.counters().applied_bad_command + tracker.counters().applied_bad_time, 0u);
}

TEST(ProtocolReplyTracker, BadAcknowledgementsAreCountedAndNotUsedButTheSampleIs) {
    ReplyTracker tracker;
    tracker.start(1, kProtocolVersion2);
    for (std::uint32_t n = 1; n <= 3; ++n) {
        tracker.command_sent(n);
        ASSERT_EQ(tracker.check(reply2(n, n, std::uint64_t{1000} * n, 0, 0)).applied,
                  Applied::reported);
    }
    tracker.command_sent(4);
    // A command never sent: four sent, so a lag of 4 names command 0.
    ReplyTracker::Result r = tracker.check(reply2(4, 4, 4000, 4, 0));
    EXPECT_EQ(r.verdict, Verdict::accept);  // the counts are as good as any
    EXPECT_EQ(r.applied, Applied::bad_command);
    // Command 2, older than command 3 named before.
    EXPECT_EQ(tracker.check(reply2(4, 5, 4000, 2, 0)).applied, Applied::bad_command);
    // "Nothing in effect" after command 3 was.
    EXPECT_EQ(tracker.check(reply2(4, 6, 4000, kAppliedLagNone, kAppliedAgeUnknown)).applied,
              Applied::bad_command);
    // The device clock going backwards (the last sound sample was at 3000 us).
    EXPECT_EQ(tracker.check(reply2(4, 7, 2999, 0, 0)).applied, Applied::bad_time);
    // Command 3 took effect at 3000 us: it cannot have done so at 2500 us as well ...
    EXPECT_EQ(tracker.check(reply2(4, 8, 4000, 1, 1500)).applied, Applied::bad_time);
    // ... and command 4 not before command 3.
    EXPECT_EQ(tracker.check(reply2(4, 9, 4000, 0, 1100)).applied, Applied::bad_time);
    // What is sound is still used: command 4 at 3900 us.
    r = tracker.check(reply2(4, 10, 4000, 0, 100));
    EXPECT_EQ(r.applied, Applied::reported);
    EXPECT_EQ(r.applied_sequence, 4u);
    EXPECT_EQ(r.applied_time_us, 3900u);
    EXPECT_EQ(tracker.counters().accepted, 10u);
    EXPECT_EQ(tracker.counters().applied_bad_command, 3u);
    EXPECT_EQ(tracker.counters().applied_bad_time, 3u);
    EXPECT_EQ(tracker.counters().applied_reported, 4u);
}

TEST(ProtocolReplyTracker, AnAcknowledgementBeforeAnyCommandIsBad) {
    ReplyTracker tracker;
    tracker.start(1, kProtocolVersion2);
    EXPECT_EQ(tracker.check(reply2(0, 0, 10, 0, 0)).applied, Applied::bad_command);
}

TEST(ProtocolReplyTracker, SerialNumberCheck) {
    Identity identity;
    ASSERT_TRUE(identity.set_serial_number("HD3-000042"));
    EXPECT_TRUE(serial_matches(identity, "HD3-000042"));
    EXPECT_FALSE(serial_matches(identity, "HD3-000043"));
    EXPECT_FALSE(serial_matches(identity, "HD3-00004"));
}

TEST(ProtocolReplyTracker, AllocatesNothing) {
    ReplyTracker tracker;
    hapticd::testing::AllocationGuard guard;
    tracker.start(3);
    for (std::uint32_t n = 1; n < 10000; ++n) {
        tracker.command_sent(n);
        EXPECT_EQ(tracker.check(reply(3, n, n)).verdict, Verdict::accept);
    }
    EXPECT_EQ(guard.allocations(), 0u);
}

// ---- HID reports ----

TEST(ProtocolHid, ReportDescriptorDeclaresTwo63ByteReports) {
    const auto& d = hid::kReportDescriptor;
    EXPECT_EQ(d.size(), 31u);
    EXPECT_EQ(d.front(), 0x06);
    EXPECT_EQ(d.back(), 0xC0);
    int report_counts_63 = 0;
    for (std::size_t i = 0; i + 1 < d.size(); ++i) {
        if (d[i] == 0x95 && d[i + 1] == 0x3F) ++report_counts_63;
    }
    EXPECT_EQ(report_counts_63, 2);
}

TEST(ProtocolHid, WrapAndUnwrap) {
    EncoderSample sample = reply(4, 5, 6);
    sample.axes = 3;
    const Bytes frame = encoded(sample);
    std::array<std::byte, hid::kReportSize> report{};
    report.fill(std::byte{0xEE});
    const Encoded e = hid::wrap_report(hid::kInputReportId, frame, report);
    ASSERT_TRUE(e.ok());
    EXPECT_EQ(e.size, 64u);
    EXPECT_EQ(report[0], std::byte{hid::kInputReportId});
    for (std::size_t i = 1 + frame.size(); i < report.size(); ++i)
        EXPECT_EQ(report[i], std::byte{0});

    std::span<const std::byte> inner;
    ASSERT_EQ(hid::unwrap_report(hid::kInputReportId, report, inner), Error::none);
    EXPECT_EQ(Bytes(inner.begin(), inner.end()), frame);
    EncoderSample back;
    EXPECT_EQ(decode(inner, back), Error::none);
    EXPECT_TRUE(back == sample);

    EXPECT_EQ(hid::unwrap_report(hid::kOutputReportId, report, inner), Error::bad_report_id);
    EXPECT_EQ(hid::unwrap_report(hid::kInputReportId, {}, inner), Error::truncated);
    // A report cut short keeps what there is, and the decoder says truncated.
    ASSERT_EQ(hid::unwrap_report(hid::kInputReportId, std::span<const std::byte>(report).first(30),
                                 inner),
              Error::none);
    EXPECT_EQ(decode(inner, back), Error::truncated);
    // Garbage: all the data bytes, and the decoder says why.
    Bytes garbage(64, std::byte{0x33});
    garbage[0] = std::byte{hid::kInputReportId};
    ASSERT_EQ(hid::unwrap_report(hid::kInputReportId, garbage, inner), Error::none);
    EXPECT_EQ(inner.size(), 63u);
    EXPECT_EQ(decode(inner, back), Error::bad_magic);

    EXPECT_EQ(hid::wrap_report(1, Bytes(64), report).error, Error::bad_length);
    EXPECT_EQ(hid::wrap_report(1, frame, std::span<std::byte>(report).first(63)).error,
              Error::no_space);
}

}  // namespace
}  // namespace hapticd::device::protocol
