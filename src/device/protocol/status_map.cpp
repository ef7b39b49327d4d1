// Protocol status bits <-> servo::StatusBit (docs/protocol.md section 4.6).
#include "hapticd/device/protocol/status_map.hpp"

#include "hapticd/device/protocol/messages.hpp"
#include "hapticd/servo/io.hpp"

namespace hapticd::device::protocol {

std::uint32_t to_servo_status(std::uint16_t sample_status, std::uint16_t sample_faults) noexcept {
    std::uint32_t status = 0;
    if ((sample_status & kSampleEncoderStale) != 0u) status |= servo::kStatusStale;
    if ((sample_status & kSampleEncoderJump) != 0u) status |= servo::kStatusJump;
    if ((sample_status & (kSampleCommandLate | kSampleCommandGap)) != 0u) {
        status |= servo::kStatusLate;
    }
    if (sample_faults != 0u) status |= servo::kStatusDeviceFault;
    return status;
}

std::uint16_t sample_status_from_servo(std::uint32_t servo_status) noexcept {
    std::uint16_t status = 0;
    if ((servo_status & servo::kStatusStale) != 0u) status |= kSampleEncoderStale;
    if ((servo_status & servo::kStatusJump) != 0u) status |= kSampleEncoderJump;
    return status;
}

}  // namespace hapticd::device::protocol
