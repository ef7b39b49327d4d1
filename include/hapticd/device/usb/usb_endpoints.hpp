// Which interface and endpoints of a device carry the protocol (docs/protocol.md 6.1): a pure
// function of the device's configuration descriptor, so that it is tested without a device.
#pragma once

#include <libusb.h>

#include <cstdint>
#include <string>

#include "hapticd/device/usb/usb_settings.hpp"

namespace hapticd::device::usb {

/// The libusb transfer type used on an endpoint (LIBUSB_TRANSFER_TYPE_INTERRUPT or _BULK).
struct UsbEndpoint {
    std::uint8_t address = 0;  ///< bEndpointAddress, e.g. 0x81
    std::uint8_t transfer_type = LIBUSB_TRANSFER_TYPE_INTERRUPT;
    std::uint16_t max_packet_size = 0;  ///< bytes per packet (wMaxPacketSize bits 0..10)
    std::uint8_t interval = 0;          ///< bInterval
};

struct UsbEndpoints {
    int interface_number = 0;  ///< bInterfaceNumber
    int alt_setting = 0;       ///< bAlternateSetting
    UsbEndpoint in;            ///< device -> host
    UsbEndpoint out;           ///< host -> device

    /// "interface 0, interrupt IN 0x81 / OUT 0x01, 64 bytes, bInterval 1"
    std::string describe() const;
};

/// Picks the interface (settings.interface_number, or the first alternate setting with class
/// 0xFF, subclass 0x48, protocol 0x01) and its first IN and first OUT endpoint of type
/// interrupt or bulk, checks them against settings.transfer and the protocol (one frame per
/// packet: wMaxPacketSize >= 64), and returns them. Throws std::runtime_error saying what the
/// device offers instead; `where` names the device ("usb 1209:0001 (bus 1 device 4)").
UsbEndpoints select_endpoints(const libusb_config_descriptor& config, const UsbSettings& settings,
                              const std::string& where);

}  // namespace hapticd::device::usb
