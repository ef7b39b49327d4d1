// Finding the configured device on the bus (usb_discovery.hpp, docs/transport-usb.md).
#include "hapticd/device/usb/usb_discovery.hpp"

#include <array>
#include <cstdio>
#include <stdexcept>
#include <vector>

namespace hapticd::device::usb {
namespace {

std::string quoted(const std::string& text) { return "\"" + text + "\""; }

std::string at_text(int bus, int address) {
    return "bus " + std::to_string(bus) + " device " + std::to_string(address);
}

/// The iSerialNumber string; empty if the device has none. `error` says why it could not be
/// read (a control transfer: the device may be misbehaving).
std::string read_usb_serial(libusb_device_handle* handle, std::uint8_t index, std::string& error) {
    if (index == 0) return {};
    std::array<unsigned char, 128> text{};
    const int length = libusb_get_string_descriptor_ascii(handle, index, text.data(),
                                                          static_cast<int>(text.size()));
    if (length < 0) {
        error = libusb_strerror(length);
        return {};
    }
    return std::string(reinterpret_cast<const char*>(text.data()),
                       static_cast<std::size_t>(length));
}

std::string looked_for(const UsbSettings& settings) {
    std::string text = vid_pid_text(settings.vendor_id, settings.product_id);
    if (!settings.serial_number.empty()) {
        text += " with serial number " + quoted(settings.serial_number);
    }
    return text;
}

std::string joined(const std::vector<std::string>& items) {
    std::string text;
    for (const std::string& item : items) text += (text.empty() ? "" : "; ") + item;
    return text;
}

}  // namespace

std::string usbfs_node(int bus, int address) {
    std::array<char, 32> path{};
    std::snprintf(path.data(), path.size(), "/dev/bus/usb/%03d/%03d", bus, address);
    return path.data();
}

FoundDevice find_device(libusb_context* context, const UsbSettings& settings) {
    libusb_device** list = nullptr;
    const ssize_t count = libusb_get_device_list(context, &list);
    if (count < 0) {
        throw std::runtime_error(std::string("usb: cannot list USB devices: ") +
                                 libusb_strerror(static_cast<int>(count)));
    }

    FoundDevice found;
    std::vector<std::string> seen;    // every device, for "not found"
    std::vector<std::string> denied;  // matching devices this user may not open
    std::vector<std::string> failed;  // matching devices that would not open for other reasons
    for (ssize_t i = 0; i < count && found.handle == nullptr; ++i) {
        libusb_device* device = list[i];
        libusb_device_descriptor descriptor{};
        if (libusb_get_device_descriptor(device, &descriptor) != LIBUSB_SUCCESS) continue;
        const int bus = libusb_get_bus_number(device);
        const int address = libusb_get_device_address(device);
        std::string entry = vid_pid_text(descriptor.idVendor, descriptor.idProduct) + " at " +
                            at_text(bus, address);
        if (descriptor.idVendor != settings.vendor_id ||
            descriptor.idProduct != settings.product_id) {
            seen.push_back(entry);
            continue;
        }

        libusb_device_handle* handle = nullptr;
        const int opened = libusb_open(device, &handle);
        if (opened == LIBUSB_ERROR_ACCESS) {
            denied.push_back(entry + " (" + usbfs_node(bus, address) + ")");
            seen.push_back(entry + " (permission denied)");
            continue;
        }
        if (opened != LIBUSB_SUCCESS) {
            failed.push_back(entry + ": " + libusb_strerror(opened));
            seen.push_back(entry + " (" + libusb_strerror(opened) + ")");
            continue;
        }
        std::string error;
        const std::string serial = read_usb_serial(handle, descriptor.iSerialNumber, error);
        if (!serial.empty()) entry += " with serial number " + quoted(serial);
        if (!error.empty()) entry += " (serial number unreadable: " + error + ")";
        // A device that reports no serial number (or cannot) is not refused here: the
        // protocol's identity, checked at the handshake, names the device for certain.
        if (!settings.serial_number.empty() && !serial.empty() &&
            serial != settings.serial_number) {
            seen.push_back(entry);
            libusb_close(handle);
            continue;
        }
        found.handle = handle;
        found.bus = bus;
        found.address = address;
        found.usb_serial = serial;
    }
    libusb_free_device_list(list, 1);
    if (found.handle != nullptr) return found;

    if (!denied.empty()) {
        throw std::runtime_error(
            "usb: permission denied opening " + joined(denied) +
            ": this user may not write to the device node. The udev rule that grants access "
            "is config/udev/70-hapticd.rules in the source tree, installed where udev reads it "
            "(/usr/lib/udev/rules.d by the .deb, /usr/local/lib/udev/rules.d by cmake "
            "--install); from a source tree, sudo cp config/udev/70-hapticd.rules "
            "/etc/udev/rules.d/. Then sudo udevadm control --reload-rules && sudo udevadm "
            "trigger, replug the device, and add the user to group plugdev (sudo usermod -aG "
            "plugdev $USER, then log in again). A device with its own VID:PID needs its own line "
            "in the rule (docs/transport-usb.md)");
    }
    if (!failed.empty()) {
        throw std::runtime_error("usb: cannot open " + joined(failed));
    }
    throw std::runtime_error(
        "usb: no device " + looked_for(settings) + " (device.usb.vid, device.usb.pid" +
        (settings.serial_number.empty() ? "" : ", device.usb.serial_number") + " in " +
        settings.source + "); seen: " + (seen.empty() ? "no USB devices at all" : joined(seen)) +
        ". Is it plugged in and powered? (lsusb lists what the kernel sees)");
}

}  // namespace hapticd::device::usb
