// The reference device: handshake and version negotiation, every refusal, a closed loop that
// matches the simulated device driven directly bit for bit, and the watchdog's timing
// (docs/protocol.md 5-7). Every fault knob as the host sees it, version 2 samples and the
// serial and HID adapters: device_emulator_faults_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <stdexcept>
#include <vector>

#include "device_emulator_fixture.hpp"

namespace hapticd::device::protocol {
namespace {

using namespace emulator_fixture;  // NOLINT

TEST(ProtocolEmulator, HelloAnswersWithTheIdentity) {
    DeviceEmulator device(config());
    Host host(device);
    const Identity identity = host.hello();
    EXPECT_EQ(identity.session, kSession);
    EXPECT_EQ(identity.axes, 3);
    EXPECT_EQ(identity.force_limit_un, 10'000'000);
    EXPECT_EQ(identity.counts_per_meter, 2e5);
    EXPECT_EQ(identity.period_us, 1000u);
    EXPECT_EQ(identity.watchdog_timeout_us, 20'000u);
    EXPECT_EQ(identity.firmware_version, 0x00010000u);
    EXPECT_EQ(identity.serial_number(), "EMU-TEST-1");
    EXPECT_TRUE(device.session_open());
    EXPECT_EQ(device.session(), kSession);

    // Before any command: a poll answers with command_sequence 0 at time 0, force off.
    const EncoderSample first = host.poll();
    EXPECT_EQ(first.command_sequence, 0u);
    EXPECT_EQ(first.sample_sequence, 0u);
    EXPECT_EQ(first.time_us, 0u);
    EXPECT_EQ(first.status, 0u);
    EXPECT_EQ(first.faults, 0u);
    EXPECT_EQ(host.tracker().check(first).verdict, Verdict::accept);
}

TEST(ProtocolEmulator, VersionNegotiation) {
    DeviceEmulator device(config());
    Host host(device);
    Hello hello;
    hello.session = 5;
    hello.min_version = 1;
    hello.max_version = 9;  // a newer host: the device picks its newest, 2
    const std::vector<Received> ok = host.send(hello);
    ASSERT_EQ(ok.size(), 1u);
    EXPECT_TRUE(std::holds_alternative<Identity>(ok[0].message));
    EXPECT_EQ(ok[0].bytes[1], std::byte{2});
    EXPECT_EQ(device.version(), 2);
    hello.max_version = 1;  // a version-1 host
    ASSERT_EQ(host.send(hello).size(), 1u);
    EXPECT_EQ(device.version(), 1);

    hello.min_version = 3;
    hello.max_version = 4;  // no version in common
    const ErrorReport report = expect_error(host.send(hello), ErrorCode::unsupported_version);
    EXPECT_EQ(report.detail, 0x0201u);  // the device speaks 1..2
    EXPECT_EQ(report.request_type, 0x01);
    EXPECT_EQ(report.session, 5u);
    EXPECT_FALSE(device.session_open());  // a refused hello still ended the old session

    EmulatorConfig newer = config();
    newer.min_version = 2;
    newer.max_version = 3;
    DeviceEmulator device2(newer);
    Host host2(device2);
    hello.min_version = 1;
    hello.max_version = 1;
    EXPECT_EQ(expect_error(host2.send(hello), ErrorCode::unsupported_version).detail, 0x0302u);

    // A firmware from before version 2 answers a new host in version 1.
    EmulatorConfig older = config();
    older.max_version = 1;
    DeviceEmulator device3(older);
    Host host3(device3);
    EXPECT_EQ(host3.hello(kSession, kProtocolVersion2).version, 1);
    const EncoderSample sample = host3.command({0, 0, 0});
    EXPECT_EQ(sample.version, 1);
    EXPECT_FALSE(sample.names_applied());
}

TEST(ProtocolEmulator, ASessionSpeaksOnlyItsVersion) {
    DeviceEmulator device(config());
    Host host(device);
    EXPECT_EQ(host.hello(kSession, kProtocolVersion2).version, 2);
    EXPECT_EQ(host.poll().version, 2);
    ConfigureAck ack = host.ask<ConfigureAck>(Configure{kSession, 5000, kProtocolVersion2});
    EXPECT_EQ(ack.version, 2);
    // A version-1 frame in a version-2 session: refused, nothing applied.
    ForceCommand command = host.command_frame({1.0, 0, 0});
    command.version = kProtocolVersion1;
    EXPECT_EQ(expect_error(host.send(command), ErrorCode::bad_version).detail, 0x0201u);
    EXPECT_EQ(device.counters().commands_applied, 0u);
    EXPECT_EQ(host.ask<ByeAck>(Bye{kSession, kProtocolVersion2}).version, 2);
}

TEST(ProtocolEmulator, RefusesRequestsOutsideASession) {
    DeviceEmulator device(config());
    Host host(device);
    Poll poll;
    poll.session = 1;
    expect_error(host.send(poll), ErrorCode::no_session);
    host.hello(kSession);
    poll.session = kSession + 1;
    expect_error(host.send(poll), ErrorCode::wrong_session);

    // A command from the wrong session is not applied.
    ForceCommand stale = host.command_frame({5.0, 5.0, 5.0});
    stale.session = 0x0BADCAFE;
    const ErrorReport report = expect_error(host.send(stale), ErrorCode::wrong_session);
    EXPECT_EQ(report.session, 0x0BADCAFEu);
    EXPECT_EQ(report.request_type, 0x03);
    EXPECT_EQ(device.output_force_n(), (std::array<double, 3>{}));
    EXPECT_EQ(device.counters().commands_applied, 0u);
    EXPECT_EQ(device.time_us(), 0u);  // and no time passed
}

TEST(ProtocolEmulator, AnswersMessageLevelErrorsAndDropsFrameLevelOnes) {
    DeviceEmulator device(config());
    Host host(device);
    host.hello();

    // Frame-level: no reply at all.
    Bytes frame = encoded(host.command_frame({1.0, 0.0, 0.0}));
    Bytes bad_crc = frame;
    bad_crc[10] ^= std::byte{1};
    EXPECT_TRUE(host.send_bytes(bad_crc).empty());
    EXPECT_TRUE(host.send_bytes(std::span<const std::byte>(frame).first(20)).empty());
    Bytes bad_magic = frame;
    bad_magic[0] = std::byte{0};
    EXPECT_TRUE(host.send_bytes(bad_magic).empty());
    EXPECT_EQ(device.counters().dropped_requests, 3u);
    EXPECT_EQ(device.counters().commands_applied, 0u);

    auto refit = [](Bytes f) {
        const std::size_t crc_at = f.size() - kCrcSize;
        wire::store_u32(f, crc_at, crc32c(std::span<const std::byte>(f).first(crc_at)));
        return f;
    };
    // Message-level: an error message naming the problem.
    Bytes version = frame;
    version[1] = std::byte{3};  // not spoken
    EXPECT_EQ(expect_error(host.send_bytes(refit(version)), ErrorCode::bad_version).detail,
              0x0201u);
    version[1] = std::byte{2};  // spoken, but not this version-1 session's
    EXPECT_EQ(expect_error(host.send_bytes(refit(version)), ErrorCode::bad_version).detail,
              0x0201u);
    Bytes type = frame;
    type[2] = std::byte{0x42};
    EXPECT_EQ(expect_error(host.send_bytes(refit(type)), ErrorCode::unknown_type).request_type,
              0x42);
    Bytes flags = frame;
    flags[12] = std::byte{0x80};
    expect_error(host.send_bytes(refit(flags)), ErrorCode::bad_field);
    EncoderSample sample;
    sample.session = kSession;
    expect_error(host.send(sample), ErrorCode::unexpected_type);
    // A configure frame with a command's payload size.
    Bytes size = frame;
    size[2] = std::byte{0x02};
    expect_error(host.send_bytes(refit(size)), ErrorCode::bad_length);
    EXPECT_EQ(device.counters().commands_applied, 0u);
}

TEST(ProtocolEmulator, WrongAxesIsRefused) {
    DeviceEmulator device(config(2));
    Host host(device);
    host.hello();
    ForceCommand command = host.command_frame({1.0, 1.0, 0.0});
    command.axes = 3;
    EXPECT_EQ(expect_error(host.send(command), ErrorCode::wrong_axes).detail, 2u);
    EXPECT_EQ(device.counters().commands_applied, 0u);
}

TEST(ProtocolEmulator, ConfigureTheWatchdog) {
    DeviceEmulator device(config());
    Host host(device);
    host.hello();
    Configure configure;
    configure.session = kSession;
    configure.watchdog_timeout_us = 50'000;
    EXPECT_EQ(host.ask<ConfigureAck>(configure).watchdog_timeout_us, 50'000u);
    EXPECT_EQ(device.watchdog_timeout_us(), 50'000u);
    configure.watchdog_timeout_us = 1999;  // below two periods
    EXPECT_EQ(expect_error(host.send(configure), ErrorCode::out_of_range).detail, 2000u);
    configure.watchdog_timeout_us = 2'000'000;
    EXPECT_EQ(expect_error(host.send(configure), ErrorCode::out_of_range).detail, 1'000'000u);
    EXPECT_EQ(device.watchdog_timeout_us(), 50'000u);
    // A new session starts from the default.
    host.hello(kSession + 1);
    EXPECT_EQ(device.watchdog_timeout_us(), 20'000u);
}

// ---- the closed loop ----

/// A spring-damper pulling each axis to the origin, computed from counts only, as the servo
/// would (backward-difference velocity).
std::array<double, 3> controller(const std::array<std::int64_t, 3>& counts,
                                 const std::array<std::int64_t, 3>& previous, double cpm) {
    std::array<double, 3> force{};
    for (int i = 0; i < 3; ++i) {
        const double x = static_cast<double>(counts[i]) / cpm;
        const double v = static_cast<double>(counts[i] - previous[i]) / cpm / 1e-3;
        force[i] = -300.0 * x - 2.0 * v;
    }
    return force;
}

TEST(ProtocolEmulator, ClosedLoopMatchesTheSimulatedDeviceBitForBit) {
    EmulatorConfig c = config(3);
    c.sim.initial_position_m = {0.02, -0.015, 0.004};
    c.sim.human[1].family = sim::HumanFamily::stiff_grasp;
    c.sim.human[1].hand_mass_kg = 0.3;
    c.sim.human[1].hand_stiffness_n_per_m = 400.0;
    c.sim.human[1].hand_damping_n_s_per_m = 3.0;
    c.sim.human[1].push = {-0.015, 0.01, 0.2, 0.3, 0.5};
    c.sim.coulomb_n = 0.05;
    DeviceEmulator device(c);
    Host host(device);
    host.hello();

    sim::SimConfig direct_config = c.sim;
    direct_config.clock = sim::SimClock::lockstep;
    sim::SimDevice direct;
    direct.open(direct_config);

    // Through the protocol: poll, then command -> sample. Directly: read, write, read...
    EncoderSample wire_sample = host.poll();
    servo::Sample direct_sample;
    ASSERT_EQ(direct.read(direct_sample), servo::IoResult::ok);
    std::array<std::int64_t, 3> wire_previous = wire_sample.counts;
    std::array<std::int64_t, 3> direct_previous = direct_sample.encoder_counts;
    std::int64_t travel = 0;
    for (int n = 1; n <= 3000; ++n) {
        ASSERT_EQ(wire_sample.counts, direct_sample.encoder_counts) << "period " << n;
        ASSERT_EQ(wire_sample.time_us,
                  static_cast<std::uint64_t>(std::llround(direct_sample.device_time_s * 1e6)));
        const auto wire_force = controller(wire_sample.counts, wire_previous, 2e5);
        const auto direct_force = controller(direct_sample.encoder_counts, direct_previous, 2e5);
        wire_previous = wire_sample.counts;
        direct_previous = direct_sample.encoder_counts;

        wire_sample = host.command(wire_force);
        ASSERT_EQ(host.tracker().check(wire_sample).verdict, Verdict::accept);
        EXPECT_EQ(wire_sample.command_sequence, static_cast<std::uint32_t>(n));
        EXPECT_EQ(wire_sample.sample_sequence, static_cast<std::uint32_t>(n));  // poll was 0

        servo::Command command;  // the same quantisation the wire imposes
        command.enable = true;
        for (int i = 0; i < 3; ++i) {
            command.force_n[i] = force_from_micronewtons(force_to_micronewtons(direct_force[i]));
        }
        ASSERT_EQ(direct.write(command), servo::IoResult::ok);
        ASSERT_EQ(direct.read(direct_sample), servo::IoResult::ok);
        travel += std::llabs(wire_sample.counts[0] - wire_previous[0]);
    }
    EXPECT_EQ(wire_sample.time_us, 3'000'000u);
    EXPECT_GT(travel, 4000);  // the loop really moved the handle (0.02 m = 4000 counts)
    EXPECT_EQ(device.counters().commands_applied, 3000u);
    EXPECT_EQ(host.tracker().counters().missed, 0u);
}

TEST(ProtocolEmulator, CommandIsHeldForOnePeriodAndClampedToTheLimit) {
    DeviceEmulator device(config(1));
    Host host(device);
    host.hello();
    const EncoderSample sample = host.command({25.0, 0.0, 0.0});
    EXPECT_EQ(sample.time_us, 1000u);
    EXPECT_EQ(sample.status & (kSampleForceActive | kSampleForceClamped),
              kSampleForceActive | kSampleForceClamped);
    EXPECT_EQ(device.output_force_n()[0], 10.0);
    EXPECT_EQ(device.sim().held_force_n()[0], 10.0);
    // enable off: zero force, not active.
    const EncoderSample off = host.command({3.0, 0.0, 0.0}, false);
    EXPECT_EQ(off.status & (kSampleForceActive | kSampleForceClamped), 0u);
    EXPECT_EQ(device.sim().held_force_n()[0], 0.0);
}

TEST(ProtocolEmulator, DeviceSeesLateAndLostCommands) {
    DeviceEmulator device(config(1));
    Host host(device);
    host.hello();
    EXPECT_EQ(host.command({1.0, 0, 0}).status & (kSampleCommandLate | kSampleCommandGap), 0u);
    EXPECT_EQ(host.command({1.0, 0, 0}).status & (kSampleCommandLate | kSampleCommandGap), 0u);
    device.advance_period();  // a period without a command: the last force held for two
    EncoderSample late = host.command({1.0, 0, 0});
    EXPECT_EQ(late.status & (kSampleCommandLate | kSampleCommandGap), kSampleCommandLate);
    ++host.next_sequence();  // a command lost on the way to the device
    const EncoderSample gap = host.command({1.0, 0, 0});
    EXPECT_EQ(gap.status & (kSampleCommandLate | kSampleCommandGap), kSampleCommandGap);
    EXPECT_EQ(to_servo_status(gap.status, gap.faults), servo::kStatusLate);
}

// ---- the watchdog ----

TEST(ProtocolEmulator, WatchdogZeroesTheForceAfterTheTimeoutAndNotBefore) {
    DeviceEmulator device(config(1));
    Host host(device);
    host.hello();
    Configure configure;
    configure.session = kSession;
    configure.watchdog_timeout_us = 15'000;  // 15 periods
    host.ask<ConfigureAck>(configure);

    host.command({2.0, 0, 0});  // arrives at t = 0, held over [0, 1 ms)
    ASSERT_EQ(device.sim().held_force_n()[0], 2.0);
    // Periods without commands: the force is held over every period that starts before
    // t = 15 ms (15 ms after the command arrived), and zero from then on.
    for (int k = 1; k <= 20; ++k) {
        const std::uint64_t period_start_us = device.time_us();
        device.advance_period();  // simulates [start, start + 1 ms)
        EXPECT_EQ(device.sim().held_force_n()[0], period_start_us < 15'000 ? 2.0 : 0.0)
            << "period starting at " << period_start_us << " us";
        EXPECT_EQ((device.latched_faults() & kDeviceFaultWatchdog) != 0u,
                  device.time_us() >= 15'000)
            << "t = " << device.time_us() << " us";
    }
    EXPECT_EQ(device.counters().watchdog_trips, 1u);
    EXPECT_EQ(device.output_force_n()[0], 0.0);

    // The host sees it: fault bit, device fault for the servo, force inactive.
    const EncoderSample sample = host.poll();
    EXPECT_EQ(sample.faults, kDeviceFaultWatchdog);
    EXPECT_EQ(sample.status & kSampleForceActive, 0u);
    EXPECT_EQ(to_servo_status(sample.status, sample.faults), servo::kStatusDeviceFault);

    // Latched: enabled commands hold zero, clear_faults with enable on does nothing.
    EXPECT_EQ(host.command({2.0, 0, 0}).faults, kDeviceFaultWatchdog);
    EXPECT_EQ(host.command({2.0, 0, 0}, true, kCommandClearFaults).faults, kDeviceFaultWatchdog);
    EXPECT_EQ(device.sim().held_force_n()[0], 0.0);
    // clear_faults with enable off clears it; the next command applies force again.
    EXPECT_EQ(host.command({0.0, 0, 0}, false, kCommandClearFaults).faults, 0u);
    const EncoderSample again = host.command({2.0, 0, 0});
    EXPECT_EQ(again.faults, 0u);
    EXPECT_NE(again.status & kSampleForceActive, 0u);
    EXPECT_EQ(device.sim().held_force_n()[0], 2.0);
}

TEST(ProtocolEmulator, WatchdogTripsExactlyAtTheDefaultTimeout) {
    DeviceEmulator device(config(1));
    Host host(device);
    host.hello();
    host.command({1.0, 0, 0});
    int periods = 1;  // the command's own period
    while ((device.latched_faults() & kDeviceFaultWatchdog) == 0u && periods < 100) {
        device.advance_period();
        ++periods;
    }
    EXPECT_EQ(periods, 20);  // 20 ms default: tripped at t = 20 ms
    EXPECT_EQ(device.time_us(), 20'000u);
}

TEST(ProtocolEmulator, WatchdogStaysQuietWhileCommandsArrive) {
    DeviceEmulator device(config(1));
    Host host(device);
    host.hello();
    for (int n = 0; n < 2000; ++n) ASSERT_EQ(host.command({0.5, 0, 0}).faults, 0u);
    // Commands 19 periods apart (the 20 ms timeout minus one): late, never tripped.
    for (int n = 0; n < 20; ++n) {
        for (int k = 0; k < 18; ++k) device.advance_period();
        const EncoderSample s = host.command({0.5, 0, 0});
        ASSERT_EQ(s.faults, 0u);
        EXPECT_NE(s.status & kSampleCommandLate, 0u);
    }
    EXPECT_EQ(device.counters().watchdog_trips, 0u);
}

TEST(ProtocolEmulator, WatchdogIdleBeforeTheFirstCommandAndAfterBye) {
    DeviceEmulator device(config(1));
    Host host(device);
    host.hello();
    for (int k = 0; k < 100; ++k) device.advance_period();
    EXPECT_EQ(device.latched_faults(), 0u);
    host.command({1.0, 0, 0});
    Bye bye;
    bye.session = kSession;
    EXPECT_EQ(host.ask<ByeAck>(bye).session, kSession);
    EXPECT_FALSE(device.session_open());
    EXPECT_EQ(device.output_force_n()[0], 0.0);
    for (int k = 0; k < 100; ++k) device.advance_period();
    EXPECT_EQ(device.latched_faults(), 0u);
    EXPECT_EQ(device.sim().held_force_n()[0], 0.0);
    expect_error(host.send(host.command_frame({1.0, 0, 0})), ErrorCode::no_session);
}

TEST(ProtocolEmulator, NewHelloZeroesTheForceAndClearsTheWatchdog) {
    DeviceEmulator device(config(1));
    Host host(device);
    host.hello(1);
    host.command({1.0, 0, 0});
    for (int k = 0; k < 30; ++k) device.advance_period();
    ASSERT_EQ(device.latched_faults(), kDeviceFaultWatchdog);
    Host second(device);
    second.hello(2);
    EXPECT_EQ(device.latched_faults(), 0u);
    EXPECT_EQ(device.output_force_n()[0], 0.0);
    // The first host's commands are now refused.
    expect_error(host.send(host.command_frame({1.0, 0, 0})), ErrorCode::wrong_session);
    EXPECT_EQ(second.poll().command_sequence, 0u);
}

// ---- fault knobs, each as the host must see it ----

}  // namespace
}  // namespace hapticd::device::protocol
