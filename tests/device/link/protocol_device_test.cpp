// ProtocolDevice (link/protocol_device.hpp) over a loopback link into the reference device:
// the handshake and its refusals, the tick's exchange, every reply fault of section 5.3,
// device faults (5.5), disconnect and reconnect, and zero force on close.
#include "hapticd/device/link/protocol_device.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <thread>

#include "alloc_guard.hpp"
#include "hapticd/device/protocol/crc32c.hpp"
#include "hapticd/device/protocol/wire.hpp"
#include "loopback_link.hpp"

namespace hapticd::testing {
namespace {

using device::DeviceConfig;
using device::link::LinkContext;
using device::link::ProtocolDevice;
using servo::Command;
using servo::IoResult;
using servo::Sample;

proto::EmulatorConfig emulator_config(std::string serial = "EMU-0001", int axes = 1) {
    proto::EmulatorConfig c;
    c.sim.axes = axes;
    c.sim.rate_hz = 1000.0;
    c.sim.mass_kg = 0.1;
    c.sim.damping_n_s_per_m = 2.0;
    c.sim.counts_per_meter = 1e5;
    c.sim.force_limit_n = 10.0;
    c.serial_number = std::move(serial);
    return c;
}

DeviceConfig device_config(std::string table = "", int axes = 1, double rate_hz = 1000.0) {
    DeviceConfig c;
    c.axes = axes;
    c.rate_hz = rate_hz;
    c.lockstep = true;
    c.plugin_table_toml = std::move(table);
    c.source = "cfg.toml";
    return c;
}

class ProtocolDeviceTest : public ::testing::Test {
  protected:
    void SetUp() override {
        bench_.device = std::make_unique<proto::DeviceEmulator>(emulator_config());
    }

    std::unique_ptr<ProtocolDevice> make_device() {
        return std::make_unique<ProtocolDevice>("loop",
                                                [this](device::TableReader&, const LinkContext&) {
                                                    return std::make_unique<LoopbackLink>(bench_);
                                                });
    }

    /// Opens with a fast reconnect so that the reconnect tests do not wait long.
    std::unique_ptr<ProtocolDevice> open_device(const std::string& extra = "") {
        auto d = make_device();
        d->open(device_config("reconnect_interval_ms = 10\n" + extra));
        return d;
    }

    /// Ticks like the servo until `done(sample)` or `limit` reads; returns the reads made.
    template <typename Done>
    int tick_until(ProtocolDevice& d, Done done, int limit, Command command = Command{}) {
        for (int i = 1; i <= limit; ++i) {
            Sample s;
            const IoResult r = d.read(s);
            if (done(r, s)) return i;
            (void)d.write(command);
            std::this_thread::sleep_for(std::chrono::microseconds(200));
        }
        return -1;
    }

