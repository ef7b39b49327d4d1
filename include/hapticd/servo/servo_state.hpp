// The safety state of the servo loop (docs/architecture.md §7.11), as the operator sees it:
//
//   disabled --arm--> arming --still handle, ramp done--> running
//       ^               |  ^                                 |
//       +----disarm-----+  +-----------reset------+   fault  |
//                                                  \         v
//                                                   +----- fault (latched, zero force)
//
// It is derived, once per tick, from what the loop already holds: the armed flag (arm(),
// disarm()), the fault latch and the soft start's scale (soft_start.hpp: no force until the
// handle is still, then the ramp). A fault zeroes the force in the tick that raised it and
// stays until reset; after a reset an armed loop is arming again.
#pragma once

#include <cstdint>
#include <string_view>

namespace hapticd::servo {

enum class ServoState : std::uint8_t { disabled, arming, running, fault };

constexpr ServoState servo_state(bool armed, std::uint32_t faults,
                                 double soft_start_scale) noexcept {
    if (faults != 0u) return ServoState::fault;
    if (!armed) return ServoState::disabled;
    return soft_start_scale < 1.0 ? ServoState::arming : ServoState::running;
}

constexpr std::string_view servo_state_name(ServoState state) noexcept {
    switch (state) {
        case ServoState::disabled:
            return "disabled";
        case ServoState::arming:
            return "arming";
        case ServoState::running:
            return "running";
        case ServoState::fault:
            return "fault";
    }
    return "unknown";
}

}  // namespace hapticd::servo
