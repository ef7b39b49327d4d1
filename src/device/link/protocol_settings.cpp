// Reads the keys every protocol plugin shares from its [device.<plugin>] table
// (docs/devices.md, "Keys every transport has").
#include "hapticd/device/link/protocol_settings.hpp"

#include <cmath>
#include <string>

#include "hapticd/device/protocol/messages.hpp"

namespace hapticd::device::link {

ProtocolSettings read_protocol_settings(TableReader& table, const DeviceConfig& config) {
    using input::Number;
    using input::Range;
    ProtocolSettings s;
    s.serial_number = table.read(input::Text{"serial_number", "", true});
    if (table.has("serial_number")) {
        protocol::Identity probe;
        if (!probe.set_serial_number(s.serial_number)) {
            table.fail("serial_number", "is not allowed",
                       "1 to 16 printable ASCII characters (docs/protocol.md 4.2)");
        }
    }
    const double period_ms = 1e3 / config.rate_hz;
    const auto us = [](double ms) { return static_cast<std::uint32_t>(std::lround(ms * 1e3)); };
    s.watchdog_us =
        us(table.read(Number{"watchdog_ms",
                             {.lo = 2.0 * period_ms, .hi = 1000.0, .unit = "ms, 2 periods to 1 s"},
                             s.watchdog_us / 1e3}));
    s.reply_timeout_us = us(table.read(Number{
        "reply_timeout_ms", {.lo = 0.0, .hi = 1000.0, .unit = "ms"}, s.reply_timeout_us / 1e3}));
    s.handshake_timeout_us = us(table.read(Number{"handshake_timeout_ms",
                                                  {.lo = 1.0, .hi = 10000.0, .unit = "ms"},
                                                  s.handshake_timeout_us / 1e3}));
    s.reconnect = table.read(input::Flag{"reconnect", s.reconnect});
    s.reconnect_interval_us = us(table.read(Number{"reconnect_interval_ms",
                                                   {.lo = 10.0, .hi = 60000.0, .unit = "ms"},
                                                   s.reconnect_interval_us / 1e3}));
    return s;
}

}  // namespace hapticd::device::link
