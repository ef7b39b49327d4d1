// Conversions between the protocol's wire units and the servo's types (servo/io.hpp):
// force in micronewtons <-> newtons, device time in microseconds -> seconds, and the
// command/sample structs (docs/protocol.md section 2, "Units").
#pragma once

#include <cstdint>

#include "hapticd/device/protocol/messages.hpp"
#include "hapticd/servo/io.hpp"

namespace hapticd::device::protocol {

static_assert(kMaxProtocolAxes == servo::kMaxAxes);

/// N -> uN, rounded to the nearest micronewton and saturated to the int32 range
/// (+-2147.48 N); NaN -> 0. Callers that must not send a saturated infinity check
/// std::isfinite first (make_force_command does).
std::int32_t force_to_micronewtons(double force_n) noexcept;

/// uN -> N.
constexpr double force_from_micronewtons(std::int32_t force_un) noexcept {
    return static_cast<double>(force_un) * 1e-6;
}

/// Device time, us -> s.
constexpr double time_from_microseconds(std::uint64_t time_us) noexcept {
    return static_cast<double>(time_us) * 1e-6;
}

/// Host side: the command frame for a servo command on a device with `axes` axes (1..3).
/// Returns false when a force of the used axes is not finite: `out` is then a disabled
/// command with zero force (the device must never see a saturated infinity), and the caller
/// reports IoResult::error, as the simulated device does.
bool make_force_command(const servo::Command& command, int axes, std::uint32_t session,
                        std::uint32_t sequence, ForceCommand& out) noexcept;

/// Device side: the servo command a decoded frame asks for (enable and forces, in N).
servo::Command to_servo_command(const ForceCommand& command) noexcept;

/// Host side: the servo sample of a decoded frame. `sequence` is the unwrapped 64-bit sample
/// sequence and `host_status` the host's own StatusBits (reply_tracker.hpp); the device's bits
/// are mapped with to_servo_status().
servo::Sample to_servo_sample(const EncoderSample& sample, std::uint64_t sequence,
                              std::uint32_t host_status) noexcept;

}  // namespace hapticd::device::protocol
