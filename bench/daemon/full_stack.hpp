// The daemon's full servo stack for benchmarks, assembled the way hapticd's run does it
// (src/daemon/run.cpp): the embedded default config, the scene loaded from config/scenes/,
// the `sim` device plugin dlopen()ed by name and opened in lockstep, the ServoConfig from
// make_servo_config, and ServoLoop<device::Device, Environment> over the abstract device and
// environment (virtual calls, as in the daemon).
//
// Each scenario holds the handle in contact: a stiff-grasp human whose fixed set-point lies
// beyond the surface pulls the handle from free space into it and holds it there, so the
// numbers are for a loaded contact (coupling stretched, environment active), not free space.
//
// An [external] scene's world (external_environment.hpp) is rendered by another process; here
// ExternalWorld plays it from the benchmark's own thread, through a second mapping of the
// channel in a scratch directory, between ticks.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

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

/// A scene whose world another process renders ([external]): `scene_text` is the scene (it
/// has no file: `scenario.scene_file` names it in messages), its world ExternalWorld, which
/// writes an update every `world_every_ticks` ticks of the servo.
struct ExternalScenario {
    Scenario scenario;
    const char* scene_text;
    int world_every_ticks;
};

/// demo_wall_1axis's operator and contact, the wall rendered by an external world: a
/// god-object wall at x = 0, free side x < 0 (tool = min(handle, 0)), free-running
/// (lockstep_every = 0), passivity = "control", an update every 10 ticks (100 Hz of the
/// servo's 1 kHz), between_updates = "extrapolate" (the default): the tool rests 0.16 mm
/// in, where the approach's extrapolation put it and the passivity controller holds it.
extern const ExternalScenario kExternalWall1Axis;
/// The same with between_updates = "hold": the tool rests on the wall, the controller idle.
extern const ExternalScenario kExternalWallHold1Axis;

/// The opened device, the scene and the servo settings of one scenario. Destroy any
/// ServoLoop over it first (the loop writes zero force in its destructor).
class FullStack {
  public:
    /// `lossless_log`: as hapticd --lockstep --log (the loop waits for the telemetry writer).
    /// Throws what the daemon's start-up would (bad scene, plugin not found, bad sim table).
    explicit FullStack(const Scenario& scenario, bool lossless_log = false);
    /// An [external] scene from `scene_text`, its channel at `options.external_channel` (the
    /// servo's rate is taken from the config, as the daemon's run_scene_options does).
    FullStack(const Scenario& scenario, std::string_view scene_text, env::SceneOptions options);
    ~FullStack();
    FullStack(const FullStack&) = delete;
    FullStack& operator=(const FullStack&) = delete;

    const Scenario& scenario;
    daemon::Config config;
    env::Scene scene;
    device::DeviceHandle device;
    servo::ServoConfig servo;

  private:
    void open_device(bool lossless_log);
};

/// A directory of its own under $TMPDIR (else /tmp), removed with what is left in it.
class ScratchDir {
  public:
    ScratchDir();  ///< throws std::runtime_error
    ~ScratchDir();
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;
    const std::string& path() const noexcept { return path_; }

  private:
    std::string path_;
};

/// The world's side of an external scene's channel (external_world.h), as
/// python/hapticd/external.py writes it, through a mapping of its own: it reads the daemon's
/// last step and writes where the tool of a god-object wall at x = 0 (free side x < 0) is,
/// tool = min(handle, 0) on the first axis, the velocity not given (NaN) and its clock the
/// step's time_s. Same thread as the ticks: no waiting, no race (the seqlocks are kept anyway).
class ExternalWorld {
  public:
    explicit ExternalWorld(const std::string& channel_path);  ///< throws std::runtime_error
    ~ExternalWorld();
    ExternalWorld(const ExternalWorld&) = delete;
    ExternalWorld& operator=(const ExternalWorld&) = delete;

    /// One update of the world; false when the daemon's block was caught in a write.
    bool update() noexcept;
    /// The updates written (the `update` of the last one).
    std::uint64_t updates() const noexcept { return update_; }

  private:
    void* memory_ = nullptr;
    std::uint64_t sequence_ = 0;
    std::uint64_t update_ = 0;
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
