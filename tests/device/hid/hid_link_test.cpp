// HidLink (hid_link.hpp) through the real hidapi hidraw backend against an emulated hidraw
// node with the reference device behind it (emulated_hid_device.hpp): enumeration, whole
// frames both ways, framing errors, deadlines, and a device that goes away and comes back.
#include "hapticd/device/hid/hid_link.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "emulated_hid_device.hpp"
#include "hapticd/device/hid/hid_enumeration.hpp"
#include "hapticd/device/protocol/messages.hpp"
#include "hapticd/device/protocol/transport.hpp"

namespace hapticd::testing {
namespace {

namespace proto = device::protocol;
using device::hid::HidDeviceEntry;
using device::hid::HidLink;
using device::hid::HidSettings;
using device::link::LinkResult;
using device::link::monotonic_now_ns;

constexpr std::uint32_t kSession = 0x5EED0001u;
constexpr std::int64_t kGenerousNs = 5'000'000'000;  ///< a loaded 2-core VM

HidSettings ids(std::uint16_t vid = 0x1209, std::uint16_t pid = 0x4841) {
    HidSettings s;
    s.vid = vid;
    s.pid = pid;
    s.ids_given = true;
    s.source = "cfg.toml";
    return s;
}

/// Sends a hello for kSession through the link.
void send_hello(HidLink& link) {
    std::array<std::byte, proto::kMaxFrameSize> frame{};
    const proto::Encoded hello = proto::encode(proto::Hello{kSession, 1, 1}, frame);
    ASSERT_TRUE(hello.ok());
    ASSERT_EQ(link.send(std::span<const std::byte>(frame.data(), hello.size)), LinkResult::ok);
}

/// The next frame, decoded (LinkResult and message).
struct Received {
    LinkResult result = LinkResult::error;
    proto::Error error = proto::Error::none;
    proto::Message message;
};
Received receive(HidLink& link, std::int64_t deadline_ns) {
    std::array<std::byte, proto::kMaxFrameSize> frame{};
    std::size_t size = 0;
    Received r;
    r.result = link.receive(frame, size, deadline_ns);
    if (r.result == LinkResult::ok) {
        r.error = proto::decode(std::span<const std::byte>(frame.data(), size), r.message);
    }
    return r;
}

/// What the device behind the node has seen and said, for failure messages.
std::string device_side(EmulatedHidDevice& device) {
    return "(the device read " + std::to_string(device.server().output_reports()) +
           " output reports and wrote " + std::to_string(device.server().input_reports()) +
           " input reports)";
}

/// Waits until the device has answered `output_reports` output reports in all: its answers are
/// in the node, and a receive() finds them at once, whatever the emulation's round trip takes
/// under load (hid_device_server.hpp, "Timing").
bool answered(EmulatedHidDevice& device, std::uint64_t output_reports) {
    return device.server().await_answered(output_reports, std::chrono::nanoseconds(kGenerousNs));
}

/// A USB keyboard's report descriptor (boot protocol): another device on the bus.
const std::vector<std::uint8_t> kKeyboardDescriptor = {
    0x05, 0x01, 0x09, 0x06, 0xA1, 0x01, 0x05, 0x07, 0x19, 0xE0, 0x29, 0xE7, 0x15, 0x00, 0x25,
    0x01, 0x75, 0x01, 0x95, 0x08, 0x81, 0x02, 0x95, 0x01, 0x75, 0x08, 0x81, 0x01, 0x95, 0x06,
    0x75, 0x08, 0x15, 0x00, 0x25, 0x65, 0x05, 0x07, 0x19, 0x00, 0x29, 0x65, 0x81, 0x00, 0xC0};

TEST(HidEnumeration, FindsTheEmulatedDeviceAsHidapiSeesIt) {
    EmulatedHidDevice device;
    const std::vector<HidDeviceEntry> seen = device::hid::enumerate_hid_devices();
    ASSERT_EQ(seen.size(), 1u);
    const HidDeviceEntry& e = seen.front();
    EXPECT_EQ(e.path, "/dev/hidraw0");
    EXPECT_EQ(e.vid, 0x1209);
    EXPECT_EQ(e.pid, 0x4841);
    EXPECT_EQ(e.serial, "EMU-0001");
    EXPECT_EQ(e.manufacturer, "hapticd");
    EXPECT_EQ(e.product, "hapticd emulated device");
    EXPECT_EQ(e.interface_number, 0);
    // From the report descriptor in sysfs: the protocol's vendor collection.
    EXPECT_EQ(e.usages, std::vector<std::uint32_t>{0xFF000001u});
    EXPECT_TRUE(e.may_speak_protocol());
}

TEST(HidEnumeration, ChoosesTheProtocolDeviceBesideAKeyboard) {
    EmulatedHidDevice device;
    HidrawNodeSpec keyboard;
    keyboard.vid = 0x046d;
    keyboard.pid = 0xc31c;
    keyboard.serial = "";
    keyboard.product = "USB Keyboard";
    keyboard.report_descriptor = kKeyboardDescriptor;
    keyboard.hidraw_number = 1;
    device.testbed().plug(keyboard);

    const std::vector<HidDeviceEntry> seen = device::hid::enumerate_hid_devices();
    ASSERT_EQ(seen.size(), 2u);
    EXPECT_EQ(device::hid::select_hid_device(seen, ids(0, 0)).path, "/dev/hidraw0");
    try {
        (void)device::hid::select_hid_device(seen, ids(0x046d, 0xc31c));
        ADD_FAILURE() << "the keyboard was chosen";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("/dev/hidraw1 046d:c31c \"USB Keyboard\" serial "
                                             "(none) usage 0001:0006"),
                  std::string::npos)
            << e.what();
    }
}

TEST(HidLinkFrames, HelloRoundTripThroughReports) {
    EmulatedHidDevice device;
    HidLink link(ids());
    link.open();
    ASSERT_TRUE(link.is_open());
    EXPECT_EQ(link.describe(),
              "hid 1209:4841 serial \"EMU-0001\" at /dev/hidraw0 (\"hapticd emulated device\")");

    send_hello(link);
    const Received r = receive(link, monotonic_now_ns() + kGenerousNs);
    ASSERT_EQ(r.result, LinkResult::ok) << device_side(device);
    ASSERT_EQ(r.error, proto::Error::none);
    const auto* identity = std::get_if<proto::Identity>(&r.message);
    ASSERT_NE(identity, nullptr);
    EXPECT_EQ(identity->session, kSession);
    EXPECT_EQ(identity->serial_number(), "EMU-0001");
    EXPECT_EQ(identity->axes, 1);
    EXPECT_EQ(identity->counts_per_meter, 1e5);
    EXPECT_EQ(identity->period_us, 1000u);

    EXPECT_EQ(device.server().output_reports(), 1u);
    EXPECT_EQ(device.server().input_reports(), 1u);
    const device::link::LinkCounters c = link.counters();
    EXPECT_EQ(c.frames_sent, 1u);
    EXPECT_EQ(c.frames_received, 1u);
    EXPECT_EQ(c.framing_errors, 0u);
    EXPECT_EQ(c.reopens, 0u);
}

TEST(HidLinkFrames, ReportsWithAnotherIdAreSkipped) {
    EmulatedHidDevice device;
    HidLink link(ids());
    link.open();
    // Ahead of the identity: report ID 3, and the output report's ID 1, each holding an
    // otherwise valid frame.
    std::array<std::byte, proto::kMaxFrameSize> frame{};
    const proto::Encoded poll = proto::encode(proto::Poll{kSession}, frame);
    for (const std::uint8_t id : {std::uint8_t{3}, proto::hid::kOutputReportId}) {
        std::array<std::byte, proto::hid::kReportSize> report{};
        ASSERT_TRUE(
            proto::hid::wrap_report(id, std::span<const std::byte>(frame.data(), poll.size), report)
                .ok());
        device.server().inject_input_report(report);
    }
    send_hello(link);
    const Received r = receive(link, monotonic_now_ns() + kGenerousNs);
    ASSERT_EQ(r.result, LinkResult::ok) << device_side(device);
    EXPECT_TRUE(std::holds_alternative<proto::Identity>(r.message));
    EXPECT_EQ(link.counters().framing_errors, 2u);
    EXPECT_EQ(link.counters().frames_received, 1u);
}

TEST(HidLinkFrames, APastDeadlineTakesOnlyWhatIsAlreadyThere) {
    EmulatedHidDevice device;
    HidLink link(ids());
    link.open();
    send_hello(link);
    // Once the identity is in the node, a past deadline finds it.
    ASSERT_TRUE(answered(device, 1)) << device_side(device);
    const Received r = receive(link, 0);
    ASSERT_EQ(r.result, LinkResult::ok) << device_side(device);
    EXPECT_TRUE(std::holds_alternative<proto::Identity>(r.message));
    const std::int64_t start = monotonic_now_ns();
    EXPECT_EQ(receive(link, 0).result, LinkResult::timeout);
    EXPECT_LT(monotonic_now_ns() - start, 100'000'000) << "a past deadline must not wait";
}

TEST(HidLinkFrames, TimeoutsEndAtTheDeadlineNotAtTheNextMillisecond) {
    EmulatedHidDevice device;
    HidLink link(ids());
    link.open();
    // Nothing was asked, so nothing comes: each receive() ends at its deadline. hidapi waits
    // in whole milliseconds; rounding 0.3 ms up to 1 would overshoot by 0.7 ms every time.
    constexpr std::int64_t kWaitNs = 300'000;
    std::vector<std::int64_t> overshoot_ns;
    for (int i = 0; i < 21; ++i) {
        const std::int64_t deadline = monotonic_now_ns() + kWaitNs;
        EXPECT_EQ(receive(link, deadline).result, LinkResult::timeout);
        const std::int64_t late = monotonic_now_ns() - deadline;
        EXPECT_GE(late, 0) << "returned before its deadline";
        overshoot_ns.push_back(late);
    }
    std::sort(overshoot_ns.begin(), overshoot_ns.end());
    const std::int64_t median = overshoot_ns[overshoot_ns.size() / 2];
    std::cout << "[hid] 0.3 ms timeout: overshoot min " << overshoot_ns.front() / 1000
              << " us, median " << median / 1000 << " us, max " << overshoot_ns.back() / 1000
              << " us\n";
    // Load only ever adds to the overshoot; a wait rounded up to 1 ms never ends earlier
    // than 0.7 ms late.
    EXPECT_LT(overshoot_ns.front(), 500'000);

    // A longer wait: whole milliseconds in hidapi, then the rest.
    const std::int64_t deadline = monotonic_now_ns() + 20'000'000;
    EXPECT_EQ(receive(link, deadline).result, LinkResult::timeout);
    EXPECT_GE(monotonic_now_ns(), deadline);
}

TEST(HidLinkFrames, AnUnpluggedDeviceIsDisconnectedAndFoundAgainWhenItReturns) {
    EmulatedHidDevice device;
    HidLink link(ids());
    link.open();
    device.unplug();

    EXPECT_EQ(receive(link, monotonic_now_ns() + kGenerousNs).result, LinkResult::disconnected);
    std::array<std::byte, proto::kMaxFrameSize> frame{};
    const proto::Encoded poll = proto::encode(proto::Poll{kSession}, frame);
    EXPECT_EQ(link.send(std::span<const std::byte>(frame.data(), poll.size)),
              LinkResult::disconnected);

    link.close();
    try {
        link.open();
        ADD_FAILURE() << "opened a device that is not there";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("hid: no HID device 1209:4841: there are no hidraw "
                                             "devices at all"),
                  std::string::npos)
            << e.what();
    }

    // Back, power-cycled, under another node: enumeration finds it by its ids.
    device.replug(1);
    link.open();
    EXPECT_EQ(link.entry()->path, "/dev/hidraw1");
    EXPECT_EQ(link.counters().reopens, 1u);
    send_hello(link);
    const Received r = receive(link, monotonic_now_ns() + kGenerousNs);
    ASSERT_EQ(r.result, LinkResult::ok) << device_side(device);
    EXPECT_TRUE(std::holds_alternative<proto::Identity>(r.message));
}

TEST(HidLinkFrames, AConfiguredPathOverridesEnumeration) {
    EmulatedHidDevice device;
    HidSettings by_path;
    by_path.path = "/dev/hidraw0";
    HidLink link(by_path);
    link.open();
    send_hello(link);
    EXPECT_EQ(receive(link, monotonic_now_ns() + kGenerousNs).result, LinkResult::ok)
        << device_side(device);

    HidSettings wrong = ids(0x1209, 0x1234);
    wrong.path = "/dev/hidraw0";
    HidLink checked(wrong);
    try {
        checked.open();
        ADD_FAILURE() << "opened another device than configured";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("cfg.toml: device.hid.path = \"/dev/hidraw0\" is "
                                             "/dev/hidraw0 1209:4841"),
                  std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find("not device.hid.vid, device.hid.pid = 1209:1234"),
                  std::string::npos);
    }
}

// hidraw lets any number of processes open a node: without a lock of its own, a second
// hapticd on the same device would interleave its frames with the first one's.
TEST(HidLinkFrames, ASecondLinkOnTheSameNodeIsRefusedUntilTheFirstCloses) {
    EmulatedHidDevice device;
    HidLink first(ids());
    first.open();
    HidLink second(ids());
    try {
        second.open();
        ADD_FAILURE() << "two links opened the same hidraw node";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("hid: /dev/hidraw0 1209:4841"), std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find("is in use: another hapticd has it open"),
                  std::string::npos)
            << e.what();
    }
    EXPECT_FALSE(second.is_open());
    // The first link works on, untouched by the refused one.
    send_hello(first);
    EXPECT_EQ(receive(first, monotonic_now_ns() + kGenerousNs).result, LinkResult::ok)
        << device_side(device);
    first.close();
    second.open();  // the lock went with the first link's close
    EXPECT_TRUE(second.is_open());
    send_hello(second);
    EXPECT_EQ(receive(second, monotonic_now_ns() + kGenerousNs).result, LinkResult::ok)
        << device_side(device);
}

}  // namespace
}  // namespace hapticd::testing
