// Encoders and decoders of the ten messages (docs/protocol.md section 4), versions 1 and 2.
// Offsets below are payload offsets; the document's tables give frame offsets (payload offset
// + 8).
#include "hapticd/device/protocol/messages.hpp"

#include <array>
#include <cmath>
#include <cstddef>
#include <sstream>
#include <type_traits>
#include <utility>
#include <variant>

#include "hapticd/device/protocol/wire.hpp"

namespace hapticd::device::protocol {
namespace {

using Payload = std::span<const std::byte>;
using PayloadOut = std::span<std::byte>;

constexpr bool valid_axes(std::uint8_t axes) noexcept {
    return axes >= 1 && axes <= kMaxProtocolAxes;
}

constexpr bool printable(char c) noexcept { return c >= 0x20 && c <= 0x7E; }

/// Section 4.2: printable ASCII, at least one character, NUL-padded.
bool valid_serial(const std::array<char, kSerialSize>& serial) noexcept {
    if (serial[0] == '\0') return false;
    bool ended = false;
    for (const char c : serial) {
        if (c == '\0') {
            ended = true;
        } else if (ended || !printable(c)) {
            return false;
        }
    }
    return true;
}

/// Unused axes must be zero, so that the struct and the frame say the same thing.
template <typename T>
bool unused_axes_zero(const std::array<T, kMaxProtocolAxes>& values, std::uint8_t axes) noexcept {
    for (std::size_t i = axes; i < values.size(); ++i) {
        if (values[i] != 0) return false;
    }
    return true;
}

// Per message: check() (the encoder refuses what the decoder would refuse), payload_size(),
// write() and read(). read() checks the payload size first, then the fields.

// ---- 4.1 hello ----
Error check(const Hello& m) noexcept {
    if (m.session == 0 || m.min_version == 0 || m.max_version < m.min_version) {
        return Error::bad_field;
    }
    return Error::none;
}
std::size_t payload_size(const Hello&) noexcept { return kHelloPayloadSize; }
void write(const Hello& m, PayloadOut p) noexcept {
    wire::store_u8(p, 0, m.min_version);
    wire::store_u8(p, 1, m.max_version);
    wire::store_u16(p, 2, 0);
}
Error read(Payload p, Hello& m) noexcept {
    if (p.size() != kHelloPayloadSize) return Error::bad_payload_size;
    if (wire::load_u16(p, 2) != 0) return Error::bad_field;
    m.min_version = wire::load_u8(p, 0);
    m.max_version = wire::load_u8(p, 1);
    return check(m);
}

// ---- 4.2 identity ----
enum class IdentityField {
    none,
    axes,
    flags,
    force_limit,
    counts_per_meter,
    period,
    watchdog,
    serial
};

/// The flags a version allows: none before version 3.
std::uint8_t allowed_identity_flags(std::uint8_t version) noexcept {
    return version >= kProtocolVersion3 ? kIdentityFlagsMask : std::uint8_t{0};
}

IdentityField first_out_of_range(const Identity& m) noexcept {
    if (!valid_axes(m.axes)) return IdentityField::axes;
    if ((m.flags & ~allowed_identity_flags(m.version)) != 0u) return IdentityField::flags;
    if (m.force_limit_un <= 0) return IdentityField::force_limit;
    if (!std::isfinite(m.counts_per_meter) || !(m.counts_per_meter > 0.0)) {
        return IdentityField::counts_per_meter;
    }
    if (m.period_us == 0) return IdentityField::period;
    if (m.watchdog_timeout_us == 0) return IdentityField::watchdog;
    if (!valid_serial(m.serial)) return IdentityField::serial;
    return IdentityField::none;
}

Error check(const Identity& m) noexcept {
    return first_out_of_range(m) == IdentityField::none ? Error::none : Error::bad_field;
}
std::size_t payload_size(const Identity&) noexcept { return kIdentityPayloadSize; }
void write(const Identity& m, PayloadOut p) noexcept {
    wire::store_u8(p, 0, m.axes);
    wire::store_u8(p, 1, m.flags);  // reserved (0) before version 3: check() sees to it
    wire::store_u16(p, 2, 0);
    wire::store_i32(p, 4, m.force_limit_un);
    wire::store_f64(p, 8, m.counts_per_meter);
    wire::store_u32(p, 16, m.period_us);
    wire::store_u32(p, 20, m.watchdog_timeout_us);
    wire::store_u32(p, 24, m.firmware_version);
    for (std::size_t i = 0; i < kSerialSize; ++i) {
        wire::store_u8(p, 28 + i, static_cast<std::uint8_t>(m.serial[i]));
    }
}
Error read(Payload p, Identity& m) noexcept {
    if (p.size() != kIdentityPayloadSize) return Error::bad_payload_size;
    if (wire::load_u16(p, 2) != 0) return Error::bad_field;
    m.axes = wire::load_u8(p, 0);
    m.flags = wire::load_u8(p, 1);
    m.force_limit_un = wire::load_i32(p, 4);
    m.counts_per_meter = wire::load_f64(p, 8);
    m.period_us = wire::load_u32(p, 16);
    m.watchdog_timeout_us = wire::load_u32(p, 20);
    m.firmware_version = wire::load_u32(p, 24);
    for (std::size_t i = 0; i < kSerialSize; ++i) {
        m.serial[i] = static_cast<char>(wire::load_u8(p, 28 + i));
    }
    return check(m);
}

// ---- 4.3 configure, 4.4 configure_ack (same layout) ----
template <typename M>
Error check_configure(const M& m) noexcept {
    return m.watchdog_timeout_us == 0 ? Error::bad_field : Error::none;
}
template <typename M>
void write_configure(const M& m, PayloadOut p) noexcept {
    wire::store_u32(p, 0, m.watchdog_timeout_us);
}
template <typename M>
Error read_configure(Payload p, M& m) noexcept {
    if (p.size() != kConfigurePayloadSize) return Error::bad_payload_size;
    m.watchdog_timeout_us = wire::load_u32(p, 0);
    return check_configure(m);
}
Error check(const Configure& m) noexcept { return check_configure(m); }
std::size_t payload_size(const Configure&) noexcept { return kConfigurePayloadSize; }
void write(const Configure& m, PayloadOut p) noexcept { write_configure(m, p); }
Error read(Payload p, Configure& m) noexcept { return read_configure(p, m); }
Error check(const ConfigureAck& m) noexcept { return check_configure(m); }
std::size_t payload_size(const ConfigureAck&) noexcept { return kConfigurePayloadSize; }
void write(const ConfigureAck& m, PayloadOut p) noexcept { write_configure(m, p); }
Error read(Payload p, ConfigureAck& m) noexcept { return read_configure(p, m); }

// ---- 4.5 command ----
Error check(const ForceCommand& m) noexcept {
    if ((m.flags & ~kCommandFlagsMask) != 0u || !valid_axes(m.axes) ||
        !unused_axes_zero(m.force_un, m.axes)) {
        return Error::bad_field;
    }
    return Error::none;
}
std::size_t payload_size(const ForceCommand& m) noexcept { return command_payload_size(m.axes); }
void write(const ForceCommand& m, PayloadOut p) noexcept {
    wire::store_u32(p, 0, m.sequence);
    wire::store_u8(p, 4, m.flags);
    wire::store_u8(p, 5, m.axes);
    wire::store_u16(p, 6, 0);
    for (std::size_t i = 0; i < m.axes; ++i) wire::store_i32(p, 8 + 4 * i, m.force_un[i]);
}
Error read(Payload p, ForceCommand& m) noexcept {
    if (p.size() != command_payload_size(1) && p.size() != command_payload_size(2) &&
        p.size() != command_payload_size(3)) {
        return Error::bad_payload_size;
    }
    m.sequence = wire::load_u32(p, 0);
    m.flags = wire::load_u8(p, 4);
    m.axes = wire::load_u8(p, 5);
    if (wire::load_u16(p, 6) != 0 || !valid_axes(m.axes) ||
        p.size() != command_payload_size(m.axes)) {
        return Error::bad_field;
    }
    m.force_un.fill(0);
    for (std::size_t i = 0; i < m.axes; ++i) m.force_un[i] = wire::load_i32(p, 8 + 4 * i);
    return check(m);
}

// ---- 4.6 sample ----
// Version 2 uses the three bytes that version 1 reserves (payload 21..23) for applied_lag and
// applied_age_us; a version-1 struct holds their "nothing said" values.
Error check(const EncoderSample& m) noexcept {
    if ((m.status & ~kSampleStatusMask) != 0u || (m.faults & ~kDeviceFaultAllowedMask) != 0u ||
        !valid_axes(m.axes) || !unused_axes_zero(m.counts, m.axes)) {
        return Error::bad_field;
    }
    if (m.version == kProtocolVersion1) {
        if (m.applied_lag != kAppliedLagNone || m.applied_age_us != kAppliedAgeUnknown) {
            return Error::bad_field;  // version 1 cannot say it
        }
        return Error::none;
    }
    // No command named: no age. An age: the command took effect after the clock started.
    if (m.applied_lag == kAppliedLagNone && m.applied_age_us != kAppliedAgeUnknown) {
        return Error::bad_field;
    }
    if (m.applied_age_us != kAppliedAgeUnknown && m.applied_age_us > m.time_us) {
        return Error::bad_field;
    }
    return Error::none;
}
std::size_t payload_size(const EncoderSample& m) noexcept { return sample_payload_size(m.axes); }
void write(const EncoderSample& m, PayloadOut p) noexcept {
    wire::store_u32(p, 0, m.command_sequence);
    wire::store_u32(p, 4, m.sample_sequence);
    wire::store_u64(p, 8, m.time_us);
    wire::store_u16(p, 16, m.status);
    wire::store_u16(p, 18, m.faults);
    wire::store_u8(p, 20, m.axes);
    if (m.version == kProtocolVersion1) {
        wire::store_u8(p, 21, 0);
        wire::store_u16(p, 22, 0);
    } else {
        wire::store_u8(p, 21, m.applied_lag);
        wire::store_u16(p, 22, m.applied_age_us);
    }
    for (std::size_t i = 0; i < m.axes; ++i) wire::store_i64(p, 24 + 8 * i, m.counts[i]);
}
Error read(Payload p, EncoderSample& m) noexcept {
    if (p.size() != sample_payload_size(1) && p.size() != sample_payload_size(2) &&
        p.size() != sample_payload_size(3)) {
        return Error::bad_payload_size;
    }
    m.command_sequence = wire::load_u32(p, 0);
    m.sample_sequence = wire::load_u32(p, 4);
    m.time_us = wire::load_u64(p, 8);
    m.status = wire::load_u16(p, 16);
    m.faults = wire::load_u16(p, 18);
    m.axes = wire::load_u8(p, 20);
    if (m.version == kProtocolVersion1) {
        if (wire::load_u8(p, 21) != 0 || wire::load_u16(p, 22) != 0) return Error::bad_field;
        m.applied_lag = kAppliedLagNone;
        m.applied_age_us = kAppliedAgeUnknown;
    } else {
        m.applied_lag = wire::load_u8(p, 21);
        m.applied_age_us = wire::load_u16(p, 22);
    }
    if (!valid_axes(m.axes) || p.size() != sample_payload_size(m.axes)) return Error::bad_field;
    m.counts.fill(0);
    for (std::size_t i = 0; i < m.axes; ++i) m.counts[i] = wire::load_i64(p, 24 + 8 * i);
    return check(m);
}

// ---- 4.7 poll, 4.8 bye, 4.9 bye_ack: empty payloads ----
template <typename M>
Error read_empty(Payload p, M&) noexcept {
    return p.empty() ? Error::none : Error::bad_payload_size;
}
Error check(const Poll&) noexcept { return Error::none; }
std::size_t payload_size(const Poll&) noexcept { return 0; }
void write(const Poll&, PayloadOut) noexcept {}
Error read(Payload p, Poll& m) noexcept { return read_empty(p, m); }
Error check(const Bye&) noexcept { return Error::none; }
std::size_t payload_size(const Bye&) noexcept { return 0; }
void write(const Bye&, PayloadOut) noexcept {}
Error read(Payload p, Bye& m) noexcept { return read_empty(p, m); }
Error check(const ByeAck&) noexcept { return Error::none; }
std::size_t payload_size(const ByeAck&) noexcept { return 0; }
void write(const ByeAck&, PayloadOut) noexcept {}
Error read(Payload p, ByeAck& m) noexcept { return read_empty(p, m); }

// ---- 4.10 error ----
Error check(const ErrorReport& m) noexcept {
    return static_cast<std::uint8_t>(m.code) == 0 ? Error::bad_field : Error::none;
}
std::size_t payload_size(const ErrorReport&) noexcept { return kErrorPayloadSize; }
void write(const ErrorReport& m, PayloadOut p) noexcept {
    wire::store_u8(p, 0, static_cast<std::uint8_t>(m.code));
    wire::store_u8(p, 1, m.request_type);
    wire::store_u16(p, 2, 0);
    wire::store_u32(p, 4, m.detail);
}
Error read(Payload p, ErrorReport& m) noexcept {
    if (p.size() != kErrorPayloadSize) return Error::bad_payload_size;
    if (wire::load_u16(p, 2) != 0) return Error::bad_field;
    m.code = static_cast<ErrorCode>(wire::load_u8(p, 0));
    m.request_type = wire::load_u8(p, 1);
    m.detail = wire::load_u32(p, 4);
    return check(m);
}

// ---- the message set ----

/// Whether a message struct has a version member: all but the frozen hello and error.
template <typename M>
constexpr bool has_version = requires(const M& m) {
    m.version;
};

/// The header version a struct is laid out in: its own, or the frozen version of hello and
/// error.
template <typename M>
constexpr std::uint8_t version_of(const M& m) noexcept {
    if constexpr (has_version<M>) {
        return m.version;
    } else {
        return kFrozenVersion;
    }
}

/// Message's alternatives are the messages: each says its type once (kType), no two the same,
/// every type that decode_frame() lets through has one, and exactly the frozen types (hello,
/// error) have no version member.
template <std::size_t... I>
constexpr bool consistent_message_set(std::index_sequence<I...>) noexcept {
    constexpr std::array<MessageType, sizeof...(I)> types{
        std::variant_alternative_t<I, Message>::kType...};
    constexpr std::array<bool, sizeof...(I)> versioned{
        has_version<std::variant_alternative_t<I, Message>>...};
    std::size_t message_types = 0;
    for (int value = 0; value <= 0xFF; ++value) {
        if (is_message_type(static_cast<std::uint8_t>(value))) ++message_types;
    }
    if (message_types != types.size()) return false;
    for (std::size_t i = 0; i < types.size(); ++i) {
        if (!is_message_type(static_cast<std::uint8_t>(types[i]))) return false;
        if (versioned[i] == is_frozen_type(types[i])) return false;
        for (std::size_t j = i + 1; j < types.size(); ++j) {
            if (types[i] == types[j]) return false;
        }
    }
    return true;
}
static_assert(consistent_message_set(std::make_index_sequence<std::variant_size_v<Message>>{}),
              "every message type has exactly one struct in Message, whose kType it is");

template <typename M>
Encoded encode_message(const M& m, std::span<std::byte> out) noexcept {
    if (!is_spoken_version(version_of(m))) return {0, Error::bad_version};
    if (const Error error = check(m); error != Error::none) return {0, error};
    const std::size_t size = payload_size(m);
    if (out.size() < kMinFrameSize + size) return {0, Error::no_space};
    write(m, out.subspan(kHeaderSize, size));
    FrameHeader header;
    header.type = M::kType;
    header.version = version_of(m);
    header.payload_size = static_cast<std::uint8_t>(size);
    header.session = m.session;
    return finish_frame(header, out);
}

template <typename M>
Error read_message(const FrameView& frame, M& m) noexcept {
    m = M{};
    m.session = frame.header.session;
    if constexpr (has_version<M>) m.version = frame.header.version;
    return read(frame.payload, m);
}

template <typename M>
Error decode_typed(std::span<const std::byte> bytes, M& m) noexcept {
    FrameView frame;
    if (const Error error = decode_frame(bytes, frame); error != Error::none) return error;
    if (frame.header.type != M::kType) return Error::wrong_type;
    return read_message(frame, m);
}

/// Reads the frame into the alternative of Message whose kType is the frame's type.
template <std::size_t I = 0>
Error emplace_and_read(const FrameView& frame, Message& message) noexcept {
    using M = std::variant_alternative_t<I, Message>;
    if (frame.header.type == M::kType) return read_message(frame, message.emplace<M>());
    if constexpr (I + 1 < std::variant_size_v<Message>) {
        return emplace_and_read<I + 1>(frame, message);
    } else {
        return Error::unknown_type;  // decode_frame() lets no other type through
    }
}

/// std::visit without its bad_variant_access path: a Message is never valueless, because its
/// alternatives are trivially copyable (construction and assignment cannot throw).
template <std::size_t I = 0, typename Visitor>
auto visit_message(const Message& message, Visitor&& visitor) noexcept {
    static_assert(std::is_trivially_copyable_v<std::variant_alternative_t<I, Message>>);
    if constexpr (I + 1 < std::variant_size_v<Message>) {
        if (message.index() != I) {
            return visit_message<I + 1>(message, std::forward<Visitor>(visitor));
        }
    }
    return visitor(*std::get_if<I>(&message));
}

}  // namespace

std::string out_of_range_field(const Identity& m) {
    switch (first_out_of_range(m)) {
        case IdentityField::none:
            return {};
        case IdentityField::axes:
            return "axes = " + std::to_string(m.axes) + ": allowed 1.." +
                   std::to_string(kMaxProtocolAxes);
        case IdentityField::flags:
            return "flags = " + std::to_string(m.flags) + ": allowed " +
                   (m.version >= kProtocolVersion3 ? "bit 0 (paced) only" : "0 before version 3");
        case IdentityField::force_limit:
            return "force_limit_un = " + std::to_string(m.force_limit_un) +
                   ": allowed > 0 (micronewtons)";
        case IdentityField::counts_per_meter: {
            std::ostringstream value;
            value << m.counts_per_meter;
            return "counts_per_meter = " + value.str() +
                   ": allowed finite and > 0 (encoder counts per metre)";
        }
        case IdentityField::period:
            return "period_us = 0: allowed > 0 (the device's servo period, us)";
        case IdentityField::watchdog:
            return "watchdog_timeout_us = 0: allowed > 0 (us)";
        case IdentityField::serial:
            return "serial: allowed 1 to " + std::to_string(kSerialSize) +
                   " printable ASCII characters, then NUL padding";
    }
    return {};
}

std::string_view Identity::serial_number() const noexcept {
    std::size_t length = 0;
    while (length < serial.size() && serial[length] != '\0') ++length;
    return {serial.data(), length};
}

bool Identity::set_serial_number(std::string_view text) noexcept {
    if (text.empty() || text.size() > kSerialSize) return false;
    for (const char c : text) {
        if (!printable(c)) return false;
    }
    serial.fill('\0');
    for (std::size_t i = 0; i < text.size(); ++i) serial[i] = text[i];
    return true;
}

MessageType type_of(const Message& message) noexcept {
    return visit_message(message, [](const auto& m) { return std::decay_t<decltype(m)>::kType; });
}

std::uint32_t session_of(const Message& message) noexcept {
    return visit_message(message, [](const auto& m) { return m.session; });
}

Encoded encode(const Hello& m, std::span<std::byte> out) noexcept { return encode_message(m, out); }
Encoded encode(const Identity& m, std::span<std::byte> out) noexcept {
    return encode_message(m, out);
}
Encoded encode(const Configure& m, std::span<std::byte> out) noexcept {
    return encode_message(m, out);
}
Encoded encode(const ConfigureAck& m, std::span<std::byte> out) noexcept {
    return encode_message(m, out);
}
Encoded encode(const ForceCommand& m, std::span<std::byte> out) noexcept {
    return encode_message(m, out);
}
Encoded encode(const EncoderSample& m, std::span<std::byte> out) noexcept {
    return encode_message(m, out);
}
Encoded encode(const Poll& m, std::span<std::byte> out) noexcept { return encode_message(m, out); }
Encoded encode(const Bye& m, std::span<std::byte> out) noexcept { return encode_message(m, out); }
Encoded encode(const ByeAck& m, std::span<std::byte> out) noexcept {
    return encode_message(m, out);
}
Encoded encode(const ErrorReport& m, std::span<std::byte> out) noexcept {
    return encode_message(m, out);
}
Encoded encode(const Message& message, std::span<std::byte> out) noexcept {
    return visit_message(message, [out](const auto& m) { return encode_message(m, out); });
}

Error decode_payload(const FrameView& frame, Message& message) noexcept {
    return emplace_and_read(frame, message);
}

Error decode(std::span<const std::byte> bytes, Message& message) noexcept {
    FrameView frame;
    if (const Error error = decode_frame(bytes, frame); error != Error::none) return error;
    return decode_payload(frame, message);
}

Error decode(std::span<const std::byte> b, Hello& m) noexcept { return decode_typed(b, m); }
Error decode(std::span<const std::byte> b, Identity& m) noexcept { return decode_typed(b, m); }
Error decode(std::span<const std::byte> b, Configure& m) noexcept { return decode_typed(b, m); }
Error decode(std::span<const std::byte> b, ConfigureAck& m) noexcept { return decode_typed(b, m); }
Error decode(std::span<const std::byte> b, ForceCommand& m) noexcept { return decode_typed(b, m); }
Error decode(std::span<const std::byte> b, EncoderSample& m) noexcept { return decode_typed(b, m); }
Error decode(std::span<const std::byte> b, Poll& m) noexcept { return decode_typed(b, m); }
Error decode(std::span<const std::byte> b, Bye& m) noexcept { return decode_typed(b, m); }
Error decode(std::span<const std::byte> b, ByeAck& m) noexcept { return decode_typed(b, m); }
Error decode(std::span<const std::byte> b, ErrorReport& m) noexcept { return decode_typed(b, m); }

}  // namespace hapticd::device::protocol
