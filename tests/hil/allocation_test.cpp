// HilAllocation: the real-time rule "no allocation in the tick" (docs/architecture.md §6.2,
// §6.3), checked on the daemon's own pieces wired as run_daemon wires them: the real sim plugin
// loaded through the plugin loader, every shipped scene built by the scene loader, the
// ServoConfig from
// make_servo_config, the lock-free telemetry ring drained by the daemon's TelemetryWriter
// on its own thread, and ServoLoop::run, the loop the servo thread runs. Only the test
// thread (the servo thread here) is counted, with the handle pressed into each scene by a
// stiff grasp so that the environment, the coupling (17)/(22) and the safety stage all work
// during the guarded ticks.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iostream>
#include <set>
#include <string>
#include <vector>

#include "alloc_guard.hpp"
#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/device_open.hpp"
#include "hapticd/daemon/servo_settings.hpp"
#include "hapticd/daemon/telemetry_writer.hpp"
#include "hapticd/device/plugin_loader.hpp"
#include "hapticd/env/scene.hpp"
#include "hapticd/servo/servo_loop.hpp"
#include "operators.hpp"
#include "pen_display.hpp"
#include "scratch_dir.hpp"
#include "telemetry_csv.hpp"

namespace hapticd::testing {
namespace {

constexpr std::uint64_t kWarmupTicks = 2'000;  ///< soft start done, the push arrived
constexpr std::uint64_t kGuardedTicks = 20'000;

/// Every scene shipped in config/scenes, with its axes and where the grasp's set-point goes
/// (the same on every axis: along the diagonal) and how fast, so that the handle presses
/// into something during the guarded ticks.
struct SceneCase {
    std::string file;
    int axes;
    double push_to_m;
    double push_ramp_s;
};

const std::vector<SceneCase>& shipped_scenes() {
    static const std::vector<SceneCase> scenes = {
        {"demo-wall.toml", 1, 0.005, 0.5},          // 5 mm into the wall at x = 0
        {"god-object-sphere.toml", 3, -0.06, 0.5},  // 1 cm into the table at z = -5 cm
        {"box-16-planes.toml", 3, 0.055, 0.5},      // into three faces and a chamfered corner
        {"virtual-mass.toml", 3, -0.06, 0.5},       // drags the puck onto the floor and bowl
        {"detent-friction.toml", 2, 0.05, 20.0},    // slides over 10 detents, slipping
    };
    return scenes;
}

std::string scenes_dir() { return std::string(HAPTICD_SOURCE_DIR) + "/config/scenes"; }

struct GuardedRun {
    std::uint64_t allocations = 0;
    std::uint32_t faults = 0;
    std::size_t guarded_rows = 0;
    std::size_t rows_with_force = 0;  ///< |F| > 0.1 N
    double max_force_n = 0.0;
};

template <typename Environment>
GuardedRun run_guarded(device::Device& device, Environment& environment,
                       const servo::ServoConfig& servo_config, const std::string& csv_path,
                       int axes) {
    // The daemon's lockstep ring and writer: the loop waits for room (backpressure), the
    // writer formats CSV on its own thread.
    servo::TelemetryRing ring(std::size_t{1} << 14);
    daemon::TelemetryWriter writer(ring, csv_path, axes);
    writer.start();
    GuardedRun result;
    {
        servo::ServoLoop<device::Device, Environment> loop(device, environment, servo_config,
                                                           &ring);
        const std::atomic<bool> stop{false};
        (void)loop.run(stop, kWarmupTicks);
        const AllocationGuard guard;
        (void)loop.run(stop, kGuardedTicks);
        result.allocations = guard.allocations();
        result.faults = loop.faults_seen();
    }
    writer.finish();

    const TelemetryLog log = read_telemetry(csv_path);
    const auto& tick = log.column("tick");
    for (std::size_t row = 0; row < log.rows(); ++row) {
        if (tick[row] < static_cast<double>(kWarmupTicks)) continue;
        ++result.guarded_rows;
        double force_squared = 0.0;
        for (int axis = 0; axis < axes; ++axis) {
            const double f = log.column("f" + std::to_string(axis) + "_n")[row];
            force_squared += f * f;
        }
        const double force_n = std::sqrt(force_squared);
        result.max_force_n = std::max(result.max_force_n, force_n);
        if (force_n > 0.1) ++result.rows_with_force;
    }
    return result;
}

/// A stiff grasp's hand, set-point spring and push, with absorbers on the handle (the
/// largest operator the sim holds is 8 of them; 3 here, 80 Hz to 2 kHz).
std::string multi_mode_grasp(const std::string& push) {
    return "model = \"multi-mode-grasp\"\nhand_mass = 0.3\nhand_stiffness = 500.0\n"
           "hand_damping = 5.0\nmodes = [{ mass = 0.05, stiffness = 12633.0, damping = 0.2 }, "
           "{ mass = 0.01, stiffness = 63165.0, damping = 0.01 }, "
           "{ mass = 0.002, stiffness = 315827.0 }]\n" +
           push;
}

GuardedRun run_scene(
    const SceneCase& scene_case, const std::string& passivity, double stiffness_n_per_m = 3600.0,
    const std::string& sim_keys = "", double damping_n_s_per_m = 0.0,
    double velocity_filter_hz = 0.0,
    const std::function<std::string(const std::string&)>& grasp = [](const std::string& push) {
        return stiff_grasp(push);
    }) {
    const ScratchDir dir;
    DaemonConfig text;
    text.axes = scene_case.axes;
    text.sim_keys = sim_keys;
    text.coupling = coupling_table({.stiffness_n_per_m = stiffness_n_per_m,
                                    .damping_n_s_per_m = damping_n_s_per_m,
                                    .velocity_filter_hz = velocity_filter_hz},
                                   "encoder");
    text.humans =
        human_table(grasp(push_toml(scene_case.push_to_m, 0.0, scene_case.push_ramp_s, 1000.0)));
    text.passivity = passivity;
    text.scene_file = scenes_dir() + "/" + scene_case.file;
    const daemon::Config config =
        daemon::parse_config(text.toml(), "hil-allocation.toml", dir.path().string());

    device::DeviceHandle device = device::load_device("sim");
    device->open(daemon::device_config(config, /*lockstep=*/true));
    const device::DeviceInfo info = device->info();
    EXPECT_TRUE(info.lockstep);
    const servo::ServoConfig servo_config = daemon::make_servo_config(config, info, true);
    EXPECT_TRUE(servo_config.telemetry_backpressure);

    env::Scene scene = env::load_scene(config.scene_file, config.device.axes);
    const std::string csv = dir.file("run.csv");
    GuardedRun result =
        scene.causality == env::Causality::impedance
            ? run_guarded(*device, *scene.impedance, servo_config, csv, scene_case.axes)
            : run_guarded(*device, *scene.admittance, servo_config, csv, scene_case.axes);
    device->close();
    return result;
}

// The guard is live in this program: it sees an allocation made on this thread.
TEST(HilAllocation, GuardCountsThisThreadsAllocations) {
    const AllocationGuard guard;
    const std::vector<double> buffer(1000, 1.0);
    EXPECT_GE(guard.allocations(), 1u);
    EXPECT_EQ(buffer.size(), 1000u);
}

TEST(HilAllocation, EveryShippedSceneIsCovered) {
    std::set<std::string> shipped;
    for (const auto& entry : std::filesystem::directory_iterator(scenes_dir())) {
        if (entry.path().extension() == ".toml") shipped.insert(entry.path().filename().string());
    }
    std::set<std::string> covered;
    for (const SceneCase& scene : shipped_scenes()) covered.insert(scene.file);
    EXPECT_EQ(shipped, covered) << "add the new scene to shipped_scenes() with a push into it";
}

TEST(HilAllocation, TicksOfTheDaemonLoopDoNotAllocateInAnyShippedScene) {
    for (const SceneCase& scene : shipped_scenes()) {
        for (const std::string passivity : {"observe", "control"}) {
            SCOPED_TRACE(scene.file + ", passivity = " + passivity);
            const GuardedRun run = run_scene(scene, passivity);
            std::cout << "[hil] allocation: " << scene.file << " (passivity " << passivity
                      << "): " << run.allocations << " allocations in " << kGuardedTicks
                      << " ticks; force > 0.1 N in " << run.rows_with_force << "/"
                      << run.guarded_rows << " ticks, max " << run.max_force_n << " N\n";
            EXPECT_EQ(run.allocations, 0u);
            EXPECT_EQ(run.faults, 0u);
            EXPECT_EQ(run.guarded_rows, kGuardedTicks);  // every tick logged (backpressure)
            // In contact: the guarded ticks really rendered forces.
            EXPECT_GE(run.rows_with_force, kGuardedTicks * 9 / 10);
        }
    }
}

// The sim's loop delay (1.5 periods: the whole-period pipeline and the split period) is in the
// tick too; gains inside its passive bound (4000/6.5 = 615 N/m) keep the contact.
TEST(HilAllocation, TicksWithADelayedSimDoNotAllocate) {
    const GuardedRun run =
        run_scene(shipped_scenes().front(), "observe", 500.0, "delay = 0.0015\n");
    EXPECT_EQ(run.allocations, 0u);
    EXPECT_EQ(run.faults, 0u);
    EXPECT_EQ(run.guarded_rows, kGuardedTicks);
    EXPECT_GE(run.rows_with_force, kGuardedTicks * 9 / 10);
}

// The sim's plant at its largest kind: a multi-mode grasp (a network of 4 masses, 8 states),
// with a fractional delay (the split period's two exact steps): fixed-size Eigen storage, no
// heap, in the sim's write as in the loop's own tick.
TEST(HilAllocation, TicksWithAMultiModeGraspInTheSimDoNotAllocate) {
    const GuardedRun run = run_scene(shipped_scenes().front(), "observe", 500.0, "delay = 0.0015\n",
                                     0.0, 0.0, multi_mode_grasp);
    EXPECT_EQ(run.allocations, 0u);
    EXPECT_EQ(run.faults, 0u);
    EXPECT_EQ(run.guarded_rows, kGuardedTicks);
    EXPECT_GE(run.rows_with_force, kGuardedTicks * 9 / 10);
}

// The coupling damper on a filtered velocity ([coupling] velocity_filter), in the series solve
// (17) of the demo wall and the admittance step (22) of the virtual mass: its state and the
// equivalent gains handed to the environment are in the coupling, nothing on the heap.
TEST(HilAllocation, TicksWithAFilteredCouplingDoNotAllocate) {
    for (const SceneCase& scene : shipped_scenes()) {
        if (scene.file != "demo-wall.toml" && scene.file != "virtual-mass.toml") continue;
        SCOPED_TRACE(scene.file);
        const GuardedRun run = run_scene(scene, "observe", 3000.0, "", 0.5, 100.0);
        EXPECT_EQ(run.allocations, 0u);
        EXPECT_EQ(run.faults, 0u);
        EXPECT_EQ(run.guarded_rows, kGuardedTicks);
        EXPECT_GE(run.rows_with_force, kGuardedTicks * 9 / 10);
    }
}

}  // namespace
}  // namespace hapticd::testing
