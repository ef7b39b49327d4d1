// The protocol's status and fault bits in terms of the servo's StatusBit (servo/io.hpp), and
// back (docs/protocol.md section 4.6, "Mapping to the servo").
//
//   sample.status / sample.faults         servo::StatusBit
//   encoder_stale                          kStatusStale
//   encoder_jump                           kStatusJump (the servo latches kFaultEncoderJump)
//   command_late, command_gap              kStatusLate: the device held the previous force
//                                          longer than a period, because the command came
//                                          late or was lost on the way
//   any fault bit                          kStatusDeviceFault (the servo latches
//                                          kFaultDeviceFault)
//   force_active, force_clamped            none (informational)
//
// kStatusDisconnected and kStatusDropped are the host's own findings (the transport is gone;
// no valid reply arrived this period), never a device's: the servo treats kStatusDropped as
// "no sample", so a sample that did arrive must not carry it. A gap in sample_sequence shows
// up in the unwrapped Sample::sequence instead (reply_tracker.hpp).
#pragma once

#include <cstdint>

namespace hapticd::device::protocol {

/// sample.status and sample.faults -> servo::StatusBit flags.
std::uint32_t to_servo_status(std::uint16_t sample_status, std::uint16_t sample_faults) noexcept;

/// servo::StatusBit flags -> the sample.status bits a device reports for them (stale, jump).
/// The device emulator uses it for the simulated device's injected encoder faults; the other
/// servo bits have no device-side meaning and are ignored.
std::uint16_t sample_status_from_servo(std::uint32_t servo_status) noexcept;

}  // namespace hapticd::device::protocol
