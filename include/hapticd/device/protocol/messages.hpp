// The ten messages of protocol versions 1 and 2, their encoders and their decoders
// (docs/protocol.md section 4; each struct names its section).
//
// Every message but the frozen hello and error carries `version`: the header version it is
// laid out in, which is the session's negotiated version (section 3.2). The layouts of the two
// versions are the same except the sample's, whose reserved bytes become applied_lag and
// applied_age_us in version 2 (section 4.6).
//
// Each struct declares its MessageType once, as kType; the codec takes the header's type, and
// the struct a frame of that type decodes into, from there.
//
// Encoders write one whole frame (header, payload, CRC) into the caller's buffer and return
// its size; decoders check one whole frame and fill the struct. Neither allocates nor throws.
// A struct's fields are exactly the frame's fields, so a frame that decodes re-encodes to the
// same bytes (the fuzzer checks it); reserved fields are not in the structs because they must
// be zero on the wire.
//
// Units: force in micronewtons (int32, N = uN * 1e-6), encoder counts (int64), device time in
// microseconds (uint64), durations in microseconds (uint32).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <variant>

#include "hapticd/device/protocol/error.hpp"
#include "hapticd/device/protocol/frame.hpp"

namespace hapticd::device::protocol {

/// Axes a frame can carry (1..3: a Cartesian device).
inline constexpr int kMaxProtocolAxes = 3;
/// Bytes of the serial-number field (section 4.2).
inline constexpr std::size_t kSerialSize = 16;
/// The longest watchdog timeout a device may accept, us (section 5.4); the shortest is two
/// periods.
inline constexpr std::uint32_t kMaxWatchdogTimeoutUs = 1'000'000;
/// The default a device should report at hello, us (section 5.4).
inline constexpr std::uint32_t kDefaultWatchdogTimeoutUs = 20'000;

/// command.flags (section 4.5).
enum CommandFlag : std::uint8_t {
    kCommandEnable = 1u << 0,       ///< apply force_un; clear: the device outputs zero force
    kCommandClearFaults = 1u << 1,  ///< clear latched faults (honoured only with enable clear)
};
inline constexpr std::uint8_t kCommandFlagsMask = kCommandEnable | kCommandClearFaults;

/// sample.status: conditions of this sample (section 4.6). Cleared every sample.
enum SampleStatus : std::uint16_t {
    kSampleForceActive = 1u << 0,   ///< the device is applying the commanded force
    kSampleForceClamped = 1u << 1,  ///< the command exceeded force_limit on some axis
    kSampleEncoderStale = 1u << 2,  ///< the counts were not updated since the last sample
    kSampleEncoderJump = 1u << 3,   ///< the encoder interface saw an impossible step
    kSampleCommandLate = 1u << 4,   ///< the previous force was held longer than 1.5 periods
    kSampleCommandGap = 1u << 5,    ///< sequence is not the previous command's + 1
};
inline constexpr std::uint16_t kSampleStatusMask = 0x003Fu;

/// sample.faults: latched faults (section 4.6). Any bit set means the force is zero. Bits
/// 8..11 are reserved (zero); bits 12..15 are the vendor's own faults.
enum SampleFault : std::uint16_t {
    kDeviceFaultWatchdog = 1u << 0,         ///< no command for watchdog_timeout_us
    kDeviceFaultOverTemperature = 1u << 1,  ///< motor or amplifier too hot
    kDeviceFaultAmplifier = 1u << 2,        ///< the amplifier reports a fault
    kDeviceFaultOverCurrent = 1u << 3,      ///< current limit tripped
    kDeviceFaultEncoder = 1u << 4,          ///< encoder signal lost or invalid
    kDeviceFaultEmergencyStop = 1u << 5,    ///< e-stop pressed or interlock open
    kDeviceFaultSupplyVoltage = 1u << 6,    ///< supply under- or over-voltage
    kDeviceFaultInternal = 1u << 7,         ///< firmware error
    kDeviceFaultVendorMask = 0xF000u,       ///< bits 12..15: vendor-defined
};
inline constexpr std::uint16_t kDeviceFaultDefinedMask = 0x00FFu;
inline constexpr std::uint16_t kDeviceFaultAllowedMask =
    kDeviceFaultDefinedMask | kDeviceFaultVendorMask;

/// sample.applied_lag (version 2): no command of this session is in effect yet, or the one in
/// effect is more than kMaxAppliedLag commands behind command_sequence. applied_age_us is then
/// kAppliedAgeUnknown. Also what a version-1 sample says (it has no such fields).
inline constexpr std::uint8_t kAppliedLagNone = 0xFF;
inline constexpr std::uint8_t kMaxAppliedLag = 0xFE;
/// sample.applied_age_us (version 2): the command in effect took effect kAppliedAgeUnknown us
/// (65.535 ms) or more before time_us, or applied_lag is kAppliedLagNone.
inline constexpr std::uint16_t kAppliedAgeUnknown = 0xFFFF;

/// 4.1 hello, host -> device. Opens a session; header version is always 1.
struct Hello {
    static constexpr MessageType kType = MessageType::hello;  ///< the header's type

