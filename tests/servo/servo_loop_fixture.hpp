// The servo loop's test configuration and loop type, for servo_loop_test.cpp and
// servo_loop_requests_test.cpp.
#pragma once

#include "hapticd/servo/servo_loop.hpp"
#include "servo_fakes.hpp"

namespace hapticd::servo {

using fakes::FakeClock;
using fakes::FakeDevice;
using fakes::PlaneWall;
using fakes::VirtualTime;

inline constexpr double kCountsPerMeter = 1e6;  // 1 um per count

inline ServoConfig test_config() {
    ServoConfig config;
    config.rate_hz = 1000.0;
    config.axes = 1;
    config.counts_per_meter = kCountsPerMeter;
    config.coupling = {.stiffness_n_per_m = 2000.0, .damping_n_s_per_m = 0.0};
    config.safety.max_force_n = 10.0;
    config.safety.soft_start = {.still_speed_mps = 1.0, .still_time_s = 0.0, .ramp_time_s = 0.0};
    config.safety.passivity.mode = PassivityMode::observe;
    config.realtime.mode = RealtimeMode::off;
    config.link_recovery.enabled = false;  // a lost device ends the run
    return config;
}

template <typename Environment>
using TestLoop = ServoLoop<FakeDevice, Environment, FakeClock>;

}  // namespace hapticd::servo
