// The plain data that crosses between a device and the servo tick: one encoder sample in,
// one force command out. Devices (device/device.hpp) produce and consume these; the servo
// loop never sees anything else of a device.
//
// Units: encoder counts are integers (metres = counts / counts_per_meter); forces are the
// force the device applies to the handle along each +axis, in newtons.
#pragma once

#include <array>
#include <cstdint>

namespace hapticd::servo {

inline constexpr int kMaxAxes = 3;

/// Status bits of a sample; the telemetry's status column carries them unchanged.
enum StatusBit : std::uint32_t {
    kStatusDisconnected = 1u << 0,  ///< the device is gone
    kStatusStale = 1u << 1,         ///< the encoder did not update this period
    kStatusJump = 1u << 2,          ///< the encoder jumped further than physics allows
    kStatusLate = 1u << 3,          ///< the reply came after the deadline
    kStatusDropped = 1u << 4,       ///< no reply this period
    kStatusDeviceFault = 1u << 5,   ///< the device reports a fault of its own
};

/// One encoder reading.
struct Sample {
    std::array<std::int64_t, kMaxAxes> encoder_counts{};
    double device_time_s = 0.0;  ///< the device's own clock (virtual time for lockstep)
    std::uint64_t sequence = 0;  ///< increments by one per sample the device produced
    std::uint32_t status = 0;    ///< StatusBit flags
};

/// One force command, held by the device until the next one (zero-order hold).
struct Command {
    std::array<double, kMaxAxes> force_n{};  ///< force on the handle along +axis, N
    bool enable = false;                     ///< false: the device outputs zero force
};

enum class IoResult { ok, timeout, disconnected, error };

}  // namespace hapticd::servo
