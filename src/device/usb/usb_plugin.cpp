// The `usb` plugin's entry point (plugin_abi.hpp): the open protocol (docs/protocol.md) over
// libusb-1.0 (docs/transport-usb.md).
#include "hapticd/device/link/protocol_device.hpp"
#include "hapticd/device/plugin_abi.hpp"
#include "hapticd/device/usb/make_usb_link.hpp"

namespace {

hapticd::device::Device* create_usb() {
    return new hapticd::device::link::ProtocolDevice("usb", hapticd::device::usb::make_usb_link);
}
void destroy_usb(hapticd::device::Device* device) { delete device; }

constexpr hapticd_device_plugin kUsbPlugin{
    hapticd::device::kDeviceAbiVersion,
    "usb",
    "hapticd protocol device on USB (libusb-1.0): interrupt or bulk endpoints, selected by "
    "VID, PID and serial number; reconnects when the device comes back",
    &create_usb,
    &destroy_usb,
};

}  // namespace

extern "C" __attribute__((visibility("default"))) const hapticd_device_plugin*
hapticd_device_plugin_entry(void) {
    return &kUsbPlugin;
}
