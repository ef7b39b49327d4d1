// The daemon's full servo stack for benchmarks, assembled the way hapticd's run does it
// (src/daemon/run.cpp): the embedded default config, the scene loaded from config/scenes/,
// the `sim` device plugin dlopen()ed by name and opened in lockstep, the ServoConfig from
// make_servo_config, and ServoLoop<device::Device, Environment> over the abstract device and
// environment (virtual calls, as in the daemon).
//
// Each scenario holds the handle in contact: a stiff-grasp human whose fixed set-point lies
// beyond the surface pulls the handle from free space into it and holds it there, so the
// numbers are for a loaded contact (coupling stretched, environment active), not free space.
#pragma once

#include <string>

#include "hapticd/daemon/config.hpp"
#include "hapticd/device/plugin_loader.hpp"
#include "hapticd/env/scene.hpp"
#include "hapticd/servo/servo_config.hpp"
#include "hapticd/servo/servo_loop.hpp"
#include "hapticd/servo/telemetry.hpp"

namespace hapticd::bench {

/// One scene with a sim operator that holds the handle in contact.
struct Scenario {
    const char* scene_file;      ///< under config/scenes/
    int axes;                    ///< the scene's and the device's axis count
    std::string sim_table_toml;  ///< [device.sim] contents with keys at top level
    /// True when `record` shows the contact the scenario is about (beyond the wall, past
    /// the box corner, in the ball, the virtual mass on the floor), at full force.
    bool (*in_contact)(const servo::TelemetryRecord& record);
};

extern const Scenario kDemoWall1Axis;         ///< demo-wall.toml: handle 5 mm set into the wall
extern const Scenario kBox16Planes3Axis;      ///< box-16-planes.toml: past a chamfered corner
extern const Scenario kGodObjectSphere3Axis;  ///< god-object-sphere.toml: pressed into the ball
extern const Scenario kVirtualMass3Axis;      ///< virtual-mass.toml: the puck pushed onto the floor

/// The opened device, the scene and the servo settings of one scenario. Destroy any
/// ServoLoop over it first (the loop writes zero force in its destructor).
class FullStack {
  public:
    /// `lossless_log`: as hapticd --lockstep --log (the loop waits for the telemetry writer).
    /// Throws what the daemon's start-up would (bad scene, plugin not found, bad sim table).
    explicit FullStack(const Scenario& scenario, bool lossless_log = false);
    ~FullStack();
    FullStack(const FullStack&) = delete;
    FullStack& operator=(const FullStack&) = delete;

    const Scenario& scenario;
    daemon::Config config;
    env::Scene scene;
    device::DeviceHandle device;
    servo::ServoConfig servo;
};

/// The loop type hapticd runs (run.cpp): abstract device, abstract environment, CLOCK_MONOTONIC.
template <typename Environment>
using DaemonLoop = servo::ServoLoop<device::Device, Environment>;

/// Calls `body(environment)` with the scene's impedance or admittance environment.
template <typename Body>
void with_environment(env::Scene& scene, Body&& body) {
    if (scene.impedance) {
        body(*scene.impedance);
    } else {
        body(*scene.admittance);
    }
}

/// Virtual time run before measuring: the handle travels into contact, the soft start
/// waits for it to be still (0.2 s) and ramps (0.5 s), and the contact settles.
inline constexpr int kWarmUpTicks = 5000;

/// Ticks `loop` through the warm-up; true when it ends in the scenario's contact.
template <typename Loop>
bool warm_up_into_contact(Loop& loop, const Scenario& scenario) {
    for (int i = 0; i < kWarmUpTicks; ++i) (void)loop.tick();
    return scenario.in_contact(loop.last_record());
}

/// |f|, N, of a record.
double force_norm_n(const servo::TelemetryRecord& record);

}  // namespace hapticd::bench
