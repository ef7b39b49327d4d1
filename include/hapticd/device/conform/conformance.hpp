// The conformance tester of docs/protocol.md section 9 (`haptic-tune conform`, docs/conform.md):
// a device on the open protocol, real or emulated, put through the firmware checklist over its
// own transport (any FrameLink: serial, USB, HID), at zero force. Each check says what it
// found: the evidence when it passes, the first broken promise, with the section, when it
// fails.
//
//   handshake        5.1, 4.2   hello -> identity of the session, its fields in range, the
//                               period the host's rate, the serial number if one is expected
//   versions         3.2, 4.1   the highest common version chosen; a range it does not speak
//                               refused with unsupported_version; a frame in another version
//                               refused with bad_version
//   sessions         5.1        no_session before hello and after bye, wrong_session for a
//                               stale session id, a new hello ending the old session,
//                               sample_sequence from 0 in each session
//   configure        4.3, 5.4   a watchdog timeout under two periods or over 1 s refused with
//                               out_of_range; one in range acknowledged as sent
//   commands         4.5, 4.6   every command answered with its sequence, sample_sequence +1,
//                               the clock rising, no fault; command_gap flagged; a command
//                               with the wrong axes refused and not applied; version 2's
//                               acknowledgements consistent (5.3)
//   timing           5.2, 5.7   one exchange per period for `timing_exchanges` commands: every
//                               one answered, the device's clock one period apart, the answer
//                               within a period (real time); the loop delay from version 2's
//                               acknowledgements
//   frame_errors     3.3, 3.4   a bad CRC, a truncated frame, a bad magic and garbage dropped
//                               in silence; the session still answers after them
//   message_errors   3.4, 4.10  an unknown type, a device-to-host type, a wrong payload size
//                               and a reserved bit answered with the right error code
//   watchdog         5.4, 5.5   the watchdog fault latched within [timeout, timeout + 2
//                               periods] after the last command while the host only polls;
//                               clear_faults ignored with enable set, honoured with it clear
//   bye              4.8, 5.1   bye -> bye_ack; the session closed after it
//
// The force itself is not visible over the link: that the motor is at zero after bye, on the
// watchdog and on a fault is for an instrument (the firmware-in-the-loop tests read the
// motor's pins). Every command the tester sends asks for zero force.
//
// Time: in real time the tester sends at most one request per period, so a device's own clock
// runs as it would under hapticd; with `lockstep` (an emulated board that runs a period per
// request) it does not wait, and round trips are not judged.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hapticd/device/link/frame_link.hpp"
#include "hapticd/device/protocol/messages.hpp"

namespace hapticd::device::conform {

enum class Outcome : std::uint8_t { pass, fail, skipped };
/// "pass", "FAIL", "skipped".
std::string_view to_string(Outcome outcome) noexcept;

struct CheckResult {
    std::string name;     ///< "handshake", ... (the table above)
    std::string section;  ///< of docs/protocol.md: "5.1, 4.2"
    Outcome outcome = Outcome::skipped;
    std::string detail;  ///< pass: what was seen; fail: what broke; skipped: why
};

struct ConformOptions {
    double rate_hz = 1000.0;  ///< the host's rate ([servo] rate_hz): the identity must match
    /// The watchdog timeout the watchdog check configures, us; >= 2 periods and <= 1 s.
    std::uint32_t watchdog_timeout_us = 20'000;
    int timing_exchanges = 1000;  ///< commands in the timing check (1 s at 1 kHz)
    bool lockstep = false;        ///< the device runs a period per request (see the comment)
    std::string expected_serial;  ///< empty: any serial number
    /// How long an answer may take, and how long silence must last to count as silence.
    std::int64_t reply_timeout_ns = 100'000'000;
};

struct ConformReport {
    std::string device;  ///< the link's describe()
    std::optional<protocol::Identity> identity;
    std::vector<CheckResult> checks;
    /// No check failed (a skipped check is not a pass: passed() is false if any was skipped
    /// because an earlier one failed).
    bool passed() const noexcept;
};

/// Opens `link`, runs every check in the order above, says bye and closes it. Never throws
/// for what the device does (that is a failed check); throws std::invalid_argument for bad
/// options and std::runtime_error when the link cannot be opened.
ConformReport run_conformance(link::FrameLink& link, const ConformOptions& options);

}  // namespace hapticd::device::conform
