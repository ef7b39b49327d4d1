// The `hid` plugin as the daemon gets it: loaded by name (plugin_loader.hpp), a
// ProtocolDevice over HidLink, through the real hidapi hidraw backend to the reference device
// behind an emulated hidraw node (emulated_hid_device.hpp). Lockstep ticks without
// allocation (neither operator new nor malloc, so hidapi's included); every reply fault of
// docs/protocol.md 5.3 seen as the servo sees it, and the loop going on; the device unplugged (lost
// in that tick) and replugged (adopted again); bad configuration named by key.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <stdexcept>
#include <string>
#include <thread>

#include "alloc_guard.hpp"
#include "emulated_hid_device.hpp"
#include "hapticd/device/link/frame_link.hpp"
#include "hapticd/device/plugin_loader.hpp"
#include "malloc_count.hpp"

namespace hapticd::testing {
namespace {

using device::DeviceConfig;
using device::DeviceHandle;
using servo::Command;
using servo::IoResult;
using servo::Sample;

constexpr std::int64_t kGenerousNs = 10'000'000'000;  ///< a loaded 2-core VM

/// The device's configuration for the node: its ids, a handshake that waits as generously
/// as the tests do (each step waits for a reply that comes; on a loaded machine the emulated
/// node's round trip can outlast the 200 ms default: hid_device_server.hpp, "Timing"), and
/// `extra`.
DeviceConfig hid_config(const EmulatedHidDevice& emulated, const std::string& extra = "") {
    DeviceConfig c;
    c.axes = 1;
    c.rate_hz = 1000.0;
    c.lockstep = true;
    c.plugin_table_toml = emulated.table_toml() + "handshake_timeout_ms = 10000\n" + extra;
    c.source = "cfg.toml";
    return c;
}

Command push(double force_n) {
    Command c;
    c.enable = true;
    c.force_n[0] = force_n;
    return c;
}

/// One lockstep tick: a command, then the sample answering it.
struct Tick {
    IoResult write = IoResult::error;
    bool answered = false;  ///< the device answered the command within kGenerousNs
    IoResult read = IoResult::error;
    Sample sample;
};
/// The command; then, once the device has answered it (its reports, if any, are in the node),
/// the read. What the read returns is then the device's answer, whatever the emulation's
/// round trip takes under load: a reply in the node is found at once, and a read that
/// passes over it waits out its deadline for nothing (hid_device_server.hpp, "Timing").
/// Needs every earlier report answered: every tick here waits, and so does open().
/// Allocates nothing.
Tick answered_tick(device::Device& device, HidDeviceServer& server, const Command& command) {
    Tick t;
    const std::uint64_t reports = server.output_reports() + 1;
    t.write = device.write(command);
    t.answered = server.await_answered(reports, std::chrono::nanoseconds(kGenerousNs));
    t.read = device.read(t.sample);
    return t;
}

std::string open_error(const DeviceConfig& config) {
    DeviceHandle device = device::load_device("hid");
    try {
        device->open(config);
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return "<no error>";
}

TEST(HidDevice, LoadedByNameItRunsLockstepTicksWithoutAllocating) {
    EmulatedHidDevice emulated;
    DeviceHandle device = device::load_device("hid");
    const std::uint64_t mallocs_at_open = thread_malloc_count();
    device->open(hid_config(emulated));
    // open() may allocate, and hidapi's enumeration does: the counter sees C libraries.
    EXPECT_GT(thread_malloc_count(), mallocs_at_open + 10);
    const device::DeviceInfo info = device->info();
    EXPECT_EQ(info.name, "hid");
    EXPECT_EQ(info.serial, "EMU-0001");
    EXPECT_EQ(info.axes, 1);
    EXPECT_EQ(info.counts_per_meter, 1e5);
    EXPECT_EQ(info.force_limit_n, 20.0);
    EXPECT_TRUE(info.paces_loop);
    EXPECT_TRUE(info.lockstep);

    HidDeviceServer& server = emulated.server();
    for (int i = 0; i < 10; ++i) {
        ASSERT_EQ(answered_tick(*device, server, push(0.0)).read, IoResult::ok);
    }

    constexpr int kTicks = 2500;
    const Command command = push(0.2);  // 0.2 N on 0.1 kg with 2 N s/m: 0.1 m/s at rest
    int reads_ok = 0;
    int writes_ok = 0;
    int answered = 0;
    std::uint64_t first_sequence = 0;
    Sample last;
    std::uint64_t allocations = 0;
    std::uint64_t mallocs = 0;
    const std::int64_t start = device::link::monotonic_now_ns();
    {
        const std::uint64_t mallocs_before = thread_malloc_count();
        AllocationGuard guard;
        for (int i = 0; i < kTicks; ++i) {
            const Tick t = answered_tick(*device, server, command);
            writes_ok += t.write == IoResult::ok ? 1 : 0;
            answered += t.answered ? 1 : 0;
            reads_ok += t.read == IoResult::ok ? 1 : 0;
            if (i == 0) first_sequence = t.sample.sequence;
            last = t.sample;
        }
        allocations = guard.allocations();
        mallocs = thread_malloc_count() - mallocs_before;
    }
    const double elapsed_s = 1e-9 * static_cast<double>(device::link::monotonic_now_ns() - start);
    std::cout << "[hid] " << kTicks << " lockstep ticks through hidapi/umockdev in " << elapsed_s
              << " s (" << 1e6 * elapsed_s / kTicks << " us per tick)\n";

    EXPECT_EQ(allocations, 0u) << "operator new: ours";
    EXPECT_EQ(mallocs, 0u) << "malloc: hidapi's, libc's, libumockdev-preload's";
    EXPECT_EQ(writes_ok, kTicks);
    ASSERT_EQ(answered, kTicks) << "the emulated device did not answer within 10 s";
    EXPECT_EQ(reads_ok, kTicks);
    EXPECT_EQ(last.sequence - first_sequence, static_cast<std::uint64_t>(kTicks - 1));

    // The sample answering the last command is the reference device's own state, latched.
    const auto [position_m, time_us, held_n] = server.with_device([](auto& d) {
        return std::tuple(d.sim().plant(0).state().position_m, d.time_us(), d.output_force_n()[0]);
    });
    EXPECT_EQ(last.encoder_counts[0], static_cast<std::int64_t>(std::floor(position_m * 1e5)));
    EXPECT_DOUBLE_EQ(last.device_time_s, 1e-6 * static_cast<double>(time_us));
    EXPECT_DOUBLE_EQ(held_n, 0.2);
    // 2.5 s of 0.2 N: the handle coasts at F/b = 0.1 m/s, about 0.245 m from the start.
    EXPECT_NEAR(position_m, 0.1 * (2.51 - 0.05), 0.005);
    // close(): a command of zero force and a bye, which the device has handled once it has
    // answered them (close() waits for the bye's answer only so long).
    const std::uint64_t reports = server.output_reports() + 2;
    device->close();
    ASSERT_TRUE(server.await_answered(reports, std::chrono::nanoseconds(kGenerousNs)));
    EXPECT_DOUBLE_EQ(server.with_device([](auto& d) { return d.output_force_n()[0]; }), 0.0);
    EXPECT_FALSE(server.with_device([](auto& d) { return d.session_open(); }));
}

/// The reply to the next command misbehaves as `knob` says; what the servo sees.
class HidDeviceFaults : public ::testing::Test {
  protected:
    void SetUp() override {
        device_ = device::load_device("hid");
        // The reply timeout bounds only the reads that find no good reply: every read here
        // waits until the device has answered (answered_tick()).
        device_->open(hid_config(emulated_, "reply_timeout_ms = 300\n"));
        // Commands and their samples, ending on a sample: no reply is outstanding.
        for (int i = 0; i < 5; ++i) {
            const Tick t = answered_tick(*device_, emulated_.server(), push(0.1));
            ASSERT_TRUE(t.answered);
            ASSERT_EQ(t.write, IoResult::ok);
            ASSERT_EQ(t.read, IoResult::ok);
            last_ = t.sample;
        }
    }

    /// Sets a knob, then the next command's reply is the faulty one: returns that tick.
    template <typename Knob>
    Tick faulty_tick(Knob knob) {
        emulated_.server().with_device([&](auto& d) { knob(d.faults()); });
        const Tick t = answered_tick(*device_, emulated_.server(), push(0.1));
        EXPECT_TRUE(t.answered) << "the device did not handle the command within 10 s";
        return t;
    }
    /// A clean tick after it: the loop goes on.
    Tick next_tick() {
        const Tick t = answered_tick(*device_, emulated_.server(), push(0.1));
        EXPECT_TRUE(t.answered) << "the device did not answer within 10 s";
        return t;
    }

    EmulatedHidDevice emulated_;
    DeviceHandle device_;
    Sample last_;  ///< the last good sample before the fault
};

TEST_F(HidDeviceFaults, CorruptedCrcIsDroppedAndTheNextSampleCountsTheLoss) {
    const Tick bad = faulty_tick([](auto& f) { f.corrupt_crc = 1; });
    EXPECT_EQ(bad.read, IoResult::timeout);
    EXPECT_NE(bad.sample.status & servo::kStatusDropped, 0u);
    const Tick good = next_tick();
    ASSERT_EQ(good.read, IoResult::ok);
    EXPECT_EQ(good.sample.sequence, last_.sequence + 2) << "the corrupted sample was one sample";
}

TEST_F(HidDeviceFaults, ATruncatedFrameInAPaddedReportIsDropped) {
    const Tick bad = faulty_tick([](auto& f) { f.truncate = 1; });
    EXPECT_EQ(bad.read, IoResult::timeout);
    EXPECT_NE(bad.sample.status & servo::kStatusDropped, 0u);
    EXPECT_EQ(next_tick().read, IoResult::ok);
}

TEST_F(HidDeviceFaults, ASequenceGapShowsAsAJumpInTheSampleSequence) {
    const Tick gap = faulty_tick([](auto& f) { f.sequence_gap = 3; });
    ASSERT_EQ(gap.read, IoResult::ok);
    EXPECT_EQ(gap.sample.sequence, last_.sequence + 4);
    const Tick good = next_tick();
    ASSERT_EQ(good.read, IoResult::ok);
    EXPECT_EQ(good.sample.sequence, gap.sample.sequence + 1);
}

TEST_F(HidDeviceFaults, AReplyOfAnotherSessionIsIgnored) {
    const Tick bad = faulty_tick([](auto& f) { f.wrong_session = 1; });
    EXPECT_EQ(bad.read, IoResult::timeout);
    EXPECT_NE(bad.sample.status & servo::kStatusDropped, 0u);
    EXPECT_EQ(next_tick().read, IoResult::ok);
}

TEST_F(HidDeviceFaults, ADelayedReplyIsLateAndFlagged) {
    const Tick bad = faulty_tick([](auto& f) { f.delay = 1; });
    EXPECT_EQ(bad.read, IoResult::timeout);
    const Tick good = next_tick();  // the late reply arrives first and is passed over
    ASSERT_EQ(good.read, IoResult::ok);
    EXPECT_NE(good.sample.status & servo::kStatusLate, 0u);
}

TEST(HidDevice, UnpluggedItIsLostInThatTickAndAdoptedWhenItReturns) {
    EmulatedHidDevice emulated;
    DeviceHandle device = device::load_device("hid");
    device->open(hid_config(emulated, "reconnect_interval_ms = 20\n"));
    for (int i = 0; i < 20; ++i) {
        ASSERT_EQ(answered_tick(*device, emulated.server(), push(0.1)).read, IoResult::ok);
    }
    ASSERT_EQ(device->write(push(0.1)), IoResult::ok);  // its answer is what read() waits for

    emulated.unplug();
    Sample sample;
    EXPECT_EQ(device->read(sample), IoResult::disconnected);  // the reply that never comes
    EXPECT_NE(sample.status & servo::kStatusDisconnected, 0u);
    EXPECT_EQ(device->write(push(0.1)), IoResult::disconnected);
    // While it is away every tick says so at once.
    for (int i = 0; i < 10; ++i) {
        const std::int64_t start = device::link::monotonic_now_ns();
        EXPECT_EQ(device->read(sample), IoResult::disconnected);
        EXPECT_LT(device::link::monotonic_now_ns() - start, 100'000'000);
    }

    emulated.replug(1);  // power-cycled, and under another node
    const std::int64_t deadline = device::link::monotonic_now_ns() + kGenerousNs;
    IoResult result = IoResult::disconnected;
    while (result != IoResult::ok && device::link::monotonic_now_ns() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        result = device->read(sample);
    }
    ASSERT_EQ(result, IoResult::ok) << "not adopted again within 10 s";
    for (int i = 0; i < 100; ++i) {
        const Tick t = answered_tick(*device, emulated.server(), push(0.1));
        ASSERT_EQ(t.write, IoResult::ok) << "tick " << i;
        ASSERT_TRUE(t.answered) << "tick " << i;
        ASSERT_EQ(t.read, IoResult::ok) << "tick " << i;
    }
    // The replugged device (power-cycled: counting from zero) got every command since.
    EXPECT_TRUE(emulated.server().with_device([](auto& d) { return d.session_open(); }));
    EXPECT_EQ(emulated.server().with_device([](auto& d) { return d.counters().commands_applied; }),
              100u);
}

TEST(HidDevice, BadConfigurationNamesTheKey) {
    EmulatedHidDevice emulated;
    DeviceConfig config = hid_config(emulated);
    config.plugin_table_toml = "vid = 0x1209\npid = 70000\n";
    EXPECT_EQ(open_error(config),
              "cfg.toml:2: [device.hid] pid = 70000 is out of range: allowed 0..65535");
    config.plugin_table_toml = "vid = 0x1209\npid = 0x4841\nport = \"/dev/hidraw0\"\n";
    const std::string unknown = open_error(config);
    EXPECT_NE(unknown.find("cfg.toml:3: [device.hid] port = \"/dev/hidraw0\" is not a known key"),
              std::string::npos)
        << unknown;
    EXPECT_NE(unknown.find("docs/transport-hid.md"), std::string::npos) << unknown;
    config.plugin_table_toml = "pid = 0x4841\n";
    EXPECT_NE(open_error(config).find("[device.hid] vid is missing: required with pid"),
              std::string::npos);
}

TEST(HidDevice, NotFoundSaysWhatWasLookedForAndWhatIsThere) {
    EmulatedHidDevice emulated;
    DeviceConfig config = hid_config(emulated);
    config.plugin_table_toml = "vid = 0x1209\npid = 0x9999\n";
    const std::string ids = open_error(config);
    EXPECT_NE(ids.find("hid: no HID device 1209:9999"), std::string::npos) << ids;
    EXPECT_NE(ids.find("/dev/hidraw0 1209:4841 \"hapticd emulated device\" serial \"EMU-0001\""),
              std::string::npos)
        << ids;

    config.plugin_table_toml = emulated.table_toml() + "serial_number = \"HX-0002\"\n";
    const std::string serial = open_error(config);
    EXPECT_NE(serial.find("with serial number \"HX-0002\""), std::string::npos) << serial;
    EXPECT_NE(serial.find("these have other serial numbers"), std::string::npos) << serial;
}

}  // namespace
}  // namespace hapticd::testing
