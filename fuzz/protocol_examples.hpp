// The worked examples of docs/protocol.md section 8 and the seed corpus of the protocol fuzzer,
// both produced by the encoder (never written by hand). One list serves three users:
//   fuzz/protocol_corpus.cpp   writes the seed corpus and prints the document's examples;
//   tests/device/protocol      checks that docs/protocol.md holds exactly these examples.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "hapticd/device/protocol/messages.hpp"
#include "hapticd/device/protocol/stream_framer.hpp"
#include "hapticd/device/protocol/transport.hpp"

namespace hapticd::device::protocol::examples {

struct Example {
    std::string name;  ///< corpus file name (without extension) and anchor
    std::string title;
    std::string description;
    std::vector<std::byte> bytes;  ///< one frame; or a byte stream / HID report, see `kind`
    enum class Kind { frame, stream, hid_report } kind = Kind::frame;
};

inline std::vector<std::byte> encode_or_throw(const Message& message) {
    std::array<std::byte, kMaxFrameSize> frame{};
    const Encoded encoded = encode(message, frame);
    if (!encoded.ok()) {
        throw std::logic_error("example does not encode: " + std::string(to_string(encoded.error)));
    }
    return {frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(encoded.size)};
}

inline constexpr std::uint32_t kExampleSession = 0x5EC7A3B1u;

/// Valid frames of every message type: a session as a host and a firmware would hold it, in
/// protocol version 2 (what hapticd offers), and a version-1 firmware's sample.
inline std::vector<Example> frame_examples() {
    std::vector<Example> out;
    auto add = [&out](std::string name, std::string title, std::string description,
                      const Message& message) {
        out.push_back({std::move(name), std::move(title), std::move(description),
                       encode_or_throw(message), Example::Kind::frame});
    };

    Hello hello;
    hello.session = kExampleSession;
    hello.min_version = 1;
    hello.max_version = 2;
    add("hello", "hello",
        "The host opens session 0x5EC7A3B1 and offers versions 1..2 (the header says 1: hello "
        "is frozen).",
        hello);

    Identity identity;
    identity.session = kExampleSession;
    identity.axes = 3;
    identity.force_limit_un = 20'000'000;
    identity.counts_per_meter = 100'000.0;
    identity.period_us = 1000;
    identity.watchdog_timeout_us = 20'000;
    identity.firmware_version = 0x00010203;
    identity.set_serial_number("HD3-000042");
    identity.version = kProtocolVersion2;
    add("identity", "identity",
        "The device picks version 2 (the header's version byte; every later frame of the "
        "session has it): a 3-axis device, 20 N per axis, 1e5 counts/m, 1 kHz, watchdog 20 ms, "
        "firmware 0x00010203, serial \"HD3-000042\".",
        identity);

    Configure configure;
    configure.session = kExampleSession;
    configure.watchdog_timeout_us = 50'000;
    configure.version = kProtocolVersion2;
    add("configure", "configure", "Set the watchdog timeout to 50 ms.", configure);

    ConfigureAck ack;
    ack.session = kExampleSession;
    ack.watchdog_timeout_us = 50'000;
    ack.version = kProtocolVersion2;
    add("configure_ack", "configure_ack", "The device now trips after 50 ms without a command.",
        ack);

    Poll poll;
    poll.session = kExampleSession;
    poll.version = kProtocolVersion2;
    add("poll", "poll", "Ask for a sample without commanding anything.", poll);

    EncoderSample first;
    first.session = kExampleSession;
    first.command_sequence = 0;
    first.sample_sequence = 0;
    first.time_us = 5'000'000;
    first.axes = 3;
    first.counts = {1000, -250, 0};
    first.version = kProtocolVersion2;
    add("sample_poll", "sample (answer to poll)",
        "No command yet (command_sequence 0; applied_lag 0xFF and applied_age_us 0xFFFF: none "
        "in effect); sample 0 at device time 5 s; counts 1000, -250, 0.",
        first);

    ForceCommand command;
    command.session = kExampleSession;
    command.sequence = 1;
    command.flags = kCommandEnable;
    command.axes = 3;
    command.force_un = {1'500'000, -250'000, 0};
    command.version = kProtocolVersion2;
    add("command_3axis", "command (3 axes)", "Command 1, enabled: +1.5 N, -0.25 N, 0 N.", command);

    EncoderSample sample;
    sample.session = kExampleSession;
    sample.command_sequence = 1;
    sample.sample_sequence = 1;
    sample.time_us = 5'001'000;
    sample.status = kSampleForceActive;
    sample.axes = 3;
    sample.counts = {1003, -251, 0};
    sample.version = kProtocolVersion2;
    sample.applied_lag = 0;
    sample.applied_age_us = 1000;
    add("sample_3axis", "sample (3 axes)",
        "The answer to command 1: sample 1, 1 ms later, force active; command 1 (applied_lag 0) "
        "in effect for 1000 us (applied_age_us 0x03e8), so since device time 5 s: it took "
        "effect on arrival; counts 1003, -251, 0.",
        sample);

    EncoderSample pipelined = sample;
    pipelined.command_sequence = 2;
    pipelined.sample_sequence = 2;
    pipelined.time_us = 5'002'000;
    pipelined.applied_lag = 1;
    pipelined.applied_age_us = 500;
    pipelined.counts = {1006, -252, 0};
    add("sample_3axis_pipelined", "sample (3 axes, a device 1.5 periods behind)",
        "A device whose force takes effect 1.5 ms after a command arrives answers command 2 "
        "before command 2 acts: command 1 (applied_lag 1) is in effect, for 500 us "
        "(applied_age_us 0x01f4), since device time 5.0015 s, 1.5 ms after sample 0 that it "
        "was computed from.",
        pipelined);

    ForceCommand command1;
    command1.session = kExampleSession;
    command1.sequence = 0xFFFFFFFFu;
    command1.flags = kCommandEnable;
    command1.axes = 1;
    command1.force_un = {-2'000'000, 0, 0};
    command1.version = kProtocolVersion2;
    add("command_1axis", "command (1 axis)",
        "A 1-axis device: command 0xFFFFFFFF (the next is 0: sequences wrap), -2 N.", command1);

    EncoderSample sample1;
    sample1.session = kExampleSession;
    sample1.command_sequence = 0xFFFFFFFFu;
    sample1.sample_sequence = 70'000;
    sample1.time_us = 0x0000000100000000ull;
    sample1.status = kSampleCommandLate;
    sample1.faults = kDeviceFaultWatchdog;
    sample1.axes = 1;
    sample1.counts = {-5'000'000'000ll, 0, 0};
    sample1.version = kProtocolVersion2;
    sample1.applied_lag = 0;
    sample1.applied_age_us = 0;
    add("sample_1axis_fault", "sample (1 axis, watchdog tripped)",
        "The command came after the watchdog had tripped: command_late, fault watchdog (force "
        "zero; the command is still the one in effect, applied_lag 0, latched at once, "
        "applied_age_us 0); counts -5e9 (beyond int32); device time 2^32 us.",
        sample1);

    EncoderSample old = sample;
    old.version = kProtocolVersion1;
    old.applied_lag = kAppliedLagNone;
    old.applied_age_us = kAppliedAgeUnknown;
    add("sample_3axis_version1", "sample (3 axes, a version-1 firmware)",
        "The answer to command 1 from a device that speaks only version 1: version byte 1, and "
        "bytes 29..31 reserved (zero): it does not say when the command took effect.",
        old);

    ForceCommand clear;
    clear.session = kExampleSession;
    clear.sequence = 2;
    clear.flags = kCommandClearFaults;
    clear.axes = 3;
    clear.version = kProtocolVersion2;
    add("command_clear_faults", "command (clear faults)",
        "Enable off and clear_faults: the device clears its latched faults and holds zero.", clear);

    Bye bye;
    bye.session = kExampleSession;
    bye.version = kProtocolVersion2;
    add("bye", "bye", "The host closes the session.", bye);

    ByeAck bye_ack;
    bye_ack.session = kExampleSession;
    bye_ack.version = kProtocolVersion2;
    add("bye_ack", "bye_ack", "The device holds zero force and has closed the session.", bye_ack);

    ErrorReport unsupported;
    unsupported.session = kExampleSession;
    unsupported.code = ErrorCode::unsupported_version;
    unsupported.request_type = static_cast<std::uint8_t>(MessageType::hello);
    unsupported.detail = 0x0403;
    add("error_unsupported_version", "error (unsupported_version)",
        "A device that speaks versions 3..4 refuses a hello offering 1..2: detail = min | max << "
        "8.",
        unsupported);

    ErrorReport wrong_session;
    wrong_session.session = 0x0BADCAFEu;
    wrong_session.code = ErrorCode::wrong_session;
    wrong_session.request_type = static_cast<std::uint8_t>(MessageType::command);
    add("error_wrong_session", "error (wrong_session)",
        "A command from an old session 0x0BADCAFE is refused, not applied.", wrong_session);
    return out;
}

/// The same frames as they look on a serial line and in HID reports.
inline std::vector<Example> transport_examples() {
    std::vector<Example> out;
    const std::vector<Example> frames = frame_examples();
    auto find = [&frames](const std::string& name) -> const std::vector<std::byte>& {
        for (const Example& e : frames) {
            if (e.name == name) return e.bytes;
        }
        throw std::logic_error("no example " + name);
    };

    const std::vector<std::byte>& command = find("command_3axis");
    std::array<std::byte, kMaxStreamFrameSize> stream{};
    const Encoded encoded = encode_stream(command, stream);
    std::vector<std::byte> serial{std::byte{0x00}};  // the host's leading delimiter
    serial.insert(serial.end(), stream.begin(),
                  stream.begin() + static_cast<std::ptrdiff_t>(encoded.size));
    out.push_back({"serial_command_3axis", "serial: command (3 axes)",
                   "The 3-axis command as COBS bytes on a serial line, after the leading 0x00 "
                   "the host sends once when it opens the port, and with the 0x00 delimiter.",
                   serial, Example::Kind::stream});

    std::array<std::byte, hid::kReportSize> report{};
    hid::wrap_report(hid::kInputReportId, find("sample_3axis"), report);
    out.push_back({"hid_sample_3axis",
                   "HID: sample (3 axes)",
                   "The 3-axis sample in input report 2: report ID, the 60-byte frame, 3 bytes "
                   "of zero padding.",
                   {report.begin(), report.end()},
                   Example::Kind::hid_report});
    return out;
}

inline std::string hex_lines(std::span<const std::byte> bytes) {
    std::string text;
    char buffer[4];
    for (std::size_t i = 0; i < bytes.size(); ++i) {
        std::snprintf(buffer, sizeof buffer, "%02x", static_cast<unsigned>(bytes[i]));
        text += buffer;
        text += (i + 1) % 16 == 0 || i + 1 == bytes.size() ? "\n" : " ";
    }
    return text;
}

/// The document's section 8 body, between its BEGIN/END markers.
inline std::string markdown() {
    std::string text;
    std::vector<Example> all = frame_examples();
    for (Example& e : transport_examples()) all.push_back(std::move(e));
    for (const Example& e : all) {
        text += "#### " + e.title + "\n\n" + e.description + " " + std::to_string(e.bytes.size()) +
                " bytes:\n\n```\n" + hex_lines(e.bytes) + "```\n\n";
    }
    return text;
}

inline constexpr const char* kMarkdownBegin =
    "<!-- BEGIN GENERATED EXAMPLES (fuzz/protocol_corpus --markdown) -->";
inline constexpr const char* kMarkdownEnd = "<!-- END GENERATED EXAMPLES -->";

}  // namespace hapticd::device::protocol::examples
