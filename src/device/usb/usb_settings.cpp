// The [device.usb] keys (usb_settings.hpp, docs/transport-usb.md).
#include "hapticd/device/usb/usb_settings.hpp"

#include <array>
#include <cstdio>
#include <string_view>
#include <utility>

namespace hapticd::device::usb {

const char* to_string(TransferKind kind) noexcept {
    switch (kind) {
        case TransferKind::automatic:
            return "automatic";
        case TransferKind::interrupt:
            return "interrupt";
        case TransferKind::bulk:
            return "bulk";
    }
    return "?";
}

std::string vid_pid_text(std::uint16_t vendor_id, std::uint16_t product_id) {
    std::array<char, 16> text{};
    std::snprintf(text.data(), text.size(), "%04x:%04x", vendor_id, product_id);
    return text.data();
}

namespace {

/// A USB ID (idVendor, idProduct: u16). TOML takes hex as written: vid = 0x1209.
std::uint16_t read_usb_id(TableReader& table, std::string_view key, std::uint16_t fallback) {
    const toml::node* node = table.get(key);
    if (node == nullptr) return fallback;
    const auto* value = node->as_integer();
    if (value == nullptr || value->get() < 0 || value->get() > 0xFFFF) {
        table.fail(key, value == nullptr ? "is not an integer" : "is out of range",
                   "0..0xFFFF, written in hex as lsusb shows it (" + std::string(key) + " = 0x" +
                       vid_pid_text(fallback, 0).substr(0, 4) + ")");
    }
    return static_cast<std::uint16_t>(value->get());
}

std::string_view to_name(TransferKind kind) noexcept { return to_string(kind); }
constexpr TransferKind kTransfers[] = {TransferKind::automatic, TransferKind::interrupt,
                                       TransferKind::bulk};

}  // namespace

UsbSettings read_usb_settings(TableReader& table, std::string serial_number) {
    UsbSettings settings;
    settings.source = table.source();
    settings.serial_number = std::move(serial_number);
    settings.vendor_id = read_usb_id(table, "vid", kDefaultVendorId);
    settings.product_id = read_usb_id(table, "pid", kDefaultProductId);
    // bInterfaceNumber is a u8 (USB 2.0 table 9-12).
    settings.interface_number = static_cast<int>(
        table.read(input::Integer{"interface", 0, 255, settings.interface_number}));
    settings.transfer = table.read(
        input::Choice<TransferKind>{"transfer", kTransfers, &to_name, settings.transfer});
    return settings;
}

}  // namespace hapticd::device::usb