    LoopbackBench bench_;
};

TEST_F(ProtocolDeviceTest, HandshakeReportsTheDevicesIdentity) {
    auto d = open_device();
    const device::DeviceInfo info = d->info();
    EXPECT_EQ(info.axes, 1);
    EXPECT_DOUBLE_EQ(info.counts_per_meter, 1e5);
    EXPECT_DOUBLE_EQ(info.force_limit_n, 10.0);
    EXPECT_EQ(info.serial, "EMU-0001");
    EXPECT_EQ(info.name, "loop");
    EXPECT_TRUE(info.paces_loop);  // lockstep: one command = one virtual period
    EXPECT_TRUE(bench_.device->session_open());
    EXPECT_EQ(bench_.device->watchdog_timeout_us(), 20'000u);  // watchdog_ms default
}

TEST_F(ProtocolDeviceTest, EachCommandIsAnsweredByTheNextRead) {
    auto d = open_device();
    Sample s;
    ASSERT_EQ(d->read(s), IoResult::ok);  // a poll: no command yet
    const std::uint64_t first = s.sequence;
    Command push;
    push.enable = true;
    push.force_n[0] = 1.0;
    for (int tick = 1; tick <= 100; ++tick) {
        ASSERT_EQ(d->write(push), IoResult::ok);
        ASSERT_EQ(d->read(s), IoResult::ok);
        EXPECT_EQ(s.sequence, first + static_cast<std::uint64_t>(tick));
        EXPECT_EQ(s.status, 0u);
    }
    // 1 N held on m = 0.1 kg, b = 2 N s/m from rest for t = 0.1 s, (10) in closed form:
    // x = F/b (t - tau (1 - exp(-t/tau))), tau = m/b; counts = floor(x * 1e5).
    const double tau = 0.1 / 2.0;
    const double x = 1.0 / 2.0 * (0.1 - tau * (1.0 - std::exp(-0.1 / tau)));
    EXPECT_NEAR(static_cast<double>(s.encoder_counts[0]), std::floor(x * 1e5), 1.0);
    EXPECT_NEAR(s.device_time_s, 0.1, 1e-9);
    EXPECT_DOUBLE_EQ(bench_.device->output_force_n()[0], 1.0);
    EXPECT_EQ(d->counters().commands_sent, 100u);
    EXPECT_EQ(d->counters().polls_sent, 1u);
}

TEST_F(ProtocolDeviceTest, TicksDoNotAllocate) {
    auto d = open_device();
    Sample s;
    Command push;
    push.enable = true;
    push.force_n[0] = 0.2;
    AllocationGuard guard;
    for (int tick = 0; tick < 5000; ++tick) {
        (void)d->read(s);
        (void)d->write(push);
    }
    EXPECT_EQ(guard.allocations(), 0u);
    EXPECT_EQ(d->counters().samples_accepted, 5000u);
}

TEST_F(ProtocolDeviceTest, RefusesAnotherSerialNumberNamingTheKey) {
    auto d = make_device();
    try {
        d->open(device_config("serial_number = \"HX-0002\"\n"));
        FAIL() << "opened the wrong device";
    } catch (const std::runtime_error& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find("wrong device"), std::string::npos) << message;
        EXPECT_NE(message.find("device.loop.serial_number = \"HX-0002\""), std::string::npos)
            << message;
        EXPECT_NE(message.find("\"EMU-0001\""), std::string::npos) << message;
    }
    EXPECT_FALSE(bench_.device->session_open() && bench_.device->output_force_n()[0] != 0.0);
}

TEST_F(ProtocolDeviceTest, RefusesAxesAndRateThatDoNotMatchTheDevice) {
    auto d = make_device();
    try {
        d->open(device_config("", 2));
        FAIL() << "opened a 1-axis device as 2 axes";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("device.axes = 2"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("reports 1 axes"), std::string::npos) << e.what();
    }
    try {
        d->open(device_config("", 1, 500.0));
        FAIL() << "opened a 1 kHz device at 500 Hz";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("servo.rate_hz = 500"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("1000 us"), std::string::npos) << e.what();
    }
}

// A device whose identity holds a field out of range is named with that field, at once,
// not taken for a device that never answered ("no identity ... the right baud rate?").
TEST_F(ProtocolDeviceTest, AnIdentityOutOfRangeIsRefusedNamingItsField) {
    bench_.tamper = [](std::span<std::byte> frame) {
        if (frame[proto::kOffsetType] != static_cast<std::byte>(proto::MessageType::identity)) {
            return;
        }
        constexpr std::size_t kCountsPerMeter = proto::kHeaderSize + 8;
        proto::wire::store_f64(frame, kCountsPerMeter, std::nan(""));
        const std::size_t crc_offset = frame.size() - proto::kCrcSize;
        proto::wire::store_u32(frame, crc_offset, proto::crc32c(frame.first(crc_offset)));
    };
    auto d = make_device();
    try {
        d->open(device_config());
        FAIL() << "opened a device whose counts_per_meter is NaN";
    } catch (const std::runtime_error& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find("loopback sent an identity whose counts_per_meter = nan: allowed "
                               "finite and > 0 (encoder counts per metre) (docs/protocol.md 4.2)"),
                  std::string::npos)
            << message;
        EXPECT_EQ(message.find("baud"), std::string::npos) << message;
    }
}

TEST_F(ProtocolDeviceTest, BadKeysAreNamedWithTheirRange) {
    auto d = make_device();
    auto message_for = [&](const std::string& table) {
        try {
            d->open(device_config(table));
        } catch (const std::runtime_error& e) {
            return std::string(e.what());
        }
        return std::string("(opened)");
    };
    EXPECT_NE(
        message_for("watchdog_ms = 1\n").find("[device.loop] watchdog_ms = 1 is out of range"),
        std::string::npos);
    EXPECT_NE(message_for("watchdog_ms = 1\n").find(">= 2"), std::string::npos);
    EXPECT_NE(message_for("baud = 9600\n").find("[device.loop] baud = 9600 is not a known key"),
              std::string::npos);
    EXPECT_NE(message_for("serial_number = \"\"\n").find("1 to 16 printable ASCII"),
              std::string::npos);
    EXPECT_NE(message_for("reconnect = 1\n").find("true or false"), std::string::npos);
}

TEST_F(ProtocolDeviceTest, ConfiguresTheWatchdog) {
    auto d = open_device("watchdog_ms = 5\n");
    EXPECT_EQ(bench_.device->watchdog_timeout_us(), 5000u);
}

TEST_F(ProtocolDeviceTest, CorruptAndTruncatedRepliesAreDroppedSamples) {
    auto d = open_device();
    Sample s;
    ASSERT_EQ(d->read(s), IoResult::ok);
    ASSERT_EQ(d->write(Command{}), IoResult::ok);
    bench_.device->faults().corrupt_crc = 1;
    ASSERT_EQ(d->read(s), IoResult::ok);  // this reply was sent before the knob
    ASSERT_EQ(d->write(Command{}), IoResult::ok);
    EXPECT_EQ(d->read(s), IoResult::timeout);
    EXPECT_EQ(s.status, servo::kStatusDropped);
    bench_.device->faults().truncate = 1;
    ASSERT_EQ(d->write(Command{}), IoResult::ok);
    EXPECT_EQ(d->read(s), IoResult::timeout);
    EXPECT_EQ(d->counters().bad_frames, 2u);
    EXPECT_EQ(d->counters().reply_timeouts, 2u);
    ASSERT_EQ(d->write(Command{}), IoResult::ok);
    EXPECT_EQ(d->read(s), IoResult::ok);  // and the link goes on
}

TEST_F(ProtocolDeviceTest, ReplyOfAnotherSessionIsIgnored) {
    auto d = open_device();
    Sample s;
    ASSERT_EQ(d->read(s), IoResult::ok);
    bench_.device->faults().wrong_session = 1;
    ASSERT_EQ(d->write(Command{}), IoResult::ok);
    EXPECT_EQ(d->read(s), IoResult::timeout);
    EXPECT_EQ(d->counters().wrong_session, 1u);
}

TEST_F(ProtocolDeviceTest, SequenceGapAdvancesTheSampleSequence) {
    auto d = open_device();
    Sample s;
    ASSERT_EQ(d->read(s), IoResult::ok);
    const std::uint64_t before = s.sequence;
    bench_.device->faults().sequence_gap = 4;
    ASSERT_EQ(d->write(Command{}), IoResult::ok);
    ASSERT_EQ(d->read(s), IoResult::ok);
    EXPECT_EQ(s.sequence, before + 5);  // one period + 4 lost samples
    EXPECT_EQ(d->counters().missed_samples, 4u);
}

TEST_F(ProtocolDeviceTest, ADelayedReplyIsLateAndFlagged) {
    auto d = open_device();
    Sample s;
    ASSERT_EQ(d->read(s), IoResult::ok);
    bench_.device->faults().delay = 1;
    ASSERT_EQ(d->write(Command{}), IoResult::ok);
    EXPECT_EQ(d->read(s), IoResult::timeout);  // held back by the device
    ASSERT_EQ(d->write(Command{}), IoResult::ok);
    ASSERT_EQ(d->read(s), IoResult::ok);  // the old reply is discarded, this one is used
    EXPECT_NE(s.status & servo::kStatusLate, 0u);
    EXPECT_EQ(d->counters().late, 1u);
}

TEST_F(ProtocolDeviceTest, DeviceFaultsAreReportedAndClearedOnlyWhenForceIsWantedAgain) {
    auto d = open_device();
    Sample s;
    ASSERT_EQ(d->read(s), IoResult::ok);
    bench_.device->faults().device_faults = proto::kDeviceFaultAmplifier;
    Command push;
    push.enable = true;
    push.force_n[0] = 1.0;
    ASSERT_EQ(d->write(push), IoResult::ok);
    ASSERT_EQ(d->read(s), IoResult::ok);
    EXPECT_NE(s.status & servo::kStatusDeviceFault, 0u);
    EXPECT_EQ(bench_.device->output_force_n()[0], 0.0);
    // The servo's latch now sends disabled commands: the device stays faulted.
    ASSERT_EQ(d->write(Command{}), IoResult::ok);
    ASSERT_EQ(d->read(s), IoResult::ok);
    EXPECT_NE(bench_.device->latched_faults(), 0u);
    // The operator reset the servo; it asks for force: one period clears, at zero force...
    ASSERT_EQ(d->write(push), IoResult::ok);
    EXPECT_EQ(bench_.device->latched_faults(), 0u);
    EXPECT_EQ(bench_.device->output_force_n()[0], 0.0);
    ASSERT_EQ(d->read(s), IoResult::ok);
    EXPECT_EQ(s.status & servo::kStatusDeviceFault, 0u);
    // ...and the next command applies it.
    ASSERT_EQ(d->write(push), IoResult::ok);
    EXPECT_DOUBLE_EQ(bench_.device->output_force_n()[0], 1.0);
}

TEST_F(ProtocolDeviceTest, ReconnectsToTheSameDeviceWhenItReturns) {
    auto d = open_device();
    Sample s;
    ASSERT_EQ(d->read(s), IoResult::ok);
    bench_.present = false;
    Command push;
    push.enable = true;
    push.force_n[0] = 1.0;
    EXPECT_EQ(d->write(push), IoResult::disconnected);
    EXPECT_EQ(d->read(s), IoResult::disconnected);
    EXPECT_NE(s.status & servo::kStatusDisconnected, 0u);
    EXPECT_EQ(d->counters().disconnects, 1u);

    // The same device comes back (restarted: a fresh emulator with the same serial).
    bench_.device = std::make_unique<proto::DeviceEmulator>(emulator_config());
    bench_.present = true;
    const int reads = tick_until(
        *d, [](IoResult r, const Sample&) { return r == IoResult::ok; }, 5000);
    ASSERT_GT(reads, 0) << "never reconnected";
    EXPECT_EQ(d->counters().reconnects, 1u);
    EXPECT_TRUE(bench_.device->session_open());
    ASSERT_EQ(d->write(push), IoResult::ok);
    EXPECT_DOUBLE_EQ(bench_.device->output_force_n()[0], 1.0);
}

TEST_F(ProtocolDeviceTest, RefusesAnotherDeviceOnReconnect) {
    auto d = open_device();
    Sample s;
    ASSERT_EQ(d->read(s), IoResult::ok);
    bench_.present = false;
    EXPECT_EQ(d->read(s), IoResult::disconnected);
    bench_.device = std::make_unique<proto::DeviceEmulator>(emulator_config("EMU-OTHER"));
    bench_.present = true;
    const int reads = tick_until(
        *d, [&](IoResult, const Sample&) { return d->counters().refused_devices >= 2; }, 5000);
    ASSERT_GT(reads, 0) << "the other device was never tried";
    EXPECT_EQ(d->read(s), IoResult::disconnected);
    EXPECT_EQ(d->counters().reconnects, 0u);
    d->close();  // stops the reconnect thread before the test looks at the device
    EXPECT_EQ(bench_.device->output_force_n()[0], 0.0);
}

TEST_F(ProtocolDeviceTest, AReplyFromADeviceThatLostTheSessionStartsANewHandshake) {
    auto d = open_device();
    Sample s;
    ASSERT_EQ(d->read(s), IoResult::ok);
    // The device restarts behind the link's back: it no longer knows the session.
    bench_.device = std::make_unique<proto::DeviceEmulator>(emulator_config());
    ASSERT_EQ(d->write(Command{}), IoResult::ok);
    EXPECT_EQ(d->read(s), IoResult::disconnected);
    const int reads = tick_until(
        *d, [](IoResult r, const Sample&) { return r == IoResult::ok; }, 5000);
    EXPECT_GT(reads, 0);
    EXPECT_EQ(d->counters().device_errors, 1u);
}

// A sample_sequence that jumped ahead past the CRC (or a firmware that restarted its count)
// puts the host ahead of the device: every later sample looks like a repeat and is refused,
// although the device answers every command. Three such reads in a row end the session as a
// lost device, and the reconnect thread starts a new one. (The serial fault campaign found
// the link stuck for good with the device answering: seed 193.)
TEST_F(ProtocolDeviceTest, AHostAheadOfTheDevicesSequenceStartsANewSession) {
    auto d = open_device();
    Sample s;
    ASSERT_EQ(d->read(s), IoResult::ok);
    ASSERT_EQ(d->write(Command{}), IoResult::ok);
    ASSERT_EQ(d->read(s), IoResult::ok);
    bench_.device->faults().sequence_ahead = 100'000;
    ASSERT_EQ(d->write(Command{}), IoResult::ok);
    ASSERT_EQ(d->read(s), IoResult::ok);  // taken: a gap, as far as any host can tell
    for (int n = 0; n < 2; ++n) {
        ASSERT_EQ(d->write(Command{}), IoResult::ok);
        EXPECT_EQ(d->read(s), IoResult::timeout);  // answered, but behind the host: refused
    }
    ASSERT_EQ(d->write(Command{}), IoResult::ok);
    EXPECT_EQ(d->read(s), IoResult::disconnected);
    EXPECT_NE(s.status & servo::kStatusDisconnected, 0u);
    EXPECT_EQ(d->counters().out_of_step, 1u);
    EXPECT_EQ(d->counters().duplicate, 3u);
    const int reads = tick_until(
        *d, [](IoResult r, const Sample&) { return r == IoResult::ok; }, 5000);
    EXPECT_GT(reads, 0) << "never reconnected";
    EXPECT_EQ(d->counters().reconnects, 1u);
}

// Device::link_quality(): the operator's view of counters() and the link's own counts.
TEST_F(ProtocolDeviceTest, LinkQualityReflectsTheCounters) {
    LoopbackLink* link = nullptr;
    ProtocolDevice d("loop", [&](device::TableReader&, const LinkContext&) {
        auto made = std::make_unique<LoopbackLink>(bench_);
        link = made.get();
        return made;
    });
    d.open(device_config("reconnect_interval_ms = 10\n"));
    ASSERT_NE(link, nullptr);
    Sample s;
    ASSERT_EQ(d.read(s), IoResult::ok);
    const device::LinkQuality clean = d.link_quality();
    EXPECT_TRUE(clean.counted);
    EXPECT_EQ(clean.bad_frames, 0u);
    EXPECT_EQ(clean.reply_timeouts, 0u);
    EXPECT_GT(clean.frames_sent, 0u);  // the handshake's and the poll

    auto tick = [&] {
        EXPECT_EQ(d.write(Command{}), IoResult::ok);
        return d.read(s);
    };
    ASSERT_EQ(tick(), IoResult::ok);
    bench_.device->faults().corrupt_crc = 1;  // the answer to the next write
    EXPECT_EQ(tick(), IoResult::timeout);
    bench_.device->faults().truncate = 1;
    EXPECT_EQ(tick(), IoResult::timeout);
    bench_.device->faults().sequence_gap = 4;
    ASSERT_EQ(tick(), IoResult::ok);
    bench_.device->faults().delay = 1;
    EXPECT_EQ(tick(), IoResult::timeout);
    ASSERT_EQ(tick(), IoResult::ok);  // the held-back reply is late and dropped
    link->count_framing_error();      // transport garbage counts as a bad frame too

    const device::LinkQuality q = d.link_quality();
    const device::link::ProtocolCounters c = d.counters();
    const device::link::LinkCounters l = link->counters();
    EXPECT_TRUE(q.counted);
    EXPECT_EQ(q.frames_sent, l.frames_sent);
    EXPECT_EQ(q.frames_received, l.frames_received);
    EXPECT_EQ(q.frames_sent, clean.frames_sent + 6u);
    EXPECT_EQ(q.bad_frames, 3u);  // CRC, truncated, one framing error
    EXPECT_EQ(q.bad_frames, c.bad_frames + l.framing_errors);
    EXPECT_EQ(q.transfer_errors, 0u);
    EXPECT_EQ(q.reply_timeouts, 3u);
    EXPECT_EQ(q.reply_timeouts, c.reply_timeouts);
    EXPECT_GE(q.missed_samples, 6u);  // the gap's 4, and each lost reply's sample
    EXPECT_EQ(q.missed_samples, c.missed_samples);
    EXPECT_EQ(q.late, 1u);
    EXPECT_EQ(q.late, c.late);
    EXPECT_EQ(q.duplicate, c.duplicate);
    EXPECT_EQ(q.device_errors, 0u);
    EXPECT_EQ(q.disconnects, 0u);
    EXPECT_EQ(q.reconnects, 0u);
    EXPECT_EQ(q.wrong_session, 0u);
    EXPECT_EQ(q.unexpected, c.unexpected);
    EXPECT_EQ(q.out_of_step, 0u);

    // A reply of another session: dropped, and counted as such.
    bench_.device->faults().wrong_session = 1;
    tick();
    const device::LinkQuality w = d.link_quality();
    EXPECT_EQ(w.wrong_session, 1u);
    EXPECT_EQ(w.wrong_session, d.counters().wrong_session);
    EXPECT_EQ(w.unexpected, d.counters().unexpected);
    EXPECT_EQ(w.out_of_step, d.counters().out_of_step);
    ASSERT_EQ(tick(), IoResult::ok);

    // A lost device and its return.
    bench_.present = false;
    EXPECT_EQ(d.read(s), IoResult::disconnected);
    bench_.device = std::make_unique<proto::DeviceEmulator>(emulator_config());
    bench_.present = true;
    ASSERT_GT(tick_until(
                  d, [](IoResult r, const Sample&) { return r == IoResult::ok; }, 5000),
              0);
    EXPECT_EQ(d.link_quality().disconnects, 1u);
    EXPECT_EQ(d.link_quality().reconnects, 1u);
}

// The control socket's thread reads link_quality() while the servo thread ticks through
// reply faults, and while the reconnect thread shakes hands again: no data race (this
// executable runs under ThreadSanitizer, label `threads`), and no count ever goes back.
TEST_F(ProtocolDeviceTest, LinkQualityIsReadFromAnotherThreadWhileTheTickRuns) {
    auto d = open_device();
    std::atomic<bool> done{false};
    std::atomic<int> looks{0};
    std::atomic<int> went_back{0};
    std::thread reader([&] {
        device::LinkQuality last;
        while (!done.load()) {
            const device::LinkQuality q = d->link_quality();
            if (!q.counted || q.frames_sent < last.frames_sent ||
                q.frames_received < last.frames_received || q.bad_frames < last.bad_frames ||
                q.reply_timeouts < last.reply_timeouts || q.late < last.late ||
                q.missed_samples < last.missed_samples || q.disconnects < last.disconnects ||
                q.reconnects < last.reconnects) {
                went_back.fetch_add(1);
            }
            last = q;
            looks.fetch_add(1);
        }
    });
    Sample s;
    for (int i = 0; i < 3000; ++i) {
        if (i % 100 == 50) bench_.device->faults().corrupt_crc = 1;
        if (i % 100 == 75) bench_.device->faults().sequence_gap = 2;
        (void)d->read(s);
        (void)d->write(Command{});
    }
    // A disconnect: the reconnect thread's handshake writes the counts meanwhile.
    bench_.present = false;
    EXPECT_EQ(d->read(s), IoResult::disconnected);
    bench_.device = std::make_unique<proto::DeviceEmulator>(emulator_config());
    bench_.present = true;
    EXPECT_GT(tick_until(
                  *d, [](IoResult r, const Sample&) { return r == IoResult::ok; }, 5000),
              0);
    while (looks.load() < 100) std::this_thread::yield();
    done = true;
    reader.join();
    EXPECT_EQ(went_back.load(), 0);
    const device::LinkQuality q = d->link_quality();
    EXPECT_EQ(q.bad_frames, 30u);
    EXPECT_EQ(q.reply_timeouts, 30u);
    EXPECT_EQ(q.missed_samples, 90u);  // the gaps' 60, and each corrupted reply's sample
    EXPECT_EQ(q.disconnects, 1u);
    EXPECT_EQ(q.reconnects, 1u);
}

TEST_F(ProtocolDeviceTest, CloseLeavesZeroForceAndEndsTheSession) {
    auto d = open_device();
    Command push;
    push.enable = true;
    push.force_n[0] = 2.0;
    Sample s;
    ASSERT_EQ(d->read(s), IoResult::ok);
    ASSERT_EQ(d->write(push), IoResult::ok);
    ASSERT_DOUBLE_EQ(bench_.device->output_force_n()[0], 2.0);
    const std::uint64_t commands = d->counters().commands_sent;
    d->close();
    EXPECT_EQ(d->counters().commands_sent, commands + 1);  // a zero-force command, then bye
    EXPECT_EQ(bench_.device->output_force_n()[0], 0.0);
    EXPECT_FALSE(bench_.device->session_open());
    d->close();  // twice is fine
}

}  // namespace
}  // namespace hapticd::testing
