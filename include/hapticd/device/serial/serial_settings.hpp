// The [device.serial] keys (docs/transport-serial.md): which port, at which baud rate, and
// how to open it. Read once in Device::open(), outside the tick.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "hapticd/device/plugin_table.hpp"

namespace hapticd::device::serial {

/// The rates the plugin accepts: the Linux B-constants from 9600 to 4000000 baud
/// (<termios.h>), every one a rate that cfsetspeed() can ask a UART driver for by name.
/// 1200 is left out on purpose: opening a native-USB Arduino (ATmega32u4, SAMD) at 1200 baud
/// and closing it starts its bootloader.
inline constexpr std::array<std::uint32_t, 18> kStandardBaudRates{
    9'600,     19'200,    38'400,    57'600,    115'200,   230'400,
    460'800,   500'000,   576'000,   921'600,   1'000'000, 1'152'000,
    1'500'000, 2'000'000, 2'500'000, 3'000'000, 3'500'000, 4'000'000};

/// docs/protocol.md section 6.3: 2 Mbaud carries a 3-axis command and sample in 0.48 ms.
inline constexpr std::uint32_t kDefaultBaud = 2'000'000;

struct SerialSettings {
    std::string port;                   ///< device.serial.port: a path, e.g. /dev/ttyACM0
    std::uint32_t baud = kDefaultBaud;  ///< device.serial.baud: one of kStandardBaudRates
    /// device.serial.reset_on_open: pulse DTR on open (reset an Arduino-style board on
    /// purpose) and wait reset_wait_ms for its bootloader; false (default): leave DTR alone
    /// and clear HUPCL so that closing does not reset the board either.
    bool reset_on_open = false;
    std::uint32_t reset_wait_ms = 2000;  ///< device.serial.reset_wait_ms, 0..10000

    /// device.serial.exclusive: TIOCEXCL and flock(LOCK_EX) so that no other program (a
    /// serial monitor, ModemManager) opens the port while hapticd uses it.
    bool exclusive = true;

    // Not keys: filled in from the rest of the configuration.
    std::int64_t write_timeout_ns = 1'000'000;  ///< send() waits this long for room; 1 period
    std::string source = "<config>";            ///< the config file, for messages
};

/// "9600, 19200, ..., 4000000": the allowed rates, for messages.
std::string baud_rates_text();

/// True if `baud` is one of kStandardBaudRates.
bool is_standard_baud(std::int64_t baud) noexcept;

/// Reads the keys above from the plugin's table (the reader remembers them; the caller calls
/// finish()). Throws std::runtime_error naming the file and device.serial.<key>: port missing
/// or empty, a baud rate not in the list, a value of the wrong type.
SerialSettings read_serial_settings(TableReader& table);

}  // namespace hapticd::device::serial
