// The plain data that crosses between a device and the servo tick: one encoder sample in,
// one force command out. Devices (device/device.hpp) produce and consume these; the servo
// loop never sees anything else of a device.
//
// Units: encoder counts are integers (metres = counts / counts_per_meter); forces are the
// force the device applies to the handle along each +axis, in newtons.
#pragma once

#include <array>
#include <cstdint>
#include <string>

namespace hapticd::servo {

inline constexpr int kMaxAxes = 3;

/// "1 axis", "3 axes": for messages.
inline std::string axes_text(int axes) {
    return std::to_string(axes) + (axes == 1 ? " axis" : " axes");
}

/// Status bits of a sample; the telemetry's status column carries them unchanged.
enum StatusBit : std::uint32_t {
    kStatusDisconnected = 1u << 0,  ///< the device is gone
    kStatusStale = 1u << 1,         ///< the encoder did not update this period
    kStatusJump = 1u << 2,          ///< the encoder jumped further than physics allows
    kStatusLate = 1u << 3,          ///< the reply came after the deadline
    kStatusDropped = 1u << 4,       ///< no reply this period
    kStatusDeviceFault = 1u << 5,   ///< the device reports a fault of its own
};

/// What a sample says about when the commands took effect (Sample::applied): the device's
/// side of the loop delay, which only the device can see (docs/link-diagnostics.md).
enum class AppliedReport : std::uint8_t {
    unsupported,  ///< the device does not say (the open protocol's version 1)
    none,         ///< it does, but not in this sample: no command has taken effect yet, or
                  ///< the one in effect took effect too long ago to say
    reported,     ///< applied_write and applied_time_s are valid
    bad_command,  ///< it names a command never sent, or one older than it named before
    bad_time,     ///< its times contradict themselves (its clock went backwards, or the moment
                  ///< a command took effect moved): nothing in it is used
};

/// One encoder reading.
struct Sample {
    std::array<std::int64_t, kMaxAxes> encoder_counts{};
    double device_time_s = 0.0;  ///< the device's own clock (virtual time for lockstep)
    std::uint64_t sequence = 0;  ///< increments by one per sample the device produced
    std::uint32_t status = 0;    ///< StatusBit flags
    /// The command in effect at device_time_s, as the device reports it: the write() call it
    /// came from, counted from 1 at the first write() after open() (calls that failed
    /// included), and the device time (device_time_s's clock) at which it took effect. Valid
    /// only when applied == AppliedReport::reported. The servo does not use them; the link
    /// diagnosis measures the loop delay from them.
    std::uint64_t applied_write = 0;
    double applied_time_s = 0.0;
    AppliedReport applied = AppliedReport::unsupported;
};

/// One force command, held by the device until the next one (zero-order hold).
struct Command {
    std::array<double, kMaxAxes> force_n{};  ///< force on the handle along +axis, N
    bool enable = false;                     ///< false: the device outputs zero force
};

enum class IoResult { ok, timeout, disconnected, error };

}  // namespace hapticd::servo
