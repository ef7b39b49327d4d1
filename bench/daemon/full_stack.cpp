#include "full_stack.hpp"

#include <cmath>
#include <glm/geometric.hpp>
#include <initializer_list>

#include "hapticd/daemon/servo_settings.hpp"

namespace hapticd::bench {
namespace {

const std::string kSceneDir = std::string(HAPTICD_SOURCE_DIR) + "/config/scenes/";

// The pen display of config/hapticd.toml (m = 0.1 kg, b = 2 N s/m, 10 um counts) on the
// lockstep clock, starting at `initial_position`. Each axis is held by a stiff grasp (hand
// 0.3 kg, 500 N/m, 5 N s/m) whose set-point is fixed beyond the surface: with the default
// coupling (k_c = 3600 N/m) the handle settles about 12 % of the way from the surface to
// the set-point, and stays there.
std::string sim_table(const std::string& initial_position,
                      std::initializer_list<const char*> set_points_m) {
    std::string toml =
        "mass = 0.1\ndamping = 2.0\ncounts_per_meter = 1e5\nforce_limit = 20.0\n"
        "clock = \"lockstep\"\ninitial_position = " +
        initial_position + "\n";
    for (const char* set_point_m : set_points_m) {
        toml += "[[human]]\nmodel = \"stiff-grasp\"\nhand_mass = 0.3\nhand_stiffness = 500.0\n";
        toml += "hand_damping = 5.0\nset_point = " + std::string(set_point_m) + "\n";
    }
    return toml;
}

/// Full force is flowing: no fault, soft start over, armed, at least 0.5 N.
bool loaded(const servo::TelemetryRecord& r) {
    constexpr std::uint32_t kNotLoaded = servo::kFlagSoftStart | servo::kFlagDisarmed;
    return r.faults == 0u && (r.flags & kNotLoaded) == 0u && force_norm_n(r) > 0.5;
}

// Wall at x = 0, free side x < 0; set-point 5 mm inside: the handle rests ~0.7 mm in,
// about 2.2 N.
bool beyond_wall(const servo::TelemetryRecord& r) { return loaded(r) && r.x_m[0] > 0.0; }

// Set-point (60, 60, 42.5) mm: the proxy sits on the vertex of faces +x, +y and the
// (+1,+1,+1) chamfer (three active constraints, the god-object's largest active set here).
bool past_box_corner(const servo::TelemetryRecord& r) {
    return loaded(r) && r.x_m[0] > 0.05 && r.x_m[1] > 0.05;
}

// Ball centre (40, 0, -20) mm, radius 30 mm; set-point (50, 0, 0) mm, 7.6 mm deep.
bool inside_ball(const servo::TelemetryRecord& r) {
    const glm::dvec3 from_centre(r.x_m[0] - 0.04, r.x_m[1], r.x_m[2] + 0.02);
    return loaded(r) && glm::length(from_centre) < 0.03;
}

// Floor at z = -40 mm; set-point z = -50 mm pulls the virtual puck onto it.
bool puck_on_floor(const servo::TelemetryRecord& r) {
    return loaded(r) && r.xe_m[2] < -0.0399 && r.x_m[2] < -0.04;
}

}  // namespace

double force_norm_n(const servo::TelemetryRecord& r) {
    return std::hypot(r.f_n[0], r.f_n[1], r.f_n[2]);
}

const Scenario kDemoWall1Axis{"demo-wall.toml", 1, sim_table("-0.002", {"0.005"}), &beyond_wall};
const Scenario kBox16Planes3Axis{"box-16-planes.toml", 3,
                                 sim_table("[0.0, 0.0, 0.0]", {"0.06", "0.06", "0.0425"}),
                                 &past_box_corner};
const Scenario kGodObjectSphere3Axis{"god-object-sphere.toml", 3,
                                     sim_table("[0.0, 0.0, 0.0]", {"0.05", "0.0", "0.0"}),
                                     &inside_ball};
const Scenario kVirtualMass3Axis{
    "virtual-mass.toml", 3, sim_table("[0.0, 0.0, 0.0]", {"0.0", "0.0", "-0.05"}), &puck_on_floor};

FullStack::FullStack(const Scenario& s, bool lossless_log)
    : scenario(s), config(daemon::default_config()) {
    config.device.axes = s.axes;
    config.device.plugin_table_toml = s.sim_table_toml;
    config.scene_file = kSceneDir + s.scene_file;
    scene = env::load_scene(config.scene_file, s.axes);

    device = device::load_device(config.device.plugin);
    device::DeviceConfig device_config;
    device_config.axes = s.axes;
    device_config.rate_hz = config.servo.rate_hz;
    device_config.lockstep = true;
    device_config.plugin_table_toml = config.device.plugin_table_toml;
    device_config.source = "daemon_bench";
    device->open(device_config);
    servo = daemon::make_servo_config(config, device->info(), lossless_log);
}

FullStack::~FullStack() { device->close(); }

}  // namespace hapticd::bench
