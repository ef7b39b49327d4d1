// The protocol's interface and endpoints in a configuration descriptor (usb_endpoints.hpp,
// docs/protocol.md 6.1).
#include "hapticd/device/usb/usb_endpoints.hpp"

#include <array>
#include <cstdio>
#include <stdexcept>

#include "hapticd/device/protocol/transport.hpp"

namespace hapticd::device::usb {
namespace {

namespace usb_ids = protocol::usb;

std::string hex2(unsigned value) {
    std::array<char, 8> text{};
    std::snprintf(text.data(), text.size(), "%02x", value & 0xFFu);
    return text.data();
}

const char* type_name(std::uint8_t transfer_type) {
    switch (transfer_type) {
        case LIBUSB_TRANSFER_TYPE_CONTROL:
            return "control";
        case LIBUSB_TRANSFER_TYPE_ISOCHRONOUS:
            return "isochronous";
        case LIBUSB_TRANSFER_TYPE_BULK:
            return "bulk";
        case LIBUSB_TRANSFER_TYPE_INTERRUPT:
            return "interrupt";
        default:
            return "?";
    }
}

bool is_protocol_interface(const libusb_interface_descriptor& alt) {
    return alt.bInterfaceClass == usb_ids::kInterfaceClass &&
           alt.bInterfaceSubClass == usb_ids::kInterfaceSubClass &&
           alt.bInterfaceProtocol == usb_ids::kInterfaceProtocol;
}

/// "0 (ff/48/01, 2 endpoints), 1 (03/00/00, 1 endpoint)": every alternate setting, for messages.
std::string list_interfaces(const libusb_config_descriptor& config) {
    std::string text;
    for (int i = 0; i < config.bNumInterfaces; ++i) {
        const libusb_interface& interface = config.interface[i];
        for (int a = 0; a < interface.num_altsetting; ++a) {
            const libusb_interface_descriptor& alt = interface.altsetting[a];
            if (!text.empty()) text += ", ";
            text += std::to_string(alt.bInterfaceNumber);
            if (alt.bAlternateSetting != 0) text += " alt " + std::to_string(alt.bAlternateSetting);
            text += " (" + hex2(alt.bInterfaceClass) + "/" + hex2(alt.bInterfaceSubClass) + "/" +
                    hex2(alt.bInterfaceProtocol) + ", " + std::to_string(alt.bNumEndpoints) +
                    " endpoints)";
        }
    }
    return text.empty() ? "none" : text;
}

UsbEndpoint endpoint_of(const libusb_endpoint_descriptor& descriptor) {
    UsbEndpoint endpoint;
    endpoint.address = descriptor.bEndpointAddress;
    endpoint.transfer_type = descriptor.bmAttributes & LIBUSB_TRANSFER_TYPE_MASK;
    endpoint.max_packet_size = descriptor.wMaxPacketSize & 0x7FFu;  // bits 11-12: HS extra
    endpoint.interval = descriptor.bInterval;
    return endpoint;
}

bool is_frame_endpoint(const libusb_endpoint_descriptor& descriptor) {
    const int type = descriptor.bmAttributes & LIBUSB_TRANSFER_TYPE_MASK;
    return type == LIBUSB_TRANSFER_TYPE_INTERRUPT || type == LIBUSB_TRANSFER_TYPE_BULK;
}

const libusb_interface_descriptor* find_interface(const libusb_config_descriptor& config,
                                                  const UsbSettings& settings) {
    for (int i = 0; i < config.bNumInterfaces; ++i) {
        const libusb_interface& interface = config.interface[i];
        for (int a = 0; a < interface.num_altsetting; ++a) {
            const libusb_interface_descriptor& alt = interface.altsetting[a];
            if (settings.interface_number >= 0) {
                // The configured interface, whatever its class: its first alternate setting.
                if (alt.bInterfaceNumber == settings.interface_number) return &alt;
            } else if (is_protocol_interface(alt)) {
                return &alt;
            }
        }
    }
    return nullptr;
}

}  // namespace

std::string UsbEndpoints::describe() const {
    std::string text = "interface " + std::to_string(interface_number);
    if (alt_setting != 0) text += " alt " + std::to_string(alt_setting);
    text += ", " + std::string(type_name(in.transfer_type)) + " IN 0x" + hex2(in.address) + " / " +
            type_name(out.transfer_type) + " OUT 0x" + hex2(out.address) + ", " +
            std::to_string(in.max_packet_size) + " bytes, bInterval " + std::to_string(in.interval);
    return text;
}

UsbEndpoints select_endpoints(const libusb_config_descriptor& config, const UsbSettings& settings,
                              const std::string& where) {
    const libusb_interface_descriptor* alt = find_interface(config, settings);
    if (alt == nullptr) {
        if (settings.interface_number >= 0) {
            throw std::runtime_error(
                where + " has no interface " + std::to_string(settings.interface_number) + " (" +
                settings.source +
                ": device.usb.interface); its interfaces: " + list_interfaces(config));
        }
        throw std::runtime_error(
            where +
            " has no hapticd protocol interface (class ff, subclass 48, protocol 01; "
            "docs/protocol.md 6.1); its interfaces: " +
            list_interfaces(config) +
            ". Set device.usb.interface if the firmware uses another class, or check "
            "device.usb.vid and device.usb.pid in " +
            settings.source);
    }

    UsbEndpoints endpoints;
    endpoints.interface_number = alt->bInterfaceNumber;
    endpoints.alt_setting = alt->bAlternateSetting;
    bool have_in = false;
    bool have_out = false;
    for (int e = 0; e < alt->bNumEndpoints; ++e) {
        const libusb_endpoint_descriptor& descriptor = alt->endpoint[e];
        if (!is_frame_endpoint(descriptor)) continue;
        const bool in = (descriptor.bEndpointAddress & LIBUSB_ENDPOINT_IN) != 0;
        if (in && !have_in) {
            endpoints.in = endpoint_of(descriptor);
            have_in = true;
        } else if (!in && !have_out) {
            endpoints.out = endpoint_of(descriptor);
            have_out = true;
        }
    }
    const std::string interface_text =
        where + " interface " + std::to_string(alt->bInterfaceNumber);
    if (!have_in || !have_out) {
        throw std::runtime_error(interface_text + " lacks an interrupt or bulk " +
                                 (have_in ? "OUT" : "IN") +
                                 " endpoint: the protocol needs one each way "
                                 "(docs/protocol.md 6.1)");
    }

    for (UsbEndpoint* endpoint : {&endpoints.in, &endpoints.out}) {
        if (endpoint->max_packet_size < usb_ids::kMaxPacketSize) {
            throw std::runtime_error(
                interface_text + " endpoint 0x" + hex2(endpoint->address) + " has wMaxPacketSize " +
                std::to_string(endpoint->max_packet_size) + ": a frame (up to " +
                std::to_string(protocol::kMaxFrameSize) +
                " bytes) must fit one packet, so at least 64 (full speed; docs/protocol.md 6.1)");
        }
        switch (settings.transfer) {
            case TransferKind::automatic:
                break;
            case TransferKind::bulk:
                // Linux usbfs submits a bulk URB on an interrupt endpoint as a one-shot
                // interrupt transfer, so this works on either kind.
                endpoint->transfer_type = LIBUSB_TRANSFER_TYPE_BULK;
                break;
            case TransferKind::interrupt:
                if (endpoint->transfer_type != LIBUSB_TRANSFER_TYPE_INTERRUPT) {
                    throw std::runtime_error(
                        settings.source + ": device.usb.transfer = \"interrupt\", but " +
                        interface_text + " endpoint 0x" + hex2(endpoint->address) + " is " +
                        type_name(endpoint->transfer_type) +
                        "; use transfer = \"bulk\" or leave the key out");
                }
                break;
        }
    }
    return endpoints;
}

}  // namespace hapticd::device::usb
