// The reference device: every fault knob as the host sees it, version 2 samples, and the
// serial and HID adapters (docs/protocol.md 5-7).
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <stdexcept>
#include <vector>

#include "device_emulator_fixture.hpp"

namespace hapticd::device::protocol {
namespace {

using namespace emulator_fixture;  // NOLINT

TEST(ProtocolEmulatorFaults, CorruptCrcGivesBadCrc) {
    DeviceEmulator device(config());
    Host host(device);
    host.hello();
    device.faults().corrupt_crc = 1;
    const std::vector<Received> r = host.send(host.command_frame({0, 0, 0}));
    ASSERT_EQ(r.size(), 1u);
    EXPECT_EQ(r[0].error, Error::bad_crc);
    EXPECT_EQ(device.faults().corrupt_crc, 0u);
    EXPECT_NO_FATAL_FAILURE(host.poll());  // one-shot
}

TEST(ProtocolEmulatorFaults, TruncateGivesTruncated) {
    DeviceEmulator device(config());
    Host host(device);
    host.hello();
    device.faults().truncate = 1;
    const std::vector<Received> r = host.send(host.command_frame({0, 0, 0}));
    ASSERT_EQ(r.size(), 1u);
    EXPECT_EQ(r[0].bytes.size(), 30u);
    EXPECT_EQ(r[0].error, Error::truncated);
}

TEST(ProtocolEmulatorFaults, DropGivesNoReplyThenAGap) {
    DeviceEmulator device(config());
    Host host(device);
    host.hello();
    ASSERT_EQ(host.tracker().check(host.command({0, 0, 0})).verdict, Verdict::accept);
    device.faults().drop = 1;
    const ForceCommand lost = host.command_frame({0, 0, 0});
    host.tracker().command_sent(lost.sequence);
    EXPECT_TRUE(host.send(lost).empty());  // the host times out: kStatusDropped, its own
    EXPECT_EQ(device.counters().commands_applied, 2u);  // but the device did apply it
    const ReplyTracker::Result r = host.tracker().check(host.command({0, 0, 0}));
    EXPECT_EQ(r.verdict, Verdict::accept);
    EXPECT_EQ(r.missed, 1u);
}

TEST(ProtocolEmulatorFaults, WrongSessionIsIgnoredByTheHost) {
    DeviceEmulator device(config());
    Host host(device);
    host.hello();
    device.faults().wrong_session = 1;
    const EncoderSample s = host.command({0, 0, 0});
    EXPECT_NE(s.session, kSession);
    EXPECT_EQ(host.tracker().check(s).verdict, Verdict::wrong_session);
    EXPECT_EQ(host.tracker().check(host.command({0, 0, 0})).verdict, Verdict::accept);
}

TEST(ProtocolEmulatorFaults, WrongDeviceIsFoundByItsSerial) {
    DeviceEmulator expected(config());
    EmulatorConfig other_config = config();
    other_config.serial_number = "EMU-OTHER";
    DeviceEmulator other(other_config);
    Host a(expected);
    Host b(other);
    EXPECT_TRUE(serial_matches(a.hello(), "EMU-TEST-1"));
    EXPECT_FALSE(serial_matches(b.hello(), "EMU-TEST-1"));
}

TEST(ProtocolEmulatorFaults, SequenceGapGivesMissedSamples) {
    DeviceEmulator device(config());
    Host host(device);
    host.hello();
    ASSERT_EQ(host.tracker().check(host.command({0, 0, 0})).verdict, Verdict::accept);
    device.faults().sequence_gap = 5;
    const ReplyTracker::Result r = host.tracker().check(host.command({0, 0, 0}));
    EXPECT_EQ(r.verdict, Verdict::accept);
    EXPECT_EQ(r.missed, 5u);
    EXPECT_EQ(host.tracker().check(host.command({0, 0, 0})).missed, 0u);
}

TEST(ProtocolEmulatorFaults, SequenceAheadPutsTheHostAheadOfTheDevice) {
    DeviceEmulator device(config());
    Host host(device);
    host.hello();
    ASSERT_EQ(host.tracker().check(host.command({0, 0, 0})).verdict, Verdict::accept);
    device.faults().sequence_ahead = 1000;
    const ReplyTracker::Result r = host.tracker().check(host.command({0, 0, 0}));
    EXPECT_EQ(r.verdict, Verdict::accept);  // no host can tell it from a real gap
    EXPECT_EQ(r.missed, 1000u);
    // The count went on from where it was: every later sample is behind the host's.
    EXPECT_EQ(host.tracker().check(host.command({0, 0, 0})).verdict, Verdict::duplicate);
    EXPECT_EQ(device.faults().sequence_ahead, 0u);
}

TEST(ProtocolEmulatorFaults, DelayGivesALateReplyBeforeTheNextOne) {
    DeviceEmulator device(config());
    Host host(device);
    host.hello();
    ASSERT_EQ(host.tracker().check(host.command({0, 0, 0})).verdict, Verdict::accept);
    device.faults().delay = 1;
    const ForceCommand first = host.command_frame({0, 0, 0});
    host.tracker().command_sent(first.sequence);
    EXPECT_TRUE(host.send(first).empty());  // nothing by the deadline
    const ForceCommand second = host.command_frame({0, 0, 0});
    host.tracker().command_sent(second.sequence);
    const std::vector<Received> r = host.send(second);
    ASSERT_EQ(r.size(), 2u);
    const auto& late = std::get<EncoderSample>(r[0].message);
    const auto& current = std::get<EncoderSample>(r[1].message);
    EXPECT_EQ(late.command_sequence, first.sequence);
    EXPECT_EQ(host.tracker().check(late).verdict, Verdict::late);
    const ReplyTracker::Result result = host.tracker().check(current);
    EXPECT_EQ(result.verdict, Verdict::accept);
    EXPECT_EQ(result.host_status, servo::kStatusLate);
}

TEST(ProtocolEmulatorFaults, StallIgnoresRequestsWhileTheClockRuns) {
    DeviceEmulator device(config(1));
    Host host(device);
    host.hello();
    host.command({1.0, 0, 0});
    device.faults().stall = 3;
    for (int i = 0; i < 3; ++i) EXPECT_TRUE(host.send(host.command_frame({5.0, 0, 0})).empty());
    EXPECT_EQ(device.counters().commands_applied, 1u);
    EXPECT_EQ(device.time_us(), 4000u);
    EXPECT_EQ(device.sim().held_force_n()[0], 1.0);  // the old force, held
    const EncoderSample s = host.command({1.0, 0, 0});
    EXPECT_EQ(s.status & (kSampleCommandLate | kSampleCommandGap),
              kSampleCommandLate | kSampleCommandGap);

    // A stall longer than the watchdog timeout trips it.
    device.faults().stall = 25;
    for (int i = 0; i < 25; ++i) host.send(host.command_frame({1.0, 0, 0}));
    EXPECT_EQ(device.latched_faults(), kDeviceFaultWatchdog);
    EXPECT_EQ(host.command({1.0, 0, 0}).faults, kDeviceFaultWatchdog);
}

TEST(ProtocolEmulatorFaults, DeviceFaultsLatchAndZeroTheForce) {
    DeviceEmulator device(config(1));
    Host host(device);
    host.hello();
    host.command({1.0, 0, 0});
    device.faults().device_faults = kDeviceFaultOverTemperature | kDeviceFaultAmplifier;
    const EncoderSample s = host.command({1.0, 0, 0});
    EXPECT_EQ(s.faults, kDeviceFaultOverTemperature | kDeviceFaultAmplifier);
    EXPECT_EQ(to_servo_status(s.status, s.faults), servo::kStatusDeviceFault);
    EXPECT_EQ(device.sim().held_force_n()[0], 0.0);
    EXPECT_EQ(host.command({0, 0, 0}, false, kCommandClearFaults).faults, 0u);
    EXPECT_EQ(host.command({1.0, 0, 0}).faults, 0u);
    EXPECT_EQ(device.sim().held_force_n()[0], 1.0);
}

TEST(ProtocolEmulatorFaults, SimulatedDeviceFaultsShowThrough) {
    EmulatorConfig c = config(1);
    c.sim.faults.stale_at_s = 0.005;
    c.sim.faults.stale_for_s = 0.002;
    c.sim.faults.drop_at_s = {0.010};
    c.sim.faults.disconnect_at_s = 0.020;
    DeviceEmulator device(c);
    Host host(device);
    host.hello();
    int replies = 0;
    for (int n = 1; n <= 25; ++n) {
        const ForceCommand frame = host.command_frame({0.1, 0, 0});
        const std::vector<Received> r = host.send(frame);
        if (n == 10 || n >= 20) {
            EXPECT_TRUE(r.empty()) << n;  // dropped, then the device is gone
            continue;
        }
        ASSERT_EQ(r.size(), 1u) << n;
        ++replies;
        const auto& s = std::get<EncoderSample>(r[0].message);
        const bool stale = n >= 5 && n < 7;
        EXPECT_EQ((s.status & kSampleEncoderStale) != 0u, stale) << n;
    }
    EXPECT_EQ(replies, 18);
    EXPECT_TRUE(device.gone());
    EXPECT_EQ(device.output_force_n()[0], 0.0);
}

// ---- transport adapters ----

// ---- version 2: which command is in effect, and since when ----

/// The delay of each command as a host measures it from version-2 samples: the device time
/// its force took effect minus that of the sample it was computed from (the answer to the
/// command before it), in microseconds.
std::vector<std::int64_t> measured_delays_us(double delay_periods, int commands) {
    EmulatorConfig c = config(1);
    c.sim.delay_s = delay_periods / c.sim.rate_hz;
    DeviceEmulator device(c);
    Host host(device);
    host.hello(kSession, kProtocolVersion2);
    std::map<std::uint32_t, std::uint64_t> basis_us;  // command -> its sample's time
    std::map<std::uint32_t, std::uint64_t> applied_us;
    std::uint64_t latest_us = host.poll().time_us;
    for (int n = 0; n < commands; ++n) {
        const ForceCommand frame = host.command_frame({0.1, 0, 0});
        host.tracker().command_sent(frame.sequence);
        basis_us[frame.sequence] = latest_us;
        const EncoderSample answer = host.ask<EncoderSample>(frame);
        const ReplyTracker::Result r = host.tracker().check(answer);
        EXPECT_EQ(r.verdict, Verdict::accept);
        EXPECT_NE(r.applied, ReplyTracker::Applied::bad_command);
        EXPECT_NE(r.applied, ReplyTracker::Applied::bad_time);
        if (r.applied == ReplyTracker::Applied::reported) {
            applied_us.emplace(r.applied_sequence, r.applied_time_us);
        }
        latest_us = answer.time_us;
    }
    std::vector<std::int64_t> delays;
    delays.reserve(applied_us.size());
    for (const auto& [command, at_us] : applied_us) {
        delays.push_back(static_cast<std::int64_t>(at_us) -
                         static_cast<std::int64_t>(basis_us.at(command)));
    }
    return delays;
}

TEST(ProtocolEmulator, Version2SamplesSayWhichCommandIsInEffectAndSinceWhen) {
    DeviceEmulator device(config(1));
    Host host(device);
    host.hello(kSession, kProtocolVersion2);
    EncoderSample s = host.poll();
    EXPECT_EQ(s.applied_lag, kAppliedLagNone);  // no command yet
    EXPECT_EQ(s.applied_age_us, kAppliedAgeUnknown);
    // No processing delay: each command acts from its arrival, held a period, then latched.
    s = host.command({1.0, 0, 0});
    EXPECT_EQ(s.version, 2);
    EXPECT_EQ(s.applied_lag, 0);
    EXPECT_EQ(s.applied_age_us, 1000u);
    EXPECT_EQ(s.time_us, 1000u);
    // A quiet period: the same command, a period older; a poll says the same.
    device.advance_period();
    s = host.poll();
    EXPECT_EQ(s.applied_lag, 0);
    EXPECT_EQ(s.applied_age_us, 2000u);
    // A new session does not hear of the old one's commands.
    host.hello(kSession + 1, kProtocolVersion2);
    EXPECT_FALSE(host.poll().names_applied());
}

TEST(ProtocolEmulator, ItsProcessingDelayIsWhatAHostMeasures) {
    // sim.delay_s is the time from a command's arrival to its force. In the emulator's
    // virtual time a command arrives at the instant the sample it was computed from (the
    // answer to the command before) was latched, so a host measures exactly the processing
    // delay, to the wire's microsecond.
    for (const double periods : {0.0, 0.25, 0.5, 1.0, 1.5, 3.0, 9.5}) {
        const std::vector<std::int64_t> delays = measured_delays_us(periods, 40);
        const auto lag_commands = static_cast<std::size_t>(std::ceil(periods));
        EXPECT_GE(delays.size(), 40u - lag_commands - 1) << periods;
        for (const std::int64_t d : delays) {
            ASSERT_EQ(d, std::llround(periods * 1000.0)) << periods;
        }
    }
    // Beyond a period the answer to command n names command n - 1 (1.5 periods: in effect
    // for half a period when the answer to the next command is latched).
    EmulatorConfig c = config(1);
    c.sim.delay_s = 1.5e-3;
    DeviceEmulator device(c);
    Host host(device);
    host.hello(kSession, kProtocolVersion2);
    EXPECT_FALSE(host.command({1.0, 0, 0}).names_applied());  // command 1 acts at 1.5 ms
    const EncoderSample s = host.command({1.0, 0, 0});        // latched at 2 ms
    EXPECT_EQ(s.command_sequence, 2u);
    EXPECT_EQ(s.applied_lag, 1);
    EXPECT_EQ(s.applied_age_us, 500u);
}

TEST(ProtocolEmulatorFaults, BadAcknowledgementsAreCountedByTheHost) {
    DeviceEmulator device(config(1));
    Host host(device);
    host.hello(kSession, kProtocolVersion2);
    for (int i = 0; i < 3; ++i) {
        ASSERT_EQ(host.tracker().check(host.command({0, 0, 0})).applied,
                  ReplyTracker::Applied::reported);
    }
    using Applied = ReplyTracker::Applied;
    // A command never sent.
    device.faults().applied_unsent = 1;
    ReplyTracker::Result r = host.tracker().check(host.command({0, 0, 0}));
    EXPECT_EQ(r.verdict, Verdict::accept);
    EXPECT_EQ(r.applied, Applied::bad_command);
    // The device clock jumping back.
    device.faults().clock_back_us = 2500;
    r = host.tracker().check(host.command({0, 0, 0}));
    EXPECT_EQ(r.verdict, Verdict::accept);
    EXPECT_EQ(r.applied, Applied::bad_time);
    // A command that took effect earlier than it did before.
    ASSERT_EQ(host.tracker().check(host.poll()).applied, Applied::reported);
    device.faults().applied_early_us = 300;
    EXPECT_EQ(host.tracker().check(host.poll()).applied, Applied::bad_time);
    // And it recovers: every knob fired once.
    EXPECT_EQ(host.tracker().check(host.command({0, 0, 0})).applied, Applied::reported);
    EXPECT_EQ(host.tracker().counters().applied_bad_command, 1u);
    EXPECT_EQ(host.tracker().counters().applied_bad_time, 2u);
}

TEST(ProtocolEmulator, SerialAdapterResynchronisesAndAnswersInCobs) {
    DeviceEmulator device(config());
    Hello hello;
    hello.session = kSession;
    Poll poll;
    poll.session = kSession;
    Noise noise(3);
    Bytes wire = noise.bytes(50);  // line noise before the host's leading delimiter
    wire.push_back(std::byte{0});
    for (const Bytes& frame : {encoded(hello), encoded(poll), encoded(poll)}) {
        Bytes s(stream_encoded_size(frame.size()));
        encode_stream(frame, s);
        wire.insert(wire.end(), s.begin(), s.end());
    }
    // Fed in awkward pieces, as a pty read would give them.
    Bytes out(1024);
    std::size_t written = 0;
    for (std::size_t at = 0; at < wire.size(); at += 13) {
        const std::size_t n = std::min<std::size_t>(13, wire.size() - at);
        written += device.handle_stream(std::span<const std::byte>(wire).subspan(at, n),
                                        std::span<std::byte>(out).subspan(written));
    }
    StreamDecoder decoder;
    std::vector<Message> replies;
    decoder.feed(std::span<const std::byte>(out).first(written), [&](std::span<const std::byte> f) {
        Message m;
        EXPECT_EQ(decode(f, m), Error::none);
        replies.push_back(m);
    });
    ASSERT_EQ(replies.size(), 3u);
    EXPECT_TRUE(std::holds_alternative<Identity>(replies[0]));
    EXPECT_EQ(std::get<EncoderSample>(replies[2]).sample_sequence, 1u);
}

TEST(ProtocolEmulator, HidAdapterAnswersWithInputReports) {
    DeviceEmulator device(config());
    Hello hello;
    hello.session = kSession;
    std::array<std::byte, hid::kReportSize> report{};
    ASSERT_TRUE(hid::wrap_report(hid::kOutputReportId, encoded(hello), report).ok());
    std::array<std::byte, 2 * hid::kReportSize> out{};
    ASSERT_EQ(device.handle_hid_report(report, out), hid::kReportSize);
    std::span<const std::byte> frame;
    ASSERT_EQ(
        hid::unwrap_report(hid::kInputReportId, std::span<const std::byte>(out).first(64), frame),
        Error::none);
    Identity identity;
    EXPECT_EQ(decode(frame, identity), Error::none);
    EXPECT_EQ(identity.session, kSession);

    // A report with the wrong ID is dropped; a truncated reply shows as a bad CRC in a
    // fixed-size report (the padding fills the missing bytes).
    report[0] = std::byte{hid::kInputReportId};
    EXPECT_EQ(device.handle_hid_report(report, out), 0u);
    device.faults().truncate = 1;
    Poll poll;
    poll.session = kSession;
    ASSERT_TRUE(hid::wrap_report(hid::kOutputReportId, encoded(poll), report).ok());
    ASSERT_EQ(device.handle_hid_report(report, out), hid::kReportSize);
    ASSERT_EQ(
        hid::unwrap_report(hid::kInputReportId, std::span<const std::byte>(out).first(64), frame),
        Error::none);
    EncoderSample sample;
    EXPECT_EQ(decode(frame, sample), Error::bad_crc);
}

TEST(ProtocolEmulator, HandleAllocatesNothing) {
    DeviceEmulator device(config());
    Host host(device);
    host.hello();
    const Bytes command = encoded(host.command_frame({0.5, -0.5, 0.0}));
    Bytes wire(stream_encoded_size(command.size()));
    encode_stream(command, wire);
    std::array<std::byte, hid::kReportSize> report{};
    hid::wrap_report(hid::kOutputReportId, command, report);
    std::array<std::byte, 4 * hid::kReportSize> out{};
    hapticd::testing::AllocationGuard guard;
    for (int i = 0; i < 1000; ++i) {
        // The same command frame each time: gaps are fine, allocation is not.
        EXPECT_EQ(device.handle(command, out).frames, 1u);
        device.advance_period();
        EXPECT_GT(device.handle_stream(wire, out), 0u);
        EXPECT_EQ(device.handle_hid_report(report, out), hid::kReportSize);
    }
    EXPECT_EQ(guard.allocations(), 0u);
}

TEST(ProtocolEmulator, RejectsConfigurationsTheWireCannotCarry) {
    EmulatorConfig c = config();
    c.serial_number = "";
    EXPECT_THROW(DeviceEmulator{c}, std::invalid_argument);
    c = config();
    c.serial_number = "THIS-SERIAL-IS-TOO-LONG";
    EXPECT_THROW(DeviceEmulator{c}, std::invalid_argument);
    c = config();
    c.sim.force_limit_n = 5000.0;  // > 2147 N
    EXPECT_THROW(DeviceEmulator{c}, std::invalid_argument);
    c = config();
    c.sim.rate_hz = 3000.0;  // 333.33 us
    EXPECT_THROW(DeviceEmulator{c}, std::invalid_argument);
    c = config();
    c.default_watchdog_timeout_us = 1500;  // below two periods
    EXPECT_THROW(DeviceEmulator{c}, std::invalid_argument);
    c = config();
    c.min_version = 0;
    EXPECT_THROW(DeviceEmulator{c}, std::invalid_argument);
    c = config();
    c.sim.rate_hz = 500.0;
    EXPECT_NO_THROW(DeviceEmulator{c});
}

}  // namespace
}  // namespace hapticd::device::protocol
