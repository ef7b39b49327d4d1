// The `hid` plugin's entry point (plugin_abi.hpp): the open protocol (docs/protocol.md) in
// HID reports through hidapi's hidraw backend (docs/transport-hid.md).
#include "hapticd/device/hid/hid_link.hpp"
#include "hapticd/device/link/protocol_device.hpp"
#include "hapticd/device/plugin_abi.hpp"

namespace {

hapticd::device::Device* create_hid() {
    return new hapticd::device::link::ProtocolDevice("hid", hapticd::device::hid::make_hid_link);
}
void destroy_hid(hapticd::device::Device* device) { delete device; }

constexpr hapticd_device_plugin kHidPlugin{
    hapticd::device::kDeviceAbiVersion,
    "hid",
    "open-protocol device over USB HID: 64-byte reports (output 1, input 2) through hidapi's "
    "hidraw backend; selected by vid, pid and serial number or by path",
    &create_hid,
    &destroy_hid,
};

}  // namespace

extern "C" __attribute__((visibility("default"))) const hapticd_device_plugin*
hapticd_device_plugin_entry(void) {
    return &kHidPlugin;
}
