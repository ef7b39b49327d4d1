// The [device.usb] keys (docs/transport-usb.md): which USB device to open and how to talk to
// it. Read once in Device::open(), outside the tick.
#pragma once

#include <cstdint>
#include <string>

#include "hapticd/device/plugin_table.hpp"
#include "hapticd/device/protocol/transport.hpp"

namespace hapticd::device::usb {

/// The development VID:PID of the protocol (transport.hpp).
inline constexpr std::uint16_t kDefaultVendorId = protocol::kDevelopmentVendorId;
inline constexpr std::uint16_t kDefaultProductId = protocol::kDevelopmentProductId;

/// How frames travel (docs/protocol.md 6.1): both endpoints interrupt or both bulk.
enum class TransferKind : std::uint8_t {
    automatic,  ///< what the endpoint descriptors say (the default)
    interrupt,
    bulk,
};

const char* to_string(TransferKind kind) noexcept;

struct UsbSettings {
    std::uint16_t vendor_id = kDefaultVendorId;    ///< device.usb.vid, 0..0xFFFF
    std::uint16_t product_id = kDefaultProductId;  ///< device.usb.pid, 0..0xFFFF
    /// device.usb.interface: the interface number to claim; < 0 (the key is absent): the
    /// first interface whose class is 0xFF/0x48/0x01 (transport.hpp).
    int interface_number = -1;
    TransferKind transfer = TransferKind::automatic;  ///< device.usb.transfer

    // Not keys of this table: filled in from the rest of the configuration.
    /// device.usb.serial_number (read by ProtocolDevice): also matched against the USB
    /// iSerialNumber string, so that of two devices with one VID:PID the right one is opened.
    std::string serial_number;
    std::string source = "<config>";  ///< the config file, for messages
};

/// Reads vid, pid, interface and transfer from the plugin's table (the reader remembers them;
/// the caller calls finish()). `serial_number` is ProtocolSettings::serial_number. Throws
/// std::runtime_error naming the file, device.usb.<key>, the value and the allowed range.
UsbSettings read_usb_settings(TableReader& table, std::string serial_number);

/// "1209:0001", lower-case hex as lsusb prints it.
std::string vid_pid_text(std::uint16_t vendor_id, std::uint16_t product_id);

}  // namespace hapticd::device::usb
