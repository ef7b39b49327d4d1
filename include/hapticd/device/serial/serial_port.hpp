// Opening a serial port for the protocol (docs/transport-serial.md): the termios settings,
// DTR and HUPCL, exclusivity, low latency, and error messages that say what to do. Outside
// the tick only: everything here may allocate and throw.
#pragma once

#include <string>
#include <vector>

#include "hapticd/device/serial/serial_settings.hpp"

namespace hapticd::device::serial {

/// What open_serial_port() did besides opening, for describe() and the tests.
struct PortReport {
    bool low_latency = false;   ///< TIOCSSERIAL accepted ASYNC_LOW_LATENCY (not on a pty)
    int latency_timer_ms = -1;  ///< an FTDI adapter's latency timer after that; -1: none
    bool dtr_pulsed = false;    ///< reset_on_open: DTR was dropped and raised
};

/// Opens settings.port: O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC; with `exclusive`
/// flock(LOCK_EX | LOCK_NB) and TIOCEXCL; raw 8N1 (cfmakeraw, CLOCAL | CREAD, no flow
/// control, VMIN = VTIME = 0) at settings.baud, checked by reading the settings back; HUPCL
/// cleared unless reset_on_open (which then pulses DTR and waits reset_wait_ms); asks for
/// ASYNC_LOW_LATENCY (ignored where unsupported); flushes both directions. Returns the file
/// descriptor. Throws std::runtime_error from open_error_message() or naming the step that
/// failed.
int open_serial_port(const SerialSettings& settings, PortReport& report);

/// The message for open() failing with `error` (errno): not found (with the ports that do
/// exist), permission denied (the group to join, the udev rule), busy (who holds it), gone.
/// `by_id_dir` is where udev's stable names are (a parameter for the tests).
std::string open_error_message(int error, const SerialSettings& settings,
                               const std::string& by_id_dir = "/dev/serial/by-id");

/// "name -> target" for each entry of `by_id_dir` (empty if there is none), then the
/// /dev/ttyACM* and /dev/ttyUSB* nodes, sorted.
std::vector<std::string> present_ports(const std::string& by_id_dir = "/dev/serial/by-id");

/// "pid 1234 (minicom)" for each process that has `path` open (those /proc lets us see).
std::vector<std::string> port_holders(const std::string& path);

}  // namespace hapticd::device::serial
