// UsbSettingsTest, UsbEndpointsTest: the [device.usb] keys and the choice of interface and
// endpoints from a configuration descriptor (docs/transport-usb.md). No device needed.
#include "hapticd/device/usb/usb_settings.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "hapticd/device/plugin_table.hpp"
#include "hapticd/device/usb/usb_endpoints.hpp"
#include "plugin_table_read.hpp"

namespace hapticd::device::usb {
namespace {

constexpr const char* kSource = "usb-test.toml";

UsbSettings read(const std::string& toml_text, const std::string& serial = "") {
    return testing::read_plugin_table({"usb", "docs/transport-usb.md", kSource}, toml_text,
                                      [&](TableReader& reader, const DeviceConfig&) {
                                          return read_usb_settings(reader, serial);
                                      });
}

/// The message read() throws with, or "" if it does not throw.
std::string error_of(const std::string& toml_text) {
    return testing::thrown_message([&] { return read(toml_text); }, "");
}

TEST(UsbSettingsTest, DefaultsArePidCodesTestIdsAndAutomaticTransfer) {
    const UsbSettings settings = read("", "EMU-0001");
    EXPECT_EQ(settings.vendor_id, 0x1209);
    EXPECT_EQ(settings.product_id, 0x0001);
    EXPECT_EQ(settings.interface_number, -1);
    EXPECT_EQ(settings.transfer, TransferKind::automatic);
    EXPECT_EQ(settings.serial_number, "EMU-0001");
    EXPECT_EQ(settings.source, kSource);
}

TEST(UsbSettingsTest, ReadsEveryKey) {
    const UsbSettings settings =
        read("vid = 0x16c0\npid = 0x05dc\ninterface = 2\ntransfer = \"bulk\"\n");
    EXPECT_EQ(settings.vendor_id, 0x16c0);
    EXPECT_EQ(settings.product_id, 0x05dc);
    EXPECT_EQ(settings.interface_number, 2);
    EXPECT_EQ(settings.transfer, TransferKind::bulk);
    EXPECT_EQ(read("transfer = \"interrupt\"\n").transfer, TransferKind::interrupt);
    EXPECT_EQ(vid_pid_text(0x16c0, 0x05dc), "16c0:05dc");
}

TEST(UsbSettingsTest, BadVidNamesFileKeyValueAndRange) {
    const std::string message = error_of("vid = 0x12345\n");
    EXPECT_NE(message.find(kSource), std::string::npos) << message;
    EXPECT_NE(message.find("[device.usb] vid"), std::string::npos) << message;
    EXPECT_NE(message.find("0x12345"), std::string::npos) << message;
    EXPECT_NE(message.find("0..0xFFFF"), std::string::npos) << message;

    const std::string text = error_of("pid = \"0001\"\n");
    EXPECT_NE(text.find("[device.usb] pid"), std::string::npos) << text;
    EXPECT_NE(text.find("\"0001\""), std::string::npos) << text;
    EXPECT_NE(error_of("vid = -1\n").find("[device.usb] vid"), std::string::npos);
}

TEST(UsbSettingsTest, BadTransferAndInterfaceAreNamed) {
    const std::string transfer = error_of("transfer = \"isochronous\"\n");
    EXPECT_NE(transfer.find("[device.usb] transfer"), std::string::npos) << transfer;
    EXPECT_NE(transfer.find("isochronous"), std::string::npos) << transfer;
    EXPECT_NE(transfer.find("interrupt"), std::string::npos) << transfer;
    const std::string interface = error_of("interface = 256\n");
    EXPECT_NE(interface.find("[device.usb] interface"), std::string::npos) << interface;
    EXPECT_NE(interface.find("255"), std::string::npos) << interface;
}

TEST(UsbSettingsTest, UnknownKeyIsRejected) {
    const std::string message = error_of("vendor = 0x1209\n");
    EXPECT_NE(message.find("[device.usb] vendor"), std::string::npos) << message;
    EXPECT_NE(message.find("docs/transport-usb.md"), std::string::npos) << message;
}

/// A configuration descriptor assembled in memory, as libusb would parse it.
class Descriptor {
  public:
    /// Adds an interface (alternate setting 0) with the class triple and endpoints given as
    /// (address, transfer type, wMaxPacketSize).
    struct Endpoint {
        std::uint8_t address;
        std::uint8_t type;
        std::uint16_t max_packet;
    };
    void add(std::uint8_t number, std::uint8_t cls, std::uint8_t sub, std::uint8_t protocol,
             const std::vector<Endpoint>& endpoints) {
        std::vector<libusb_endpoint_descriptor> eps;
        for (const Endpoint& e : endpoints) {
            libusb_endpoint_descriptor d{};
            d.bLength = 7;
            d.bDescriptorType = LIBUSB_DT_ENDPOINT;
            d.bEndpointAddress = e.address;
            d.bmAttributes = e.type;
            d.wMaxPacketSize = e.max_packet;
            d.bInterval = 1;
            eps.push_back(d);
        }
        endpoints_.push_back(std::move(eps));
        libusb_interface_descriptor alt{};
        alt.bLength = 9;
        alt.bDescriptorType = LIBUSB_DT_INTERFACE;
        alt.bInterfaceNumber = number;
        alt.bNumEndpoints = static_cast<std::uint8_t>(endpoints.size());
        alt.bInterfaceClass = cls;
        alt.bInterfaceSubClass = sub;
        alt.bInterfaceProtocol = protocol;
        alts_.push_back(alt);
    }
    const libusb_config_descriptor& get() {
        interfaces_.clear();
        for (std::size_t i = 0; i < alts_.size(); ++i) {
            alts_[i].endpoint = endpoints_[i].data();
            interfaces_.push_back(libusb_interface{&alts_[i], 1});
        }
        config_ = libusb_config_descriptor{};
        config_.bNumInterfaces = static_cast<std::uint8_t>(interfaces_.size());
        config_.interface = interfaces_.data();
        return config_;
    }

