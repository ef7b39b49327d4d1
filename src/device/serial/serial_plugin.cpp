// The `serial` plugin's entry point (plugin_abi.hpp): the open protocol (ProtocolDevice)
// over a serial port (SerialLink). docs/transport-serial.md.
#include "hapticd/device/link/protocol_device.hpp"
#include "hapticd/device/plugin_abi.hpp"
#include "hapticd/device/serial/serial_link.hpp"

namespace {

hapticd::device::Device* create_serial() {
    return new hapticd::device::link::ProtocolDevice("serial",
                                                     &hapticd::device::serial::make_serial_link);
}
void destroy_serial(hapticd::device::Device* device) { delete device; }

constexpr hapticd_device_plugin kSerialPlugin{
    hapticd::device::kDeviceAbiVersion,
    "serial",
    "the open device protocol (docs/protocol.md) over a serial port: UART or USB CDC-ACM, "
    "termios raw, COBS framing; [device.serial] port, baud",
    &create_serial,
    &destroy_serial,
};

}  // namespace

extern "C" __attribute__((visibility("default"))) const hapticd_device_plugin*
hapticd_device_plugin_entry(void) {
    return &kSerialPlugin;
}
