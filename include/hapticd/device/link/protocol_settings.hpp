// The [device.<plugin>] keys that every protocol transport shares (docs/devices.md):
//
//   serial_number          expected device serial ("" = any; then the first one seen is
//                          required on reconnect)
//   watchdog_ms            device command watchdog, 2 periods .. 1000 ms (default 20)
//   reply_timeout_ms       how long read() waits for a reply (0 = 30 % of a period in real
//                          time, 1 s in lockstep)
//   handshake_timeout_ms   per hello attempt (default 200)
//   reconnect              reopen a device that went away (default true)
//   reconnect_interval_ms  between reopen attempts (default 250)
#pragma once

#include <cstdint>
#include <string>

#include "hapticd/device/device.hpp"
#include "hapticd/device/plugin_table.hpp"

namespace hapticd::device::link {

struct ProtocolSettings {
    std::string serial_number;
    std::uint32_t watchdog_us = 20'000;
    std::uint32_t reply_timeout_us = 0;
    std::uint32_t handshake_timeout_us = 200'000;
    bool reconnect = true;
    std::uint32_t reconnect_interval_us = 250'000;
};

/// Reads the keys above; errors name config.source, the key, the value and the range.
ProtocolSettings read_protocol_settings(TableReader& table, const DeviceConfig& config);

}  // namespace hapticd::device::link
