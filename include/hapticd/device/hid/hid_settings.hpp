// The [device.hid] keys (docs/transport-hid.md): which HID device to open. Read once in
// Device::open(), outside the tick.
//
//   vid, pid        the device's USB vendor and product id, 0..0xFFFF (0 matches any);
//                   default 1209:0001, the pid.codes test id (the usb plugin's too); one
//                   of them without the other is an error
//   path            a hidraw node ("/dev/hidraw3", or a udev symlink): opened as given,
//                   without choosing by ids; with vid and pid as well, the node must be
//                   that device
//   serial_number   (read by ProtocolDevice, link/protocol_settings.hpp) also selects among
//                   several matching devices by their HID serial (HID_UNIQ, the USB
//                   iSerialNumber string), when the device reports one
#pragma once

#include <cstdint>
#include <string>

#include "hapticd/device/link/protocol_device.hpp"
#include "hapticd/device/plugin_table.hpp"
#include "hapticd/device/protocol/transport.hpp"

namespace hapticd::device::hid {

/// The development VID:PID of the protocol (transport.hpp), as the usb plugin's.
inline constexpr std::uint16_t kDefaultVendorId = protocol::kDevelopmentVendorId;
inline constexpr std::uint16_t kDefaultProductId = protocol::kDevelopmentProductId;

struct HidSettings {
    std::uint16_t vid = kDefaultVendorId;   ///< device.hid.vid; 0: any vendor
    std::uint16_t pid = kDefaultProductId;  ///< device.hid.pid; 0: any product
    bool ids_given = false;                 ///< vid and pid were in the table
    std::string path;  ///< device.hid.path; empty: choose by vid, pid, serial number

    // Not keys of this table.
    std::string serial_number;        ///< device.hid.serial_number (ProtocolSettings)
    std::string source = "<config>";  ///< the config file, for messages
};

/// Reads vid, pid and path (the reader remembers them; ProtocolDevice calls finish()).
/// Throws std::runtime_error naming the file and device.hid.<key>: a value out of range or
/// of the wrong type, vid without pid (or the other way round), an empty path.
HidSettings read_hid_settings(TableReader& table, const link::LinkContext& context);

}  // namespace hapticd::device::hid
