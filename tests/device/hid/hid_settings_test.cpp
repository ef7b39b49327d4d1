// The [device.hid] keys and the choice of a device among hidapi's enumeration
// (hid_settings.hpp, hid_enumeration.hpp, docs/transport-hid.md): plain values, no device.
#include "hapticd/device/hid/hid_settings.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "hapticd/device/hid/hid_enumeration.hpp"
#include "hapticd/device/link/protocol_settings.hpp"
#include "plugin_table_read.hpp"

namespace hapticd::device::hid {
namespace {

/// read_hid_settings() on `toml` as ProtocolDevice would call it, then finish().
HidSettings read(const std::string& toml, const std::string& serial_number = "") {
    return testing::read_plugin_table(
        {"hid", "docs/transport-hid.md", "cfg.toml"}, toml,
        [&](TableReader& reader, const DeviceConfig& config) {
            link::ProtocolSettings protocol;
            protocol.serial_number = serial_number;
            return read_hid_settings(reader, link::LinkContext{config, protocol});
        });
}

std::string error_of(const std::string& toml) {
    return testing::thrown_message([&] { return read(toml); }, "<no error>");
}

TEST(HidSettings, ReadsIdsAndPath) {
    const HidSettings ids = read("vid = 0x1209\npid = 0x4841\n", "HX-0001");
    EXPECT_EQ(ids.vid, 0x1209);
    EXPECT_EQ(ids.pid, 0x4841);
    EXPECT_TRUE(ids.ids_given);
    EXPECT_EQ(ids.path, "");
    EXPECT_EQ(ids.serial_number, "HX-0001");
    EXPECT_EQ(ids.source, "cfg.toml");

    const HidSettings path = read("path = \"/dev/hidraw3\"\n");
    EXPECT_EQ(path.path, "/dev/hidraw3");
    EXPECT_FALSE(path.ids_given);

    const HidSettings defaults = read("");  // the pid.codes test id, as the usb plugin's
    EXPECT_EQ(defaults.vid, 0x1209);
    EXPECT_EQ(defaults.pid, 0x0001);
    EXPECT_FALSE(defaults.ids_given);

    const HidSettings wildcard = read("vid = 0\npid = 0\n");
    EXPECT_TRUE(wildcard.ids_given);
    EXPECT_EQ(wildcard.vid, 0);
}

TEST(HidSettings, BadValuesNameTheKeyTheValueAndTheRange) {
    EXPECT_EQ(error_of("vid = 65536\npid = 1\n"),
              "cfg.toml:1: [device.hid] vid = 65536 is out of range: allowed 0..65535");
    EXPECT_EQ(error_of("vid = 1\npid = -1\n"),
              "cfg.toml:2: [device.hid] pid = -1 is out of range: allowed 0..65535");
    EXPECT_EQ(error_of("vid = \"1209\"\npid = 1\n"),
              "cfg.toml:1: [device.hid] vid = \"1209\" is not an integer: allowed 0..65535");
    EXPECT_EQ(error_of("path = 3\n"),
              "cfg.toml:1: [device.hid] path = 3 is not a string: allowed a hidraw node, e.g. "
              "\"/dev/hidraw3\", or none to find the device by vid and pid");
    EXPECT_NE(error_of("path = \"\"\n").find("cfg.toml:1: [device.hid] path = \"\" is empty"),
              std::string::npos);
}

TEST(HidSettings, VidAndPidGoTogether) {
    const std::string no_pid = error_of("vid = 0x1209\n");
    EXPECT_NE(no_pid.find("[device.hid] pid is missing: required with vid"), std::string::npos)
        << no_pid;
    const std::string no_vid = error_of("pid = 0x4841\n");
    EXPECT_NE(no_vid.find("[device.hid] vid is missing: required with pid"), std::string::npos)
        << no_vid;
}

TEST(HidSettings, UnknownKeysAreRejectedWithTheDocument) {
    const std::string error = error_of("vid = 1\npid = 2\nserial = \"x\"\n");
    EXPECT_NE(error.find("cfg.toml:3: [device.hid] serial = \"x\" is not a known key"),
              std::string::npos)
        << error;
    EXPECT_NE(error.find("docs/transport-hid.md"), std::string::npos) << error;
}

HidDeviceEntry entry(std::string path, std::uint16_t vid, std::uint16_t pid, std::string serial,
                     std::vector<std::uint32_t> usages = {0xFF000001u}) {
    HidDeviceEntry e;
    e.path = std::move(path);
    e.vid = vid;
    e.pid = pid;
    e.serial = std::move(serial);
    e.product = "dev";
    e.usages = std::move(usages);
    return e;
}

HidSettings wanted(std::uint16_t vid, std::uint16_t pid, std::string serial = "") {
    HidSettings s;
    s.vid = vid;
    s.pid = pid;
    s.ids_given = true;
    s.serial_number = std::move(serial);
    s.source = "cfg.toml";
    return s;
}

std::string selection_error(const std::vector<HidDeviceEntry>& seen, const HidSettings& s) {
    try {
        (void)select_hid_device(seen, s);
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return "<no error>";
}

const std::vector<HidDeviceEntry> kSeen = {
    entry("/dev/hidraw0", 0x046d, 0xc52b, "", {0x00010006u, 0xFF000001u}),  // a receiver
    entry("/dev/hidraw1", 0x1209, 0x4841, "HX-0001"),
    entry("/dev/hidraw2", 0x1209, 0x4841, "HX-0002"),
    entry("/dev/hidraw3", 0x1209, 0x4841, "HX-0002", {0x00010002u}),  // its mouse interface
    entry("/dev/hidraw4", 0x1209, 0x4842, "", {}),                    // descriptor unreadable
};

TEST(HidSelection, ByIdsUsageAndSerial) {
    EXPECT_EQ(select_hid_device(kSeen, wanted(0x1209, 0x4841, "HX-0002")).path, "/dev/hidraw2");
    EXPECT_EQ(select_hid_device(kSeen, wanted(0x1209, 0x4841, "HX-0001")).path, "/dev/hidraw1");
    // A device that does not report its collections may be it.
    EXPECT_EQ(select_hid_device(kSeen, wanted(0x1209, 0x4842)).path, "/dev/hidraw4");
    // Nor a serial: it is taken when no device has the serial number.
    EXPECT_EQ(select_hid_device(kSeen, wanted(0x1209, 0x4842, "HX-0009")).path, "/dev/hidraw4");
    // vid 0 matches any vendor.
    EXPECT_EQ(select_hid_device(kSeen, wanted(0, 0x4842)).path, "/dev/hidraw4");
}

TEST(HidSelection, SeveralMatchesAskForTheSerialNumberOrThePath) {
    const std::string error = selection_error(kSeen, wanted(0x1209, 0x4841));
    EXPECT_NE(error.find("2 devices match HID device 1209:4841"), std::string::npos) << error;
    EXPECT_NE(error.find("device.hid.serial_number or device.hid.path"), std::string::npos);
    EXPECT_NE(error.find("/dev/hidraw1 1209:4841 \"dev\" serial \"HX-0001\" usage ff00:0001"),
              std::string::npos)
        << error;
    EXPECT_NE(error.find("/dev/hidraw2"), std::string::npos);
    EXPECT_EQ(error.find("/dev/hidraw3"), std::string::npos) << "not the protocol's collection";
}

TEST(HidSelection, NotFoundListsWhatWasSeen) {
    const std::string error = selection_error(kSeen, wanted(0x1234, 0x5678));
    EXPECT_NE(error.find("hid: no HID device 1234:5678 (cfg.toml: device.hid.vid, "
                         "device.hid.pid); the hidraw devices are:"),
              std::string::npos)
        << error;
    for (const HidDeviceEntry& e : kSeen) EXPECT_NE(error.find(e.path), std::string::npos);

    const std::string serial = selection_error(kSeen, wanted(0x1209, 0x4841, "HX-0009"));
    EXPECT_NE(serial.find("with serial number \"HX-0009\""), std::string::npos) << serial;
    EXPECT_NE(serial.find("these have other serial numbers"), std::string::npos) << serial;

    const std::string usage = selection_error(kSeen, wanted(0x046d, 0xc52b));
    EXPECT_EQ(usage, "<no error>") << "the receiver has a vendor collection ff00:0001 too";
    const std::string mouse = selection_error({kSeen[3]}, wanted(0x1209, 0x4841));
    EXPECT_NE(mouse.find("declares the protocol's collection (usage page ff00, usage 0001"),
              std::string::npos)
        << mouse;

    const std::string empty = selection_error({}, wanted(0x1209, 0x4841));
    EXPECT_NE(empty.find("there are no hidraw devices at all"), std::string::npos) << empty;
}

TEST(HidSelection, AConfiguredPathIsCheckedAgainstTheIds) {
    HidSettings s = wanted(0x1209, 0x4841);
    s.path = "/dev/hidraw2";
    ASSERT_TRUE(check_configured_path(kSeen, s).has_value());
    EXPECT_EQ(check_configured_path(kSeen, s)->serial, "HX-0002");
    s.path = "/dev/hidraw0";
    try {
        (void)check_configured_path(kSeen, s);
        ADD_FAILURE() << "the receiver was taken for the device";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("device.hid.path = \"/dev/hidraw0\" is "
                                             "/dev/hidraw0 046d:c52b"),
                  std::string::npos)
            << e.what();
    }
    s.ids_given = false;  // path alone: opened as given
    EXPECT_TRUE(check_configured_path(kSeen, s).has_value());
    s.path = "/dev/nonexistent";
    EXPECT_FALSE(check_configured_path(kSeen, s).has_value());
}

TEST(HidSelection, WideStringsBecomeUtf8) {
    EXPECT_EQ(utf8_from_wide(nullptr), "");
    EXPECT_EQ(utf8_from_wide(L"HX-0001"), "HX-0001");
    EXPECT_EQ(utf8_from_wide(L"\u00e9\u20ac\U0001F600"), "\xc3\xa9\xe2\x82\xac\xf0\x9f\x98\x80");
    EXPECT_EQ(hex_ids(0x1209, 0), "1209:any");
}

}  // namespace
}  // namespace hapticd::device::hid
