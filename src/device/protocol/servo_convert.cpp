// Wire units <-> servo types (docs/protocol.md section 2).
#include "hapticd/device/protocol/servo_convert.hpp"

#include <cmath>
#include <limits>

#include "hapticd/device/protocol/status_map.hpp"

namespace hapticd::device::protocol {

std::int32_t force_to_micronewtons(double force_n) noexcept {
    if (std::isnan(force_n)) return 0;
    const double force_un = std::round(force_n * 1e6);
    constexpr double kMax = std::numeric_limits<std::int32_t>::max();
    constexpr double kMin = std::numeric_limits<std::int32_t>::min();
    if (force_un >= kMax) return std::numeric_limits<std::int32_t>::max();
    if (force_un <= kMin) return std::numeric_limits<std::int32_t>::min();
    return static_cast<std::int32_t>(force_un);
}

bool make_force_command(const servo::Command& command, int axes, std::uint32_t session,
                        std::uint32_t sequence, ForceCommand& out) noexcept {
    out = ForceCommand{};
    out.session = session;
    out.sequence = sequence;
    out.axes = static_cast<std::uint8_t>(axes);
    bool finite = true;
    for (int i = 0; i < axes && i < kMaxProtocolAxes; ++i) {
        finite = finite && std::isfinite(command.force_n[i]);
    }
    if (!finite) return false;  // disabled, zero force
    out.flags = command.enable ? kCommandEnable : 0;
    for (int i = 0; i < axes && i < kMaxProtocolAxes; ++i) {
        out.force_un[i] = force_to_micronewtons(command.force_n[i]);
    }
    return true;
}

servo::Command to_servo_command(const ForceCommand& command) noexcept {
    servo::Command out;
    out.enable = command.enable();
    for (int i = 0; i < command.axes && i < kMaxProtocolAxes; ++i) {
        out.force_n[i] = force_from_micronewtons(command.force_un[i]);
    }
    return out;
}

servo::Sample to_servo_sample(const EncoderSample& sample, std::uint64_t sequence,
                              std::uint32_t host_status) noexcept {
    servo::Sample out;
    for (int i = 0; i < sample.axes && i < kMaxProtocolAxes; ++i) {
        out.encoder_counts[i] = sample.counts[i];
    }
    out.device_time_s = time_from_microseconds(sample.time_us);
    out.sequence = sequence;
    out.status = to_servo_status(sample.status, sample.faults) | host_status;
    return out;
}

}  // namespace hapticd::device::protocol