    std::uint32_t session = 0;     ///< the new session id, != 0, chosen at random by the host
    std::uint8_t min_version = 1;  ///< oldest version the host speaks, >= 1
    std::uint8_t max_version = 1;  ///< newest, >= min_version

    bool operator==(const Hello&) const = default;
};

/// 4.2 identity flags (version 3): the device paces the loop. It answers every command and
/// poll at its next period boundary, with counts it sampled for that boundary, and the host
/// sends each command as soon as it has the sample before it (section 5.8).
inline constexpr std::uint8_t kIdentityPaced = 0x01;
inline constexpr std::uint8_t kIdentityFlagsMask = kIdentityPaced;

/// 4.2 identity, device -> host: the answer to hello, in the chosen version (`version`).
struct Identity {
    static constexpr MessageType kType = MessageType::identity;  ///< the header's type

    std::uint32_t session = 0;              ///< the hello's session
    std::uint8_t axes = 1;                  ///< 1..3
    std::int32_t force_limit_un = 1;        ///< largest |force| per axis, uN, > 0
    double counts_per_meter = 1.0;          ///< encoder resolution, every axis, finite, > 0
    std::uint32_t period_us = 1000;         ///< the device's servo period, us, > 0
    std::uint32_t watchdog_timeout_us = 1;  ///< the current watchdog timeout, us, > 0
    std::uint32_t firmware_version = 0;     ///< vendor-defined
    /// Printable ASCII (0x20..0x7E), at least one character, padded with NUL.
    std::array<char, kSerialSize> serial{};
    /// Version 3: kIdentity* bits; 0 in versions 1 and 2 (the byte is reserved there).
    std::uint8_t flags = 0;

    /// The device paces the loop (version 3, kIdentityPaced).
    bool paced() const noexcept { return (flags & kIdentityPaced) != 0u; }

    /// The serial number up to the first NUL.
    std::string_view serial_number() const noexcept;
    /// Sets `serial`; false (and unchanged) if it is empty, longer than kSerialSize or not
    /// printable ASCII.
    bool set_serial_number(std::string_view text) noexcept;

    std::uint8_t version = kProtocolVersion;  ///< header version: the session's (1 or 2)

    bool operator==(const Identity&) const = default;
};

/// 4.3 configure, host -> device.
struct Configure {
    static constexpr MessageType kType = MessageType::configure;  ///< the header's type

    std::uint32_t session = 0;
    std::uint32_t watchdog_timeout_us = 1;  ///< > 0; the device's range: section 5.4

    std::uint8_t version = kProtocolVersion;  ///< header version: the session's (1 or 2)

    bool operator==(const Configure&) const = default;
};

/// 4.4 configure_ack, device -> host: the values now in force.
struct ConfigureAck {
    static constexpr MessageType kType = MessageType::configure_ack;  ///< the header's type

    std::uint32_t session = 0;
    std::uint32_t watchdog_timeout_us = 1;

    std::uint8_t version = kProtocolVersion;  ///< header version: the session's (1 or 2)

    bool operator==(const ConfigureAck&) const = default;
};

/// 4.5 command, host -> device: the force to hold until the next command.
struct ForceCommand {
    static constexpr MessageType kType = MessageType::command;  ///< the header's type

