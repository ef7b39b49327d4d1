// Finding the configured device among those on the bus: by VID:PID and, when one is
// configured, by the USB serial number string. Outside the tick (it opens devices and reads
// string descriptors).
#pragma once

#include <libusb.h>

#include <cstdint>
#include <string>

#include "hapticd/device/usb/usb_settings.hpp"

namespace hapticd::device::usb {

struct FoundDevice {
    libusb_device_handle* handle = nullptr;  ///< open; the caller closes it
    int bus = 0;                             ///< libusb_get_bus_number
    int address = 0;                         ///< libusb_get_device_address
    std::string usb_serial;                  ///< iSerialNumber; empty if it has none
};

/// "/dev/bus/usb/001/004": the usbfs node, for messages about permissions.
std::string usbfs_node(int bus, int address);

/// Opens the first device with settings.vendor_id:product_id whose iSerialNumber equals
/// settings.serial_number (a device without an iSerialNumber matches any; the protocol's
/// identity is checked at the handshake anyway). Throws std::runtime_error:
///   - access denied: names the device node and the udev rule to install
///     (config/udev/70-hapticd.rules, docs/transport-usb.md);
///   - not found: what was looked for and every device that was seen.
FoundDevice find_device(libusb_context* context, const UsbSettings& settings);

}  // namespace hapticd::device::usb
