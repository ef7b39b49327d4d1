// The reference device: handshake and version negotiation, every refusal, a closed loop that
// matches the simulated device driven directly bit for bit, the watchdog's timing, every
// fault knob as the host sees it, and the serial and HID adapters (docs/protocol.md 5-7).
#include "hapticd/device/protocol/device_emulator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <stdexcept>
#include <vector>

#include "alloc_guard.hpp"
#include "hapticd/device/protocol/crc32c.hpp"
#include "hapticd/device/protocol/reply_tracker.hpp"
#include "hapticd/device/protocol/servo_convert.hpp"
#include "hapticd/device/protocol/status_map.hpp"
#include "hapticd/device/protocol/transport.hpp"
#include "hapticd/device/protocol/wire.hpp"
#include "protocol_test_util.hpp"

namespace hapticd::device::protocol {
namespace {

using testing::Bytes;
using testing::encoded;
using testing::Noise;
using Verdict = ReplyTracker::Verdict;

constexpr std::uint32_t kSession = 0x600DF00Du;

EmulatorConfig config(int axes = 3) {
    EmulatorConfig c;
    c.sim.axes = axes;
    c.sim.rate_hz = 1000.0;
    c.sim.mass_kg = 0.2;
    c.sim.damping_n_s_per_m = 1.5;
    c.sim.counts_per_meter = 2e5;
    c.sim.force_limit_n = 10.0;
    c.serial_number = "EMU-TEST-1";
    return c;
}

/// What a host received for one request: each frame, decoded.
struct Received {
    Bytes bytes;
    Error error = Error::none;
    Message message;
};

/// A minimal host: sends frames to the emulator and decodes what comes back.
class Host {
  public:
    explicit Host(DeviceEmulator& device) : device_(device) {}

    std::vector<Received> send_bytes(std::span<const std::byte> frame) {
        std::array<std::byte, DeviceEmulator::kMaxReplySize> out{};
        const DeviceEmulator::Reply reply = device_.handle(frame, out);
        std::vector<Received> received;
        std::size_t offset = 0;
        for (std::size_t i = 0; i < reply.frames; ++i) {
            Received r;
            r.bytes.assign(
                out.begin() + static_cast<std::ptrdiff_t>(offset),
                out.begin() + static_cast<std::ptrdiff_t>(offset + reply.frame_sizes[i]));
            offset += reply.frame_sizes[i];
            r.error = decode(r.bytes, r.message);
            received.push_back(std::move(r));
        }
        EXPECT_EQ(offset, reply.size);
        return received;
    }

    template <typename M>
    std::vector<Received> send(const M& message) {
        const Bytes frame = encoded(message);
        EXPECT_FALSE(frame.empty());
        return send_bytes(frame);
    }

    /// Sends and expects exactly one well-formed reply of type R.
    template <typename R, typename M>
    R ask(const M& message) {
        const std::vector<Received> received = send(message);
        EXPECT_EQ(received.size(), 1u);
        if (received.size() != 1 || received[0].error != Error::none ||
            !std::holds_alternative<R>(received[0].message)) {
            ADD_FAILURE() << "expected one " << typeid(R).name();
            return R{};
        }
        return std::get<R>(received[0].message);
    }

    /// Opens a session offering versions 1..max_version; later frames use the chosen one.
    Identity hello(std::uint32_t session = kSession, std::uint8_t max_version = kProtocolVersion1) {
        Hello hello;
        hello.session = session;
        hello.max_version = max_version;
        session_ = session;
        const Identity identity = ask<Identity>(hello);
        version_ = identity.version;
        tracker_.start(session, version_);
        return identity;
    }

    ForceCommand command_frame(const std::array<double, 3>& force_n, bool enable = true,
                               std::uint8_t extra_flags = 0) {
        servo::Command command;
        command.enable = enable;
        command.force_n = force_n;
        ForceCommand frame;
        EXPECT_TRUE(make_force_command(command, device_.identity().axes, session_, next_sequence_++,
                                       frame));
        frame.flags |= extra_flags;
        frame.version = version_;
        return frame;
    }

    EncoderSample command(const std::array<double, 3>& force_n, bool enable = true,
                          std::uint8_t extra_flags = 0) {
        const ForceCommand frame = command_frame(force_n, enable, extra_flags);
        tracker_.command_sent(frame.sequence);
        return ask<EncoderSample>(frame);
    }

    EncoderSample poll() {
        Poll poll;
        poll.session = session_;
        poll.version = version_;
        return ask<EncoderSample>(poll);
    }

    ReplyTracker& tracker() { return tracker_; }
    std::uint32_t session() const { return session_; }
    std::uint32_t& next_sequence() { return next_sequence_; }

  private:
    DeviceEmulator& device_;
    std::uint32_t session_ = 0;
    std::uint8_t version_ = kProtocolVersion1;
    std::uint32_t next_sequence_ = 1;
    ReplyTracker tracker_;
};

ErrorReport expect_error(const std::vector<Received>& received, ErrorCode code) {
    EXPECT_EQ(received.size(), 1u);
    if (received.size() != 1 || received[0].error != Error::none ||
        !std::holds_alternative<ErrorReport>(received[0].message)) {
        ADD_FAILURE() << "expected an error message " << to_string(code);
        return {};
    }
    const auto& report = std::get<ErrorReport>(received[0].message);
    EXPECT_EQ(report.code, code) << to_string(report.code);
    return report;
}

// ---- handshake ----

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
