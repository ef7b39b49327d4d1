// UsbDeviceTest: the `usb` plugin as the daemon uses it: ProtocolDevice over UsbLink, through
// unmodified libusb, against devices that umockdev emulates (usb_testbed.hpp). The first test
// loads the plugin by name like hapticd does; the others build the same ProtocolDevice("usb",
// make_usb_link) in-process, to read its counters.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <thread>

#include "alloc_guard.hpp"
#include "hapticd/device/link/protocol_device.hpp"
#include "hapticd/device/plugin_loader.hpp"
#include "hapticd/device/usb/make_usb_link.hpp"
#include "libusb_allocations.hpp"
#include "usb_testbed.hpp"

namespace hapticd::device::usb {
namespace {

using link::ProtocolDevice;
using servo::kStatusDisconnected;
using servo::kStatusDropped;
using servo::kStatusLate;
using testing::EmulatedUsbDevice;
using testing::UsbDeviceSpec;
using testing::UsbTestbed;

constexpr const char* kSource = "usb-device-test.toml";

DeviceConfig config_with(const std::string& table) {
    DeviceConfig config;
    config.axes = 1;
    config.rate_hz = 1000.0;
    config.lockstep = true;
    config.plugin_table_toml = table;
    config.source = kSource;
    return config;
}

/// Quick reconnects, and a reply timeout short enough that the provoked timeouts take little
/// time, long enough that no reply misses it on a loaded 2-core VM (a round trip through the
/// emulation takes about 1 ms).
constexpr double kReplyTimeoutS = 0.2;
const std::string kFastTable =
    "serial_number = \"EMU-0001\"\nreply_timeout_ms = 200.0\nreconnect_interval_ms = 20.0\n";

UsbDeviceSpec spec_for(const std::string& serial = "EMU-0001") {
    UsbDeviceSpec spec;
    spec.emulator = testing::pen_display_emulator(serial);
    return spec;
}

double elapsed_s(std::chrono::steady_clock::time_point since) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

/// One servo tick as the loop does it: read the sample, then write the command.
struct Tick {
    IoResult read = IoResult::error;
    IoResult write = IoResult::error;
    Sample sample;
};

Tick tick(Device& device, double force_n = 0.0) {
    Tick t;
    t.read = device.read(t.sample);
    Command command;
    command.force_n[0] = force_n;
    command.enable = force_n != 0.0;
    t.write = device.write(command);
    return t;
}

/// Ticks until a read is ok again (the reconnect thread has adopted the device); false after
/// `timeout_s` (generous: a loaded 2-core VM).
bool ticks_until_ok(Device& device, double timeout_s = 10.0) {
    const auto start = std::chrono::steady_clock::now();
    while (elapsed_s(start) < timeout_s) {
        if (tick(device).read == IoResult::ok) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return false;
}

/// Ticks until one reports the device lost; `ticks` counts them (at most 3). After a stall the
/// reply already received is still delivered, so that takes two.
Tick tick_until_lost(Device& device, int& ticks) {
    Tick t;
    for (ticks = 1; ticks <= 3; ++ticks) {
        t = tick(device, 0.5);
        if (t.read != IoResult::ok || t.write != IoResult::ok) break;
    }
    return t;
}

std::string open_error(Device& device, const DeviceConfig& config) {
    try {
        device.open(config);
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return "";
}

class UsbDeviceTest : public ::testing::Test {
  protected:
    UsbTestbed testbed_;
    ProtocolDevice device_{"usb", make_usb_link};
};

TEST(UsbPluginTest, LoadedByNameRunsLockstepTicksWithoutAllocation) {
    UsbTestbed testbed;
    EmulatedUsbDevice& emulated = testbed.add(spec_for());
    DeviceHandle device = load_device("usb");
    device->open(config_with("serial_number = \"EMU-0001\"\n"));
    const DeviceInfo info = device->info();
    EXPECT_EQ(info.name, "usb");
    EXPECT_EQ(info.serial, "EMU-0001");
    EXPECT_EQ(info.axes, 1);
    EXPECT_EQ(info.counts_per_meter, 1e5);
    EXPECT_EQ(info.force_limit_n, 20.0);
    EXPECT_TRUE(info.paces_loop);

    // 2000 lockstep ticks (2 s of device time) with 1 N on the handle: m dv/dt + b v = F (10).
    constexpr int kTicks = 2000;
    int ok = 0;
    bool consecutive = true;
    std::uint64_t last_sequence = 0;
    {
        hapticd::testing::AllocationGuard guard;
        for (int i = 0; i < kTicks; ++i) {
            const Tick t = tick(*device, 1.0);
            if (t.read == IoResult::ok && t.write == IoResult::ok) ++ok;
            if (i > 0 && t.sample.sequence != last_sequence + 1) consecutive = false;
            last_sequence = t.sample.sequence;
        }
        // Each tick submits one OUT and one IN transfer; the first read polls (one more OUT).
        EXPECT_EQ(guard.allocations(), hapticd::testing::libusb_urb_allocations(2 * kTicks + 1));
    }
    EXPECT_EQ(ok, kTicks);
    EXPECT_TRUE(consecutive);

    // The answer to the last command: the handle moved as (10) says. From rest under a held
    // 1 N: x(t) = (F/b) (t - (m/b)(1 - e^{-bt/m})) = 0.5 (2 - 0.05) = 0.975 m at t = 2 s.
    Sample last;
    ASSERT_EQ(device->read(last), IoResult::ok);
    const double x_m = static_cast<double>(last.encoder_counts[0]) / 1e5;
    EXPECT_NEAR(x_m, 0.975, 0.001);
    EXPECT_NEAR(last.device_time_s, 2.0, 1e-9);
    EXPECT_EQ(emulated.with_emulator([](auto& e) { return e.counters().commands_applied; }),
              static_cast<std::uint64_t>(kTicks));

    // close(): zero force, bye; the device holds zero and has no session.
    device->close();
    EXPECT_FALSE(emulated.with_emulator([](auto& e) { return e.session_open(); }));
    EXPECT_EQ(emulated.with_emulator([](auto& e) { return e.output_force_n()[0]; }), 0.0);
}

TEST_F(UsbDeviceTest, UnplugIsADisconnectAndTheDeviceIsAdoptedWhenItReturns) {
    EmulatedUsbDevice& emulated = testbed_.add(spec_for());
    device_.open(config_with(kFastTable));
    for (int i = 0; i < 50; ++i) ASSERT_EQ(tick(device_, 0.5).read, IoResult::ok);

    testbed_.unplug(emulated);
    // The next read finds the device gone (the IN transfer cannot be resubmitted: ENODEV)
    // and says so in this very tick, before a force is computed: the servo zeroes it.
    int ticks = 0;
    const Tick lost = tick_until_lost(device_, ticks);
    EXPECT_EQ(ticks, 1);
    EXPECT_EQ(lost.read, IoResult::disconnected);
    EXPECT_EQ(lost.sample.status, kStatusDisconnected | kStatusDropped);
    EXPECT_EQ(lost.write, IoResult::disconnected);
    // Gone for a while: every tick says so, at once (no waiting in the tick).
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < 100; ++i) EXPECT_EQ(tick(device_).read, IoResult::disconnected);
    EXPECT_LT(elapsed_s(start), 1.0);

    testbed_.replug(emulated);  // a new device address, a fresh firmware (no session)
    ASSERT_TRUE(ticks_until_ok(device_));
    for (int i = 0; i < 50; ++i) EXPECT_EQ(tick(device_, 0.5).read, IoResult::ok);
    const link::ProtocolCounters counters = device_.counters();
    EXPECT_EQ(counters.disconnects, 1u);
    EXPECT_EQ(counters.reconnects, 1u);
    EXPECT_EQ(device_.link()->counters().reopens, 1u);
    EXPECT_NE(device_.link()->describe().find("(bus 1 device 3)"), std::string::npos)
        << device_.link()->describe();
    EXPECT_TRUE(emulated.with_emulator([](auto& e) { return e.session_open(); }));
}

TEST_F(UsbDeviceTest, EndpointStallIsADisconnectAndTheReopenClearsIt) {
    EmulatedUsbDevice& emulated = testbed_.add(spec_for());
    device_.open(config_with(kFastTable));
    for (int i = 0; i < 10; ++i) ASSERT_EQ(tick(device_).read, IoResult::ok);
    emulated.stall_in();
    // The reply already received is read; the next IN transfer stalls.
    int ticks = 0;
    const Tick stalled = tick_until_lost(device_, ticks);
    EXPECT_EQ(ticks, 2);
    EXPECT_EQ(stalled.read, IoResult::disconnected);
    EXPECT_EQ(stalled.sample.status, kStatusDisconnected | kStatusDropped);
    EXPECT_EQ(stalled.write, IoResult::disconnected);
    ASSERT_TRUE(ticks_until_ok(device_));  // the reconnect thread's open() cleared the halt
    EXPECT_FALSE(emulated.in_halted());
    EXPECT_EQ(device_.link()->counters().stalls, 1u);
    EXPECT_EQ(device_.link()->counters().reopens, 1u);
    EXPECT_EQ(device_.counters().reconnects, 1u);
}

TEST_F(UsbDeviceTest, DroppedReplyIsATimeoutThenASequenceGap) {
    EmulatedUsbDevice& emulated = testbed_.add(spec_for());
    device_.open(config_with(kFastTable));
    Tick t;
    for (int i = 0; i < 10; ++i) ASSERT_EQ((t = tick(device_)).read, IoResult::ok);
    const std::uint64_t before = t.sample.sequence;
    emulated.with_emulator([](auto& e) { e.faults().drop = 1; });
    ASSERT_EQ(tick(device_).read, IoResult::ok);  // its command's reply is the one dropped
    const auto start = std::chrono::steady_clock::now();
    const Tick dropped = tick(device_);
    EXPECT_EQ(dropped.read, IoResult::timeout);
    EXPECT_EQ(dropped.sample.status, kStatusDropped);
    EXPECT_GE(elapsed_s(start), kReplyTimeoutS);
    const Tick after = tick(device_);
    ASSERT_EQ(after.read, IoResult::ok);
    EXPECT_EQ(after.sample.sequence, before + 3);  // 1 ok, 1 lost, this one
    EXPECT_EQ(device_.counters().missed_samples, 1u);
    EXPECT_EQ(device_.counters().reply_timeouts, 1u);
}

TEST_F(UsbDeviceTest, BrokenAndForeignFramesAreSkipped) {
    EmulatedUsbDevice& emulated = testbed_.add(spec_for());
    device_.open(config_with(kFastTable));
    for (int i = 0; i < 5; ++i) ASSERT_EQ(tick(device_).read, IoResult::ok);

    // Each knob spoils the reply to the next command: that tick's read times out.
    emulated.with_emulator([](auto& e) { e.faults().corrupt_crc = 1; });
    ASSERT_EQ(tick(device_).read, IoResult::ok);
    EXPECT_EQ(tick(device_).read, IoResult::timeout);
    EXPECT_EQ(device_.counters().bad_frames, 1u);

    emulated.with_emulator([](auto& e) { e.faults().truncate = 1; });
    ASSERT_EQ(tick(device_).read, IoResult::ok);
    EXPECT_EQ(tick(device_).read, IoResult::timeout);
    EXPECT_EQ(device_.counters().bad_frames, 2u);

    emulated.with_emulator([](auto& e) { e.faults().wrong_session = 1; });
    ASSERT_EQ(tick(device_).read, IoResult::ok);
    EXPECT_EQ(tick(device_).read, IoResult::timeout);
    EXPECT_EQ(device_.counters().wrong_session, 1u);

    for (int i = 0; i < 5; ++i) EXPECT_EQ(tick(device_).read, IoResult::ok);
    EXPECT_EQ(device_.link()->counters().framing_errors, 0u);  // they were whole transfers
}

TEST_F(UsbDeviceTest, SequenceGapAndLateReply) {
    EmulatedUsbDevice& emulated = testbed_.add(spec_for());
    device_.open(config_with(kFastTable));
    Tick t;
    for (int i = 0; i < 5; ++i) ASSERT_EQ((t = tick(device_)).read, IoResult::ok);
    emulated.with_emulator([](auto& e) { e.faults().sequence_gap = 3; });
    ASSERT_EQ(tick(device_).read, IoResult::ok);
    const Tick gap = tick(device_);
    ASSERT_EQ(gap.read, IoResult::ok);
    EXPECT_EQ(gap.sample.sequence, t.sample.sequence + 5);  // 1, then 1 + 3 skipped
    EXPECT_EQ(device_.counters().missed_samples, 3u);

    // A reply held back comes in front of the next one: dropped as late, flagged.
    emulated.with_emulator([](auto& e) { e.faults().delay = 1; });
    ASSERT_EQ(tick(device_).read, IoResult::ok);
    EXPECT_EQ(tick(device_).read, IoResult::timeout);
    const Tick late = tick(device_);
    ASSERT_EQ(late.read, IoResult::ok);
    EXPECT_NE(late.sample.status & kStatusLate, 0u);
    EXPECT_EQ(device_.counters().late, 1u);
}

TEST_F(UsbDeviceTest, AnotherDeviceIsRefused) {
    // A device that does not report its serial number over USB: the handshake names it.
    UsbDeviceSpec quiet = spec_for("EMU-0001");
    quiet.usb_serial = "";
    testbed_.add(quiet);
    const std::string message = open_error(device_, config_with("serial_number = \"EMU-0002\"\n"));
    EXPECT_NE(message.find("wrong device"), std::string::npos) << message;
    EXPECT_NE(message.find("\"EMU-0001\""), std::string::npos) << message;
    EXPECT_NE(message.find("usb-device-test.toml: device.usb.serial_number = \"EMU-0002\""),
              std::string::npos)
        << message;
}

TEST_F(UsbDeviceTest, OnlyTheSameDeviceIsAdoptedOnReconnect) {
    EmulatedUsbDevice& first = testbed_.add(spec_for("EMU-0001"));
    // No serial number configured: the first device seen is the one the run stays with.
    device_.open(config_with("reply_timeout_ms = 200.0\nreconnect_interval_ms = 20.0\n"));
    ASSERT_EQ(device_.info().serial, "EMU-0001");
    ASSERT_EQ(tick(device_).read, IoResult::ok);
    testbed_.unplug(first);
    int ticks = 0;
    EXPECT_EQ(tick_until_lost(device_, ticks).write, IoResult::disconnected);

    UsbDeviceSpec other = spec_for("EMU-0003");
    other.usb_serial = "";  // nothing tells it apart before the handshake
    EmulatedUsbDevice& stranger = testbed_.add(other);
    const auto start = std::chrono::steady_clock::now();
    while (device_.counters().refused_devices == 0 && elapsed_s(start) < 10.0) {
        EXPECT_EQ(tick(device_).read, IoResult::disconnected);
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    EXPECT_GE(device_.counters().refused_devices, 1u);

    testbed_.unplug(stranger);
    testbed_.replug(first);
    ASSERT_TRUE(ticks_until_ok(device_));
    EXPECT_EQ(device_.link()->describe().find("EMU-0003"), std::string::npos);
    EXPECT_TRUE(first.with_emulator([](auto& e) { return e.session_open(); }));
}

TEST_F(UsbDeviceTest, ConfigurationErrorsNameTheKey) {
    // Checked before the bus is touched: no device needed.
    const std::string vid = open_error(device_, config_with("vid = 0x12345\n"));
    EXPECT_NE(vid.find("usb-device-test.toml"), std::string::npos) << vid;
    EXPECT_NE(vid.find("[device.usb] vid"), std::string::npos) << vid;
    const std::string unknown = open_error(device_, config_with("product = 1\n"));
    EXPECT_NE(unknown.find("[device.usb] product"), std::string::npos) << unknown;
    EXPECT_NE(unknown.find("docs/transport-usb.md"), std::string::npos) << unknown;

    const std::string missing = open_error(device_, config_with("pid = 0x0002\n"));
    EXPECT_NE(missing.find("no device 1209:0002"), std::string::npos) << missing;
    EXPECT_NE(missing.find("no USB devices at all"), std::string::npos) << missing;
}

}  // namespace
}  // namespace hapticd::device::usb
