// The `serial` plugin's entry point (plugin_abi.hpp): the open protocol (ProtocolDevice)
// over a serial port (SerialLink). docs/transport-serial.md.
#include "hapticd/device/link/protocol_device.hpp"
#include "hapticd/device/plugin_abi.hpp"
#include "hapticd/device/serial/serial_link.hpp"

HAPTICD_DEVICE_PLUGIN("serial",
                      "the open device protocol (docs/protocol.md) over a serial port: UART or USB "
                      "CDC-ACM, termios raw, COBS framing; [device.serial] port, baud",
                      new hapticd::device::link::ProtocolDevice(
                          "serial", &hapticd::device::serial::make_serial_link));
