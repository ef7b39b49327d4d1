// UsbLinkTest: the `usb` transport frame by frame, through unmodified libusb, against devices
// that umockdev emulates (usb_testbed.hpp) with the reference device behind them.
#include "hapticd/device/usb/usb_link.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <thread>
#include <variant>

#include "alloc_guard.hpp"
#include "hapticd/device/protocol/messages.hpp"
#include "libusb_allocations.hpp"
#include "usb_testbed.hpp"

namespace hapticd::device::usb {
namespace {

namespace proto = device::protocol;
using link::LinkResult;
using testing::EmulatedUsbDevice;
using testing::UsbDeviceSpec;
using testing::UsbTestbed;

constexpr std::int64_t kGenerousNs = 5'000'000'000;  // a loaded 2-core VM
constexpr const char* kSource = "usb-link-test.toml";

UsbSettings settings_for(const std::string& serial = "EMU-0001") {
    UsbSettings settings;
    settings.serial_number = serial;
    settings.source = kSource;
    return settings;
}

UsbDeviceSpec spec_for(const std::string& serial = "EMU-0001") {
    UsbDeviceSpec spec;
    spec.emulator = testing::pen_display_emulator(serial);
    return spec;
}

std::string open_error(UsbLink& link) {
    try {
        link.open();
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return "";
}

double elapsed_s(std::chrono::steady_clock::time_point since) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

/// Waits (generously, for a loaded VM) until `condition` holds; false if it never does.
template <typename Condition>
bool eventually(Condition condition, double timeout_s = 5.0) {
    const auto start = std::chrono::steady_clock::now();
    while (!condition()) {
        if (elapsed_s(start) > timeout_s) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return true;
}

class UsbLinkTest : public ::testing::Test {
  protected:
    template <typename M>
    LinkResult send(UsbLink& link, const M& message) {
        const proto::Encoded encoded = proto::encode(message, tx_);
        EXPECT_TRUE(encoded.ok());
        return link.send(std::span<const std::byte>(tx_.data(), encoded.size));
    }

    /// The next frame, decoded; `error` is the decoder's verdict.
    LinkResult receive(UsbLink& link, proto::Message& message, proto::Error& error,
                       std::int64_t timeout_ns = kGenerousNs) {
        std::size_t size = 0;
        const LinkResult result = link.receive(rx_, size, link::monotonic_now_ns() + timeout_ns);
        if (result == LinkResult::ok) {
            size_ = size;
            error = proto::decode(std::span<const std::byte>(rx_.data(), size), message);
        }
        return result;
    }

    template <typename M>
    M expect_reply(UsbLink& link) {
        proto::Message message;
        proto::Error error = proto::Error::none;
        EXPECT_EQ(receive(link, message, error), LinkResult::ok);
        EXPECT_EQ(error, proto::Error::none);
        const M* reply = std::get_if<M>(&message);
        EXPECT_NE(reply, nullptr) << "another message type arrived";
        return reply != nullptr ? *reply : M{};
    }

    /// hello -> identity, configure -> ack, poll -> sample.
    proto::Identity handshake(UsbLink& link, std::uint32_t session) {
        EXPECT_EQ(send(link, proto::Hello{session, 1, 1}), LinkResult::ok);
        const auto identity = expect_reply<proto::Identity>(link);
        EXPECT_EQ(identity.session, session);
        EXPECT_EQ(send(link, proto::Configure{session, 20'000}), LinkResult::ok);
        EXPECT_EQ(expect_reply<proto::ConfigureAck>(link).watchdog_timeout_us, 20'000u);
        EXPECT_EQ(send(link, proto::Poll{session}), LinkResult::ok);
        EXPECT_EQ(expect_reply<proto::EncoderSample>(link).command_sequence, 0u);
        return identity;
    }

    UsbTestbed testbed_;
    std::array<std::byte, proto::kMaxFrameSize> tx_{};
    std::array<std::byte, proto::kMaxFrameSize> rx_{};
    std::size_t size_ = 0;
};

TEST_F(UsbLinkTest, HandshakeAndCommandsRoundTrip) {
    EmulatedUsbDevice& device = testbed_.add(spec_for());
    UsbLink link(settings_for());
    link.open();
    EXPECT_TRUE(link.is_open());
    EXPECT_EQ(link.describe(), "usb 1209:0001 serial EMU-0001 (bus 1 device 2)");
    EXPECT_EQ(link.endpoints().describe(),
              "interface 0, interrupt IN 0x81 / interrupt OUT 0x01, 64 bytes, bInterval 1");

    const proto::Identity identity = handshake(link, 0x5EC7A3B1);
    EXPECT_EQ(identity.serial_number(), "EMU-0001");
    EXPECT_EQ(identity.axes, 1);
    EXPECT_EQ(identity.counts_per_meter, 1e5);
    EXPECT_EQ(identity.period_us, 1000u);

    // Commands: each answered by a sample echoing its sequence, one period later.
    for (std::uint32_t sequence = 1; sequence <= 5; ++sequence) {
        proto::ForceCommand command;
        command.session = 0x5EC7A3B1;
        command.sequence = sequence;
        command.flags = proto::kCommandEnable;
        command.axes = 1;
        command.force_un[0] = 1'000'000;  // 1 N
        ASSERT_EQ(send(link, command), LinkResult::ok);
        const auto sample = expect_reply<proto::EncoderSample>(link);
        EXPECT_EQ(sample.command_sequence, sequence);
        EXPECT_EQ(sample.sample_sequence, sequence);
        EXPECT_EQ(sample.time_us, 1000u * sequence);
        EXPECT_NE(sample.status & proto::kSampleForceActive, 0u);
    }
    EXPECT_GT(device.with_emulator([](auto& e) { return e.sim().plant(0).state().position_m; }),
              0.0);

    const link::LinkCounters counters = link.counters();
    EXPECT_EQ(counters.frames_sent, 8u);
    EXPECT_EQ(counters.frames_received, 8u);
    EXPECT_EQ(counters.send_errors + counters.receive_errors + counters.framing_errors, 0u);
    const testing::UrbCounts urbs = device.counts();
    EXPECT_EQ(urbs.claims, 1u);
    EXPECT_EQ(urbs.clear_halts, 2u);  // both endpoints, at open
    EXPECT_EQ(urbs.out_submitted, 8u);
    EXPECT_EQ(urbs.in_completed, 8u);
    EXPECT_GE(urbs.control, 1u);  // the serial number string

    // close() cancels the IN transfer it keeps submitted and releases the interface.
    link.close();
    EXPECT_FALSE(link.is_open());
    EXPECT_EQ(device.counts().discarded, 1u);
    EXPECT_EQ(device.counts().releases, 1u);
    EXPECT_EQ(link.describe(), "usb 1209:0001 serial EMU-0001");
}

TEST_F(UsbLinkTest, BulkEndpoints) {
    UsbDeviceSpec spec = spec_for();
    spec.bulk = true;
    testbed_.add(spec);
    UsbLink link(settings_for());
    link.open();
    EXPECT_EQ(link.endpoints().in.transfer_type, LIBUSB_TRANSFER_TYPE_BULK);
    EXPECT_EQ(link.endpoints().out.transfer_type, LIBUSB_TRANSFER_TYPE_BULK);
    EXPECT_EQ(handshake(link, 7).serial_number(), "EMU-0001");
}

TEST_F(UsbLinkTest, SelectsAmongDevicesBySerialNumber) {
    testbed_.add(spec_for("EMU-0001"));
    testbed_.add(spec_for("EMU-0002"));
    UsbLink second(settings_for("EMU-0002"));
    second.open();
    EXPECT_EQ(second.describe(), "usb 1209:0001 serial EMU-0002 (bus 1 device 3)");
    EXPECT_EQ(handshake(second, 11).serial_number(), "EMU-0002");
    second.close();

    // No serial number configured: the first one found, whichever libusb lists first.
    UsbLink any(settings_for(""));
    any.open();
    const std::string serial(handshake(any, 12).serial_number());
    EXPECT_TRUE(serial == "EMU-0001" || serial == "EMU-0002") << serial;
    EXPECT_NE(any.describe().find("serial " + serial), std::string::npos) << any.describe();
}

TEST_F(UsbLinkTest, ADeviceInUseIsNamedAsBusy) {
    EmulatedUsbDevice& device = testbed_.add(spec_for());
    UsbLink first(settings_for());
    first.open();
    EXPECT_EQ(device.counts().open_files, 1u);
    UsbLink second(settings_for());
    const std::string message = open_error(second);
    EXPECT_NE(message.find("usb 1209:0001 serial EMU-0001 (bus 1 device 2) interface 0 is in use "
                           "by another program"),
              std::string::npos)
        << message;
    EXPECT_NE(message.find("/dev/bus/usb/001/002"), std::string::npos) << message;
    EXPECT_EQ(device.counts().busy_claims, 1u);
    EXPECT_FALSE(second.is_open());
    // The failed open() closed its file (umockdev notices the closed socket a moment later).
    EXPECT_TRUE(eventually([&] { return device.counts().open_files == 1; }));
    EXPECT_EQ(handshake(first, 13).session, 13u);
    first.close();
    EXPECT_TRUE(eventually([&] { return device.counts().open_files == 0; }));
    second.open();
}

TEST_F(UsbLinkTest, NotFoundSaysWhatWasLookedForAndWhatWasSeen) {
    testbed_.add(spec_for("EMU-0001"));
    UsbLink wrong_serial(settings_for("EMU-0009"));
    const std::string message = open_error(wrong_serial);
    EXPECT_NE(message.find("no device 1209:0001 with serial number \"EMU-0009\""),
              std::string::npos)
        << message;
    EXPECT_NE(message.find("device.usb.serial_number in usb-link-test.toml"), std::string::npos)
        << message;
    EXPECT_NE(message.find("seen: 1209:0001 at bus 1 device 2 with serial number \"EMU-0001\""),
              std::string::npos)
        << message;
    EXPECT_FALSE(wrong_serial.is_open());

    UsbSettings other = settings_for("");
    other.product_id = 0x00ff;
    UsbLink wrong_pid(other);
    const std::string pid_message = open_error(wrong_pid);
    EXPECT_NE(pid_message.find("no device 1209:00ff"), std::string::npos) << pid_message;
    EXPECT_NE(pid_message.find("seen: 1209:0001 at bus 1 device 2"), std::string::npos)
        << pid_message;
}

TEST_F(UsbLinkTest, DeviceWithoutTheProtocolInterfaceIsRefused) {
    UsbDeviceSpec spec = spec_for();
    spec.interface_class = 0x03;  // say, a HID interface
    testbed_.add(spec);
    UsbLink link(settings_for());
    const std::string message = open_error(link);
    EXPECT_NE(message.find("has no hapticd protocol interface"), std::string::npos) << message;
    EXPECT_NE(message.find("0 (03/48/01, 2 endpoints)"), std::string::npos) << message;

    // device.usb.interface names it: then any class will do.
    UsbSettings settings = settings_for();
    settings.interface_number = 0;
    UsbLink named(settings);
    named.open();
    EXPECT_EQ(handshake(named, 3).serial_number(), "EMU-0001");
}

TEST_F(UsbLinkTest, NoReplyIsATimeoutAtTheDeadlineAndTheLinkGoesOn) {
    EmulatedUsbDevice& device = testbed_.add(spec_for());
    UsbLink link(settings_for());
    link.open();
    handshake(link, 21);
    device.with_emulator([](auto& e) { e.faults().drop = 1; });
    ASSERT_EQ(send(link, proto::Poll{21}), LinkResult::ok);
    proto::Message message;
    proto::Error error = proto::Error::none;
    const auto start = std::chrono::steady_clock::now();
    EXPECT_EQ(receive(link, message, error, 50'000'000), LinkResult::timeout);
    EXPECT_GE(elapsed_s(start), 0.05);
    EXPECT_LT(elapsed_s(start), 2.0);
    // A deadline in the past: only what is already there, and nothing is.
    std::size_t size = 0;
    EXPECT_EQ(link.receive(rx_, size, 0), LinkResult::timeout);

    // The IN transfer stayed submitted: the next reply comes through it.
    ASSERT_EQ(send(link, proto::Poll{21}), LinkResult::ok);
    EXPECT_EQ(expect_reply<proto::EncoderSample>(link).session, 21u);
    EXPECT_EQ(device.counts().discarded, 0u);
    // A reply already waiting is returned even with a deadline in the past.
    ASSERT_EQ(send(link, proto::Poll{21}), LinkResult::ok);
    ASSERT_TRUE(eventually([&] { return device.counts().in_completed == 5; }));
    EXPECT_EQ(link.receive(rx_, size, 0), LinkResult::ok);
}

TEST_F(UsbLinkTest, CorruptAndTruncatedFramesArePassedUpForTheDecoderToRefuse) {
    EmulatedUsbDevice& device = testbed_.add(spec_for());
    UsbLink link(settings_for());
    link.open();
    handshake(link, 31);
    proto::Message message;
    proto::Error error = proto::Error::none;

    device.with_emulator([](auto& e) { e.faults().corrupt_crc = 1; });
    ASSERT_EQ(send(link, proto::Poll{31}), LinkResult::ok);
    ASSERT_EQ(receive(link, message, error), LinkResult::ok);
    EXPECT_EQ(error, proto::Error::bad_crc);

    device.with_emulator([](auto& e) { e.faults().truncate = 1; });
    ASSERT_EQ(send(link, proto::Poll{31}), LinkResult::ok);
    ASSERT_EQ(receive(link, message, error), LinkResult::ok);
    EXPECT_EQ(error, proto::Error::truncated);
    EXPECT_LT(size_, 44u);  // half a 1-axis sample

    ASSERT_EQ(send(link, proto::Poll{31}), LinkResult::ok);
    ASSERT_EQ(receive(link, message, error), LinkResult::ok);
    EXPECT_EQ(error, proto::Error::none);
    EXPECT_EQ(link.counters().framing_errors, 0u);  // frames; the decoder judges them
}

TEST_F(UsbLinkTest, TransfersThatAreNotFramesAreSkipped) {
    EmulatedUsbDevice& device = testbed_.add(spec_for());
    UsbLink link(settings_for());
    link.open();
    handshake(link, 41);
    device.inject_in({});                                           // zero-length packet
    device.inject_in(std::vector<std::byte>(64, std::byte{0x48}));  // 64 bytes: > 60
    device.inject_in(std::vector<std::byte>(65, std::byte{0x48}));  // babble: overflow
    ASSERT_EQ(send(link, proto::Poll{41}), LinkResult::ok);
    EXPECT_EQ(expect_reply<proto::EncoderSample>(link).session, 41u);
    EXPECT_EQ(link.counters().framing_errors, 3u);
}

TEST_F(UsbLinkTest, AFailedTransferIsAnErrorAndTheLinkStaysUsable) {
    EmulatedUsbDevice& device = testbed_.add(spec_for());
    UsbLink link(settings_for());
    link.open();
    handshake(link, 51);
    device.fail_next_in(-EPROTO);  // a CRC or bit-stuffing error on the bus
    proto::Message message;
    proto::Error error = proto::Error::none;
    EXPECT_EQ(receive(link, message, error), LinkResult::error);
    EXPECT_EQ(link.counters().receive_errors, 1u);
    ASSERT_EQ(send(link, proto::Poll{51}), LinkResult::ok);
    EXPECT_EQ(expect_reply<proto::EncoderSample>(link).session, 51u);
}

TEST_F(UsbLinkTest, DiscardInputDropsWhatArrivedBeforeTheHandshake) {
    EmulatedUsbDevice& device = testbed_.add(spec_for());
    UsbLink link(settings_for());
    link.open();
    handshake(link, 61);
    ASSERT_EQ(send(link, proto::Poll{61}), LinkResult::ok);  // its reply is never read
    ASSERT_TRUE(eventually([&] { return device.counts().in_completed == 4; }));
    link.discard_input();
    proto::Message message;
    proto::Error error = proto::Error::none;
    EXPECT_EQ(receive(link, message, error, 20'000'000), LinkResult::timeout);
    ASSERT_EQ(send(link, proto::Hello{62, 1, 1}), LinkResult::ok);
    EXPECT_EQ(expect_reply<proto::Identity>(link).session, 62u);
}

TEST_F(UsbLinkTest, UnplugIsDisconnectedAndTheLinkReopensWhenTheDeviceReturns) {
    EmulatedUsbDevice& device = testbed_.add(spec_for());
    UsbLink link(settings_for());
    link.open();
    handshake(link, 71);

    testbed_.unplug(device);  // the IN transfer in flight completes with -ENODEV
    proto::Message message;
    proto::Error error = proto::Error::none;
    EXPECT_EQ(receive(link, message, error), LinkResult::disconnected);
    EXPECT_EQ(send(link, proto::Poll{71}), LinkResult::disconnected);
    const auto start = std::chrono::steady_clock::now();
    link.close();
    EXPECT_LT(elapsed_s(start), 1.0);  // nothing in flight is waited for

    const std::string message_text = open_error(link);
    EXPECT_NE(message_text.find("no device 1209:0001"), std::string::npos) << message_text;

    testbed_.replug(device);
    link.open();
    EXPECT_EQ(link.describe(), "usb 1209:0001 serial EMU-0001 (bus 1 device 3)");
    EXPECT_EQ(handshake(link, 72).serial_number(), "EMU-0001");
    EXPECT_EQ(link.counters().reopens, 1u);
}

TEST_F(UsbLinkTest, SubmitToAVanishedDeviceIsDisconnected) {
    EmulatedUsbDevice& device = testbed_.add(spec_for());
    UsbLink link(settings_for());
    link.open();
    handshake(link, 81);
    testbed_.unplug(device);
    EXPECT_EQ(send(link, proto::Poll{81}), LinkResult::disconnected);  // ENODEV on submit
}

TEST_F(UsbLinkTest, InStallIsDisconnectedAndReopeningClearsTheHalt) {
    EmulatedUsbDevice& device = testbed_.add(spec_for());
    UsbLink link(settings_for());
    link.open();
    handshake(link, 91);
    device.stall_in();
    proto::Message message;
    proto::Error error = proto::Error::none;
    EXPECT_EQ(receive(link, message, error), LinkResult::disconnected);
    EXPECT_EQ(link.counters().stalls, 1u);
    EXPECT_TRUE(device.in_halted());
    EXPECT_EQ(send(link, proto::Poll{91}), LinkResult::disconnected);

    link.close();
    link.open();  // what ProtocolDevice's reconnect thread does
    EXPECT_FALSE(device.in_halted());
    EXPECT_EQ(device.counts().clear_halts, 4u);
    EXPECT_EQ(handshake(link, 92).session, 92u);
}

TEST_F(UsbLinkTest, OutStallIsDisconnectedAndReopeningClearsTheHalt) {
    EmulatedUsbDevice& device = testbed_.add(spec_for());
    UsbLink link(settings_for());
    link.open();
    handshake(link, 101);
    device.stall_out();
    EXPECT_EQ(send(link, proto::Poll{101}), LinkResult::ok);  // submitted; it fails on the bus
    proto::Message message;
    proto::Error error = proto::Error::none;
    EXPECT_EQ(receive(link, message, error), LinkResult::disconnected);
    EXPECT_EQ(link.counters().stalls, 1u);
    EXPECT_TRUE(device.out_halted());
    link.close();
    link.open();
    EXPECT_FALSE(device.out_halted());
    EXPECT_EQ(handshake(link, 102).session, 102u);
}

TEST_F(UsbLinkTest, ManyRoundTripsWithoutAllocation) {
    testbed_.add(spec_for());
    UsbLink link(settings_for());
    link.open();
    handshake(link, 111);
    std::array<std::byte, proto::kMaxFrameSize> poll{};
    const std::size_t poll_size = proto::encode(proto::Poll{111}, poll).size;
    int ok = 0;
    {
        hapticd::testing::AllocationGuard guard;
        for (int i = 0; i < 2000; ++i) {
            std::size_t size = 0;
            if (link.send(std::span<const std::byte>(poll.data(), poll_size)) == LinkResult::ok &&
                link.receive(rx_, size, link::monotonic_now_ns() + kGenerousNs) == LinkResult::ok) {
                ++ok;
            }
        }
        // Each round trip submits one OUT and one IN transfer.
        EXPECT_EQ(guard.allocations(),
                  hapticd::testing::libusb_urb_allocations(std::uint64_t{2} * 2000));
    }
    EXPECT_EQ(ok, 2000);
}

}  // namespace
}  // namespace hapticd::device::usb
