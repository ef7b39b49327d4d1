// The `usb` plugin's entry point (plugin_abi.hpp): the open protocol (docs/protocol.md) over
// libusb-1.0 (docs/transport-usb.md).
#include "hapticd/device/link/protocol_device.hpp"
#include "hapticd/device/plugin_abi.hpp"
#include "hapticd/device/usb/make_usb_link.hpp"

namespace {

/// [device.usb] as ProtocolDevice::open() reads it, and nothing opened.
void check_usb_table(const hapticd::device::DeviceConfig& config) {
    hapticd::device::link::ProtocolDevice::check_config(config, "usb",
                                                        hapticd::device::usb::make_usb_link);
}

}  // namespace

HAPTICD_DEVICE_PLUGIN(
    "usb",
    "hapticd protocol device on USB (libusb-1.0): interrupt or bulk endpoints, "
    "selected by VID, PID and serial number; reconnects when the device comes "
    "back",
    check_usb_table,
    new hapticd::device::link::ProtocolDevice("usb", hapticd::device::usb::make_usb_link));
