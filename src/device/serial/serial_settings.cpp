// The [device.serial] keys (serial_settings.hpp, docs/transport-serial.md).
#include "hapticd/device/serial/serial_settings.hpp"

#include <algorithm>

namespace hapticd::device::serial {

std::string baud_rates_text() {
    std::string text;
    for (const std::uint32_t rate : kStandardBaudRates) {
        if (!text.empty()) text += ", ";
        text += std::to_string(rate);
    }
    return text;
}

bool is_standard_baud(std::int64_t baud) noexcept {
    return std::find(kStandardBaudRates.begin(), kStandardBaudRates.end(), baud) !=
           kStandardBaudRates.end();
}

SerialSettings read_serial_settings(TableReader& table) {
    SerialSettings settings;
    settings.source = table.source();

    settings.port = table.read(input::Text{
        "port", std::nullopt, false,
        "the serial port's path, e.g. \"/dev/serial/by-id/usb-...-if00\" (stable across "
        "replugging) or \"/dev/ttyACM0\""});

    if (const toml::node* baud = table.get("baud")) {
        const auto* value = baud->as_integer();
        if (value == nullptr || !is_standard_baud(value->get())) {
            table.fail("baud", "is not allowed", "one of the standard rates " + baud_rates_text());
        }
        settings.baud = static_cast<std::uint32_t>(value->get());
    }

    settings.reset_on_open = table.read(input::Flag{"reset_on_open", settings.reset_on_open});
    settings.reset_wait_ms = static_cast<std::uint32_t>(
        table.read(input::Integer{"reset_wait_ms", 0, 10'000, settings.reset_wait_ms, "ms"}));
    settings.exclusive = table.read(input::Flag{"exclusive", settings.exclusive});
    return settings;
}

}  // namespace hapticd::device::serial
