// The `serial` plugin as the daemon uses it: loaded by name through the plugin loader, a
// Device over the pseudo-terminal with the reference device behind it, in lockstep. Ticks
// without allocation; every reply fault of docs/protocol.md 5.3 as the tick sees it; the
// master closing is `disconnected`, and the device coming back behind the same path is
// adopted by the reconnect thread; bad configuration names device.serial.<key>.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <iostream>
#include <stdexcept>
#include <thread>
#include <vector>

#include "alloc_guard.hpp"
#include "hapticd/device/plugin_loader.hpp"
#include "hapticd/servo/io.hpp"
#include "pty_device.hpp"
#include "scratch_dir.hpp"
#include "serial_test_util.hpp"

namespace hapticd::testing {
namespace {

using device::DeviceConfig;
using device::DeviceHandle;
using servo::Command;
using servo::IoResult;
using servo::Sample;
using ::testing::HasSubstr;
namespace proto = device::protocol;

/// [device.serial] for `port`: a short reply timeout (lockstep's default is 1 s, and the
/// fault tests wait for it) and a fast reconnect.
std::string serial_table(const std::string& port, const std::string& extra = "") {
    return "port = \"" + port + "\"\nreply_timeout_ms = 200\nreconnect_interval_ms = 20\n" + extra;
}

DeviceConfig device_config(const std::string& table) {
    DeviceConfig c;
    c.axes = 1;
    c.rate_hz = 1000.0;
    c.lockstep = true;
    c.plugin_table_toml = table;
    c.source = "test.toml";
    return c;
}

std::string open_error(const std::string& table) {
    DeviceHandle device = device::load_device("serial");
    try {
        device->open(device_config(table));
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return "";
}

Command push(double force_n) {
    Command c;
    c.enable = true;
    c.force_n[0] = force_n;
    return c;
}

class SerialDeviceTest : public ::testing::Test {
  protected:
    void SetUp() override {
        device_ = std::make_unique<PtyDevice>(emulator_config());
        handle_ = device::load_device("serial");
        handle_->open(device_config(serial_table(device_->port())));
    }
    void TearDown() override {
        if (handle_) handle_->close();
    }

    /// One servo tick in lockstep: the answer to the last command, then the next command.
    IoResult tick(Sample& sample, const Command& command = push(0.5)) {
        const IoResult result = handle_->read(sample);
        (void)handle_->write(command);
        return result;
    }

    std::unique_ptr<PtyDevice> device_;
    DeviceHandle handle_;
};

TEST(SerialPlugin, IsListedWithItsDescription) {
    const auto plugins = device::list_plugins();
    const auto serial = std::find_if(plugins.begin(), plugins.end(),
                                     [](const auto& p) { return p.name == "serial"; });
    ASSERT_NE(serial, plugins.end());
    EXPECT_EQ(serial->error, "");
    EXPECT_THAT(serial->description, HasSubstr("serial port"));
    EXPECT_THAT(serial->path, HasSubstr("hapticd-device-serial.so"));
}

TEST_F(SerialDeviceTest, OpensByNameAndReportsTheDevice) {
    const device::DeviceInfo info = handle_->info();
    EXPECT_EQ(info.name, "serial");
    EXPECT_EQ(info.serial, kEmulatorSerial);
    EXPECT_EQ(info.axes, 1);
    EXPECT_DOUBLE_EQ(info.counts_per_meter, 1e5);
    EXPECT_DOUBLE_EQ(info.force_limit_n, 20.0);
    EXPECT_TRUE(info.paces_loop);  // lockstep: each command is one virtual period
    device_->with_emulator([](proto::DeviceEmulator& e) {
        EXPECT_TRUE(e.session_open());
        EXPECT_EQ(e.watchdog_timeout_us(), 20'000u);  // configured by the handshake
    });
}

TEST_F(SerialDeviceTest, TicksInLockstepWithoutAllocating) {
    constexpr int kTicks = 2500;
    std::vector<std::int64_t> round_trip_ns;
    round_trip_ns.reserve(kTicks);
    Sample sample;
    ASSERT_EQ(handle_->read(sample), IoResult::ok);  // the first read polls
    std::uint64_t sequence = sample.sequence;
    int good = 0;
    int in_step = 0;
    {
        AllocationGuard guard;
        for (int i = 0; i < kTicks; ++i) {
            const std::int64_t sent = now_ns();
            if (handle_->write(push(i % 200 < 100 ? 0.5 : -0.5)) != IoResult::ok) break;
            if (handle_->read(sample) != IoResult::ok) break;
            round_trip_ns.push_back(now_ns() - sent);
            ++good;
            if (sample.sequence == sequence + 1 && sample.status == 0u) ++in_step;
            sequence = sample.sequence;
        }
        EXPECT_EQ(guard.allocations(), 0u);
    }
    EXPECT_EQ(good, kTicks);
    EXPECT_EQ(in_step, kTicks);  // one sample per command, no gaps, no status bits
    EXPECT_NEAR(sample.device_time_s, kTicks * 1e-3, 1e-9);  // virtual time: one period each
    device_->with_emulator([](proto::DeviceEmulator& e) {
        EXPECT_EQ(e.counters().commands_applied, static_cast<std::uint64_t>(kTicks));
        EXPECT_EQ(e.counters().dropped_requests, 0u);
        // The last command (i = 2499: +0.5 N), held (ZOH).
        EXPECT_DOUBLE_EQ(e.output_force_n()[0], (kTicks - 1) % 200 < 100 ? 0.5 : -0.5);
    });
    std::sort(round_trip_ns.begin(), round_trip_ns.end());
    if (!round_trip_ns.empty()) {
        const auto at = [&](double q) {
            return round_trip_ns[static_cast<std::size_t>(q * (round_trip_ns.size() - 1))] / 1e3;
        };
        std::cout << "[serial] pty round trip (write -> read, emulator thread): p50 " << at(0.5)
                  << " us, p99 " << at(0.99) << " us, max " << at(1.0) << " us over "
                  << round_trip_ns.size() << " ticks\n";
    }
}

TEST_F(SerialDeviceTest, ReplyFaultsAreDroppedSamplesAndTheNextTickRecovers) {
    Sample sample;
    for (int i = 0; i < 10; ++i) ASSERT_EQ(tick(sample), IoResult::ok);

    struct Case {
        const char* name;
        void (*arm)(proto::EmulatorFaults&);
    };
    const Case cases[] = {
        {"corrupt_crc", [](proto::EmulatorFaults& f) { f.corrupt_crc = 1; }},
        {"truncate", [](proto::EmulatorFaults& f) { f.truncate = 1; }},
        {"wrong_session", [](proto::EmulatorFaults& f) { f.wrong_session = 1; }},
        {"drop", [](proto::EmulatorFaults& f) { f.drop = 1; }},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        ASSERT_EQ(handle_->read(sample), IoResult::ok);
        const std::uint64_t before = sample.sequence;
        // The reply to the next command goes wrong on the way. (Armed before the command is
        // written: the emulator thread answers as soon as it arrives.)
        device_->with_emulator([&](proto::DeviceEmulator& e) { c.arm(e.faults()); });
        ASSERT_EQ(handle_->write(push(0.5)), IoResult::ok);
        const std::int64_t start = now_ns();
        EXPECT_EQ(handle_->read(sample), IoResult::timeout);
        EXPECT_GE(now_ns() - start, 200'000'000);  // reply_timeout_ms: it waited for a good one
        EXPECT_EQ(sample.status, servo::kStatusDropped);
        // No command outstanding: the next read polls, and the device answers.
        EXPECT_EQ(handle_->read(sample), IoResult::ok);
        EXPECT_EQ(sample.status & servo::kStatusDropped, 0u);
        // The lost sample shows as a step of two in the host's sequence.
        EXPECT_EQ(sample.sequence, before + 2);
        ASSERT_EQ(handle_->write(push(0.5)), IoResult::ok);
    }
    ASSERT_EQ(handle_->read(sample), IoResult::ok);
    EXPECT_EQ(sample.status, 0u);
}

TEST_F(SerialDeviceTest, ASequenceGapAdvancesTheHostsSequence) {
    Sample sample;
    ASSERT_EQ(tick(sample), IoResult::ok);
    ASSERT_EQ(handle_->read(sample), IoResult::ok);
    const std::uint64_t before = sample.sequence;
    device_->with_emulator([](proto::DeviceEmulator& e) { e.faults().sequence_gap = 4; });
    ASSERT_EQ(handle_->write(push(0.5)), IoResult::ok);
    ASSERT_EQ(handle_->read(sample), IoResult::ok);
    EXPECT_EQ(sample.sequence, before + 5);  // four samples the device says were lost
    ASSERT_EQ(handle_->write(push(0.5)), IoResult::ok);
    ASSERT_EQ(handle_->read(sample), IoResult::ok);
    EXPECT_EQ(sample.sequence, before + 6);
}

TEST_F(SerialDeviceTest, ADeviceFaultIsReported) {
    Sample sample;
    ASSERT_EQ(tick(sample), IoResult::ok);
    ASSERT_EQ(handle_->read(sample), IoResult::ok);
    EXPECT_EQ(sample.status & servo::kStatusDeviceFault, 0u);
    device_->with_emulator([](proto::DeviceEmulator& e) {
        e.faults().device_faults = proto::kDeviceFaultOverCurrent;
    });
    ASSERT_EQ(handle_->write(push(0.5)), IoResult::ok);
    ASSERT_EQ(handle_->read(sample), IoResult::ok);
    EXPECT_NE(sample.status & servo::kStatusDeviceFault, 0u);
    device_->with_emulator([](proto::DeviceEmulator& e) {
        EXPECT_EQ(e.output_force_n()[0], 0.0);  // the device holds zero force itself
        EXPECT_NE(e.latched_faults() & proto::kDeviceFaultOverCurrent, 0u);
    });
}

TEST(SerialDeviceReconnect, HangupIsDisconnectedAndTheDeviceIsAdoptedWhenItReturns) {
    const ScratchDir dir;
    const std::string stable = dir.file("by-id");
    PtyDevice device(emulator_config(), stable);
    DeviceHandle handle = device::load_device("serial");
    handle->open(device_config(serial_table(device.port())));
    Sample sample;
    for (int i = 0; i < 20; ++i) {
        ASSERT_EQ(handle->read(sample), IoResult::ok);
        ASSERT_EQ(handle->write(push(0.5)), IoResult::ok);
    }
    const std::uint32_t first_session =
        device.with_emulator([](proto::DeviceEmulator& e) { return e.session(); });
    const std::string first_slave = device.slave_path();

    device.hang_up();  // the cable is pulled: the master closes, the slave hangs up
    const std::int64_t start = now_ns();
    EXPECT_EQ(handle->read(sample), IoResult::disconnected);
    EXPECT_LT(now_ns() - start, 1'000'000'000);  // at once, not after the reply timeout
    EXPECT_NE(sample.status & servo::kStatusDisconnected, 0u);
    EXPECT_EQ(handle->write(push(0.5)), IoResult::disconnected);
    // Gone for a while: the reconnect thread keeps trying the dead path.
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    EXPECT_EQ(handle->read(sample), IoResult::disconnected);

    device.plug_in();  // the same device on a new pty; the symlink follows it
    IoResult result = IoResult::disconnected;
    for (int attempt = 0; attempt < 500 && result != IoResult::ok; ++attempt) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        result = handle->read(sample);
    }
    ASSERT_EQ(result, IoResult::ok) << "not adopted within 5 s";
    EXPECT_EQ(sample.status, 0u);
    for (int i = 0; i < 20; ++i) {
        ASSERT_EQ(handle->write(push(0.5)), IoResult::ok);
        ASSERT_EQ(handle->read(sample), IoResult::ok);
    }
    device.with_emulator([&](proto::DeviceEmulator& e) {
        EXPECT_TRUE(e.session_open());
        EXPECT_NE(e.session(), first_session);  // a new handshake, a new session
    });
    std::cout << "[serial] reconnected: " << first_slave << " -> " << device.slave_path()
              << " behind " << stable << "\n";
    handle->close();
}

TEST(SerialDeviceConfig, BadKeysNameTheirFullKey) {
    PtyDevice device(emulator_config());
    EXPECT_THAT(open_error(""), HasSubstr("[device.serial] port is missing: required"));
    EXPECT_THAT(open_error(serial_table(device.port(), "baud = 1200\n")),
                HasSubstr("[device.serial] baud = 1200 is not allowed: allowed one of the "
                          "standard rates 9600, 19200"));
    const std::string unknown = open_error(serial_table(device.port(), "buad = 9600\n"));
    EXPECT_THAT(unknown, HasSubstr("[device.serial] buad = 9600 is not a known key"));
    EXPECT_THAT(unknown, HasSubstr("docs/transport-serial.md"));
    EXPECT_THAT(open_error("port = \"/dev/ttyHAPTIC-missing\"\n"),
                HasSubstr("serial port /dev/ttyHAPTIC-missing (device.serial.port in test.toml): "
                          "not found"));
    // And nothing was left open: the device is still free for a good configuration.
    EXPECT_EQ(open_error(serial_table(device.port())), "");
}

}  // namespace
}  // namespace hapticd::testing
