// The `serial` plugin's entry point (plugin_abi.hpp): the open protocol (ProtocolDevice)
// over a serial port (SerialLink). docs/transport-serial.md.
#include "hapticd/device/link/protocol_device.hpp"
#include "hapticd/device/plugin_abi.hpp"
#include "hapticd/device/serial/serial_link.hpp"

namespace {

/// [device.serial] as ProtocolDevice::open() reads it, and nothing opened (the port is
/// named, not opened).
void check_serial_table(const hapticd::device::DeviceConfig& config) {
    hapticd::device::link::ProtocolDevice::check_config(config, "serial",
                                                        &hapticd::device::serial::make_serial_link);
}

}  // namespace

HAPTICD_DEVICE_PLUGIN("serial",
                      "the open device protocol (docs/protocol.md) over a serial port: UART or USB "
                      "CDC-ACM, termios raw, COBS framing; [device.serial] port, baud",
                      check_serial_table,
                      new hapticd::device::link::ProtocolDevice(
                          "serial", &hapticd::device::serial::make_serial_link));