    std::uint32_t session = 0;
    std::uint32_t sequence = 0;                             ///< +1 per command; wraps modulo 2^32
    std::uint8_t flags = 0;                                 ///< CommandFlag
    std::uint8_t axes = 1;                                  ///< 1..3, must equal the identity's
    std::array<std::int32_t, kMaxProtocolAxes> force_un{};  ///< uN, [axes..] unused (zero)

    bool enable() const noexcept { return (flags & kCommandEnable) != 0u; }

    std::uint8_t version = kProtocolVersion;  ///< header version: the session's (1 or 2)

    bool operator==(const ForceCommand&) const = default;
};

/// 4.6 sample, device -> host: the answer to command and poll.
struct EncoderSample {
    static constexpr MessageType kType = MessageType::sample;  ///< the header's type

    std::uint32_t session = 0;
    /// The command this sample answers: the last one received in this session (0: none).
    /// Version 1 also promises that its force is in effect (section 5.2); version 2 says
    /// which one is in applied_lag.
    std::uint32_t command_sequence = 0;
    std::uint32_t sample_sequence = 0;  ///< +1 per sample produced; wraps modulo 2^32
    std::uint64_t time_us = 0;          ///< device clock when the counts were latched, us
    std::uint16_t status = 0;           ///< SampleStatus
    std::uint16_t faults = 0;           ///< SampleFault
    std::uint8_t axes = 1;              ///< 1..3
    std::array<std::int64_t, kMaxProtocolAxes> counts{};  ///< [axes..] unused (zero)
    /// Version 2: the command in effect at time_us is command_sequence - applied_lag (mod
    /// 2^32), 0..kMaxAppliedLag; kAppliedLagNone: none (section 4.6). Version 1: always
    /// kAppliedLagNone (the bytes are reserved).
    std::uint8_t applied_lag = kAppliedLagNone;
    /// Version 2: it took effect applied_age_us before time_us, 0..0xFFFE us and <= time_us;
    /// kAppliedAgeUnknown: longer ago, or no command (section 4.6). Version 1: always
    /// kAppliedAgeUnknown.
    std::uint16_t applied_age_us = kAppliedAgeUnknown;
    std::uint8_t version = kProtocolVersion;  ///< header version: the session's (1 or 2)

    /// Version 2 and a command named: the sequence of the command in effect.
    bool names_applied() const noexcept { return applied_lag != kAppliedLagNone; }
    std::uint32_t applied_sequence() const noexcept { return command_sequence - applied_lag; }

    bool operator==(const EncoderSample&) const = default;
};

/// 4.7 poll, host -> device: answered with a sample; nothing changes, time does not advance.
struct Poll {
    static constexpr MessageType kType = MessageType::poll;  ///< the header's type

    std::uint32_t session = 0;

    std::uint8_t version = kProtocolVersion;  ///< header version: the session's (1 or 2)

    bool operator==(const Poll&) const = default;
};

/// 4.8 bye, host -> device: zero force, close the session.
struct Bye {
    static constexpr MessageType kType = MessageType::bye;  ///< the header's type

    std::uint32_t session = 0;

    std::uint8_t version = kProtocolVersion;  ///< header version: the session's (1 or 2)

    bool operator==(const Bye&) const = default;
};

/// 4.9 bye_ack, device -> host.
struct ByeAck {
    static constexpr MessageType kType = MessageType::bye_ack;  ///< the header's type

    std::uint32_t session = 0;

    std::uint8_t version = kProtocolVersion;  ///< header version: the session's (1 or 2)

    bool operator==(const ByeAck&) const = default;
};

/// 4.10 error, device -> host: the request was refused (nothing was applied). Header version
/// is always 1.
struct ErrorReport {
    static constexpr MessageType kType = MessageType::error;  ///< the header's type

    std::uint32_t session = 0;              ///< the refused request's session field
    ErrorCode code = ErrorCode::bad_field;  ///< != 0; codes above kMaxErrorCode may come from
                                            ///< newer devices and are passed through
    std::uint8_t request_type = 0;          ///< the refused request's type byte
    std::uint32_t detail = 0;               ///< code-specific (section 4.10)

