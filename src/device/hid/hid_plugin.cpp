// The `hid` plugin's entry point (plugin_abi.hpp): the open protocol (docs/protocol.md) in
// HID reports through hidapi's hidraw backend (docs/transport-hid.md).
#include "hapticd/device/hid/hid_link.hpp"
#include "hapticd/device/link/protocol_device.hpp"
#include "hapticd/device/plugin_abi.hpp"

namespace {

/// [device.hid] as ProtocolDevice::open() reads it, and nothing opened.
void check_hid_table(const hapticd::device::DeviceConfig& config) {
    hapticd::device::link::ProtocolDevice::check_config(config, "hid",
                                                        hapticd::device::hid::make_hid_link);
}

}  // namespace

HAPTICD_DEVICE_PLUGIN(
    "hid",
    "open-protocol device over USB HID: 64-byte reports (output 1, input 2) "
    "through hidapi's hidraw backend; selected by vid, pid and serial number or "
    "by path",
    check_hid_table,
    new hapticd::device::link::ProtocolDevice("hid", hapticd::device::hid::make_hid_link));