  private:
    std::vector<std::vector<libusb_endpoint_descriptor>> endpoints_;
    std::vector<libusb_interface_descriptor> alts_;
    std::vector<libusb_interface> interfaces_;
    libusb_config_descriptor config_{};
};

constexpr std::uint8_t kInterrupt = LIBUSB_TRANSFER_TYPE_INTERRUPT;
constexpr std::uint8_t kBulk = LIBUSB_TRANSFER_TYPE_BULK;
const std::string kWhere = "usb 1209:0001 (bus 1 device 2)";

std::string select_error(Descriptor& descriptor, const UsbSettings& settings) {
    try {
        (void)select_endpoints(descriptor.get(), settings, kWhere);
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return "";
}

TEST(UsbEndpointsTest, FindsTheProtocolInterfaceAmongOthers) {
    Descriptor descriptor;
    descriptor.add(0, 0x03, 0x00, 0x00, {{0x83, kInterrupt, 8}});  // a HID interface
    descriptor.add(1, 0xFF, 0x48, 0x01, {{0x02, kInterrupt, 64}, {0x82, kInterrupt, 64}});
    const UsbEndpoints endpoints = select_endpoints(descriptor.get(), UsbSettings{}, kWhere);
    EXPECT_EQ(endpoints.interface_number, 1);
    EXPECT_EQ(endpoints.in.address, 0x82);
    EXPECT_EQ(endpoints.out.address, 0x02);
    EXPECT_EQ(endpoints.in.transfer_type, kInterrupt);
    EXPECT_EQ(endpoints.in.max_packet_size, 64);
    EXPECT_EQ(endpoints.describe(),
              "interface 1, interrupt IN 0x82 / interrupt OUT 0x02, 64 bytes, bInterval 1");
}

TEST(UsbEndpointsTest, NoProtocolInterfaceListsWhatTheDeviceHas) {
    Descriptor descriptor;
    descriptor.add(0, 0x03, 0x00, 0x00, {{0x81, kInterrupt, 8}});
    descriptor.add(1, 0xFF, 0x00, 0x00, {{0x01, kBulk, 64}, {0x81, kBulk, 64}});
    const std::string message = select_error(descriptor, UsbSettings{});
    EXPECT_NE(message.find(kWhere), std::string::npos) << message;
    EXPECT_NE(message.find("no hapticd protocol interface"), std::string::npos) << message;
    EXPECT_NE(message.find("0 (03/00/00, 1 endpoints), 1 (ff/00/00, 2 endpoints)"),
              std::string::npos)
        << message;
    EXPECT_NE(message.find("device.usb.interface"), std::string::npos) << message;

    // Named by number, the vendor interface of another class is taken.
    UsbSettings settings;
    settings.interface_number = 1;
    const UsbEndpoints endpoints = select_endpoints(descriptor.get(), settings, kWhere);
    EXPECT_EQ(endpoints.interface_number, 1);
    EXPECT_EQ(endpoints.in.transfer_type, kBulk);
    settings.interface_number = 4;
    const std::string missing = select_error(descriptor, settings);
    EXPECT_NE(missing.find("has no interface 4"), std::string::npos) << missing;
}

TEST(UsbEndpointsTest, RefusesSmallPacketsAndMissingEndpoints) {
    Descriptor small;
    small.add(0, 0xFF, 0x48, 0x01, {{0x01, kInterrupt, 32}, {0x81, kInterrupt, 32}});
    const std::string packets = select_error(small, UsbSettings{});
    EXPECT_NE(packets.find("wMaxPacketSize 32"), std::string::npos) << packets;

    Descriptor one_way;
    one_way.add(0, 0xFF, 0x48, 0x01, {{0x81, kInterrupt, 64}});
    const std::string missing = select_error(one_way, UsbSettings{});
    EXPECT_NE(missing.find("lacks an interrupt or bulk OUT endpoint"), std::string::npos)
        << missing;
}

TEST(UsbEndpointsTest, TransferKeyAgainstTheEndpoints) {
    Descriptor bulk;
    bulk.add(0, 0xFF, 0x48, 0x01, {{0x01, kBulk, 64}, {0x81, kBulk, 64}});
    UsbSettings settings;
    settings.source = kSource;
    settings.transfer = TransferKind::interrupt;
    const std::string message = select_error(bulk, settings);
    EXPECT_NE(message.find("usb-test.toml: device.usb.transfer = \"interrupt\""), std::string::npos)
        << message;
    EXPECT_NE(message.find("is bulk"), std::string::npos) << message;

    // Bulk transfers on interrupt endpoints: usbfs sends them as interrupt transfers.
    Descriptor interrupt;
    interrupt.add(0, 0xFF, 0x48, 0x01, {{0x01, kInterrupt, 64}, {0x81, kInterrupt, 64}});
    settings.transfer = TransferKind::bulk;
    const UsbEndpoints endpoints = select_endpoints(interrupt.get(), settings, kWhere);
    EXPECT_EQ(endpoints.in.transfer_type, kBulk);
    EXPECT_EQ(endpoints.out.transfer_type, kBulk);
}

}  // namespace
}  // namespace hapticd::device::usb