    bool operator==(const ErrorReport&) const = default;
};

using Message = std::variant<Hello, Identity, Configure, ConfigureAck, ForceCommand, EncoderSample,
                             Poll, Bye, ByeAck, ErrorReport>;

/// The payload sizes of section 4, by axes where they depend on it.
inline constexpr std::size_t kHelloPayloadSize = 4;
inline constexpr std::size_t kIdentityPayloadSize = 44;
inline constexpr std::size_t kConfigurePayloadSize = 4;
inline constexpr std::size_t kErrorPayloadSize = 8;
constexpr std::size_t command_payload_size(int axes) noexcept {
    return 8 + 4 * static_cast<std::size_t>(axes);
}
constexpr std::size_t sample_payload_size(int axes) noexcept {
    return 24 + 8 * static_cast<std::size_t>(axes);
}
static_assert(sample_payload_size(kMaxProtocolAxes) == kMaxPayloadSize);
static_assert(kMinFrameSize + kIdentityPayloadSize <= kMaxFrameSize);

MessageType type_of(const Message& message) noexcept;
std::uint32_t session_of(const Message& message) noexcept;

// Encoders: one whole frame into `out` (at least the frame's size; kMaxFrameSize always
// suffices). Error::bad_version if `version` is not one this codec speaks, Error::bad_field if
// a field is outside its range (the frame would not decode; a version-1 sample that names an
// applied command, for instance), Error::no_space if `out` is too small; nothing useful is in
// `out` then.
Encoded encode(const Hello& message, std::span<std::byte> out) noexcept;
Encoded encode(const Identity& message, std::span<std::byte> out) noexcept;
Encoded encode(const Configure& message, std::span<std::byte> out) noexcept;
Encoded encode(const ConfigureAck& message, std::span<std::byte> out) noexcept;
Encoded encode(const ForceCommand& message, std::span<std::byte> out) noexcept;
Encoded encode(const EncoderSample& message, std::span<std::byte> out) noexcept;
Encoded encode(const Poll& message, std::span<std::byte> out) noexcept;
Encoded encode(const Bye& message, std::span<std::byte> out) noexcept;
Encoded encode(const ByeAck& message, std::span<std::byte> out) noexcept;
Encoded encode(const ErrorReport& message, std::span<std::byte> out) noexcept;
Encoded encode(const Message& message, std::span<std::byte> out) noexcept;

/// The payload of a frame that decode_frame() accepted: bad_payload_size, bad_field or none.
/// Separate from decode() so that a device still has the header (session, type) to answer
/// with an error message when the payload is wrong.
Error decode_payload(const FrameView& frame, Message& message) noexcept;

/// decode_frame() then decode_payload(): one whole frame, any type.
Error decode(std::span<const std::byte> bytes, Message& message) noexcept;

// Typed decoders: as decode(), plus Error::wrong_type (checked right after the frame) when the
// frame holds another message type.
Error decode(std::span<const std::byte> bytes, Hello& message) noexcept;
Error decode(std::span<const std::byte> bytes, Identity& message) noexcept;
Error decode(std::span<const std::byte> bytes, Configure& message) noexcept;
Error decode(std::span<const std::byte> bytes, ConfigureAck& message) noexcept;
Error decode(std::span<const std::byte> bytes, ForceCommand& message) noexcept;
Error decode(std::span<const std::byte> bytes, EncoderSample& message) noexcept;
Error decode(std::span<const std::byte> bytes, Poll& message) noexcept;
Error decode(std::span<const std::byte> bytes, Bye& message) noexcept;
Error decode(std::span<const std::byte> bytes, ByeAck& message) noexcept;
Error decode(std::span<const std::byte> bytes, ErrorReport& message) noexcept;

/// Why an identity does not decode (Error::bad_field; decode() still fills the struct): its
/// first field out of range, with the value and the range, as "counts_per_meter = nan:
/// allowed finite and > 0 (encoder counts per metre)"; empty when every field is in range.
/// For the host's message, which names the field a device's maker must fix.
std::string out_of_range_field(const Identity& identity);

}  // namespace hapticd::device::protocol
