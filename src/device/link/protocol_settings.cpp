// Reads the keys every protocol plugin shares from its [device.<plugin>] table
// (docs/devices.md, "Keys every transport has").
#include "hapticd/device/link/protocol_settings.hpp"

#include <cmath>
#include <string>

#include "hapticd/device/protocol/messages.hpp"

namespace hapticd::device::link {

ProtocolSettings read_protocol_settings(TableReader& table, const DeviceConfig& config) {
    ProtocolSettings s;
    s.serial_number = table.string("serial_number", "");
    if (const toml::node* node = table.get("serial_number"); node != nullptr) {
        protocol::Identity probe;
        if (!probe.set_serial_number(s.serial_number)) {
            table.fail_value("serial_number", *node,
                             "1 to 16 printable ASCII characters (docs/protocol.md 4.2)");
        }
    }
    const double period_ms = 1e3 / config.rate_hz;
    const double watchdog_ms = table.number(
        "watchdog_ms", 20.0, Range{2.0 * period_ms, 1000.0, false, "ms, 2 periods to 1 s"});
    s.watchdog_us = static_cast<std::uint32_t>(std::lround(watchdog_ms * 1e3));
    const double reply_ms = table.number("reply_timeout_ms", 0.0, Range{0.0, 1000.0, false, "ms"});
    s.reply_timeout_us = static_cast<std::uint32_t>(std::lround(reply_ms * 1e3));
    const double handshake_ms =
        table.number("handshake_timeout_ms", 200.0, Range{1.0, 10000.0, false, "ms"});
    s.handshake_timeout_us = static_cast<std::uint32_t>(std::lround(handshake_ms * 1e3));
    s.reconnect = table.boolean("reconnect", true);
    const double interval_ms =
        table.number("reconnect_interval_ms", 250.0, Range{10.0, 60000.0, false, "ms"});
    s.reconnect_interval_us = static_cast<std::uint32_t>(std::lround(interval_ms * 1e3));
    return s;
}

}  // namespace hapticd::device::link
