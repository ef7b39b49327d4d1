// What can be wrong with a frame: the result codes of the encoder and decoder, and the error
// codes a device sends back in an `error` message (docs/protocol.md sections 3.4 and 4.10).
//
// Decoding never throws: every function returns an Error, and Error::none is success. The
// checks run in a fixed order (the order of this enum), so a frame that is wrong in several
// ways always reports the first; the fuzzer and the tests rely on that.
#pragma once

#include <cstdint>
#include <string_view>

namespace hapticd::device::protocol {

enum class Error : std::uint8_t {
    none = 0,
    // Frame level: the frame cannot be trusted at all; a device drops it without a reply.
    truncated,   ///< fewer bytes than the smallest frame, or than the header's length says
    bad_magic,   ///< byte 0 is not kMagic
    bad_length,  ///< payload_size above the maximum, or bytes after the CRC
    bad_crc,     ///< the CRC-32C does not match
    // Message level: the frame is intact (CRC good); a device answers with an error message.
    bad_version,       ///< a version this codec does not speak (hello/error: not 1)
    unknown_type,      ///< the type byte is not a message type
    bad_payload_size,  ///< payload_size is wrong for the type (or for its axes field)
    bad_field,         ///< a field is out of its range, or a reserved field is not zero
    // Caller level.
    wrong_type,  ///< a typed decode() was handed a frame of another type
    no_space,    ///< encode(): the output buffer is smaller than the frame
    // Transport level (transport.hpp).
    bad_report_id,  ///< a HID report with another report ID
};

/// "truncated", "bad_crc", ...; "unknown" for values outside the enum.
std::string_view to_string(Error error) noexcept;

/// True for the frame-level errors, after which nothing in the frame (not even its session or
/// type) may be believed: the receiver drops the frame silently.
constexpr bool is_frame_error(Error error) noexcept {
    return error == Error::truncated || error == Error::bad_magic || error == Error::bad_length ||
           error == Error::bad_crc || error == Error::bad_report_id;
}

/// The `code` field of an error message (docs/protocol.md section 4.10). Values are wire
/// values: never renumber.
enum class ErrorCode : std::uint8_t {
    unknown_type = 1,         ///< the type byte is not a message type
    unexpected_type = 2,      ///< a device-to-host type was sent to the device
    bad_length = 3,           ///< payload_size wrong for the type
    bad_field = 4,            ///< a reserved field is not zero or a field is malformed
    bad_version = 5,          ///< the header's version is not the negotiated one
    unsupported_version = 6,  ///< hello: no version in [min, max] that the device speaks
    no_session = 7,           ///< no hello has opened a session (or bye closed it)
    wrong_session = 8,        ///< the header's session is not the current one
    wrong_axes = 9,           ///< a command's axes differ from the device's
    out_of_range = 10,        ///< a configure value outside the device's range
};

inline constexpr std::uint8_t kMaxErrorCode = 10;

/// "unknown_type", ...; "unknown" for values outside the enum.
std::string_view to_string(ErrorCode code) noexcept;

}  // namespace hapticd::device::protocol
