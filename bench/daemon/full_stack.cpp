#include "full_stack.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <glm/geometric.hpp>
#include <initializer_list>
#include <limits>
#include <stdexcept>

#include "hapticd/daemon/servo_settings.hpp"
#include "hapticd/env/external_world.h"

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

// The same, with the external world's tool in its wall, at most where the handle is. The world
// wants it at x = 0; with between_updates = "extrapolate" the approach carries it past, and
// the passivity controller keeps it there (pulling it back out against the handle would give
// the handle energy the world never took): 0.16 mm in.
bool on_external_wall(const servo::TelemetryRecord& r) {
    return beyond_wall(r) && r.xe_m[0] >= 0.0 && r.xe_m[0] <= r.x_m[0];
}

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

const ExternalScenario kExternalWall1Axis{
    {"<external-wall: daemon_bench>", 1, sim_table("-0.002", {"0.005"}), &on_external_wall},
    "[scene]\nname = \"external-wall\"\naxes = 1\n[external]\n"
    "between_updates = \"extrapolate\"\nlockstep_every = 0\npassivity = \"control\"\n",
    10};
const ExternalScenario kExternalWallHold1Axis{
    {"<external-wall-hold: daemon_bench>", 1, sim_table("-0.002", {"0.005"}), &on_external_wall},
    "[scene]\nname = \"external-wall-hold\"\naxes = 1\n[external]\n"
    "between_updates = \"hold\"\nlockstep_every = 0\npassivity = \"control\"\n",
    10};

FullStack::FullStack(const Scenario& s, bool lossless_log)
    : scenario(s), config(daemon::default_config()) {
    config.device.axes = s.axes;
    config.device.plugin_table_toml = s.sim_table_toml;
    config.scene_file = kSceneDir + s.scene_file;
    scene = env::load_scene(config.scene_file, s.axes);
    open_device(lossless_log);
}

FullStack::FullStack(const Scenario& s, std::string_view scene_text, env::SceneOptions options)
    : scenario(s), config(daemon::default_config()) {
    config.device.axes = s.axes;
    config.device.plugin_table_toml = s.sim_table_toml;
    config.scene_file = s.scene_file;
    options.rate_hz = config.servo.rate_hz;
    scene = env::parse_scene(scene_text, s.scene_file, s.axes, options);
    open_device(false);
}

void FullStack::open_device(bool lossless_log) {
    device = device::load_device(config.device.plugin);
    device::DeviceConfig device_config;
    device_config.axes = scenario.axes;
    device_config.rate_hz = config.servo.rate_hz;
    device_config.lockstep = true;
    device_config.plugin_table_toml = config.device.plugin_table_toml;
    device_config.source = "daemon_bench";
    device->open(device_config);
    servo = daemon::make_servo_config(config, device->info(), lossless_log);
}

FullStack::~FullStack() { device->close(); }

ScratchDir::ScratchDir() {
    const char* tmp = std::getenv("TMPDIR");
    std::string name =
        std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/daemon_bench.XXXXXX";
    if (::mkdtemp(name.data()) == nullptr) {
        throw std::runtime_error("mkdtemp " + name + ": " + std::strerror(errno));
    }
    path_ = name;
}

ScratchDir::~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
}

namespace {

constexpr std::size_t kWord = sizeof(std::uint64_t);

// The words of a block in the mapping as atomics, as the daemon's side (external_channel.cpp).
std::atomic_ref<std::uint64_t> word(void* memory, std::size_t offset) {
    return std::atomic_ref<std::uint64_t>(
        *static_cast<std::uint64_t*>(static_cast<void*>(static_cast<char*>(memory) + offset)));
}

}  // namespace

ExternalWorld::ExternalWorld(const std::string& channel_path) {
    const int fd = ::open(channel_path.c_str(), O_RDWR | O_CLOEXEC);
    if (fd < 0) {
        throw std::runtime_error("external world channel " + channel_path + ": " +
                                 std::strerror(errno));
    }
    memory_ = ::mmap(nullptr, HAPTICD_WORLD_SIZE, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    ::close(fd);  // the mapping keeps the file
    if (memory_ == MAP_FAILED) {
        memory_ = nullptr;
        throw std::runtime_error("external world channel " + channel_path +
                                 ": mmap: " + std::strerror(errno));
    }
    hapticd_world_header header{};
    std::memcpy(&header, memory_, sizeof header);
    if (std::memcmp(header.magic, HAPTICD_WORLD_MAGIC, sizeof header.magic) != 0 ||
        header.version != HAPTICD_WORLD_VERSION || header.closed != 0u) {
        ::munmap(memory_, HAPTICD_WORLD_SIZE);
        memory_ = nullptr;
        throw std::runtime_error("external world channel " + channel_path +
                                 ": not an open channel of version 1");
    }
    // As external.py: go on from the next even sequence.
    const std::uint64_t sequence =
        word(memory_, HAPTICD_WORLD_UPDATE_OFFSET).load(std::memory_order_relaxed);
    sequence_ = sequence + (sequence & 1u);
}

ExternalWorld::~ExternalWorld() {
    if (memory_ != nullptr) ::munmap(memory_, HAPTICD_WORLD_SIZE);
}

bool ExternalWorld::update() noexcept {
    // The daemon's block: a copy between two equal, even reads of its sequence (World.read()).
    constexpr std::size_t kTickWords = sizeof(hapticd_world_tick) / kWord;
    std::array<std::uint64_t, kTickWords> words{};
    auto tick_sequence = word(memory_, HAPTICD_WORLD_TICK_OFFSET);
    const std::uint64_t before = tick_sequence.load(std::memory_order_acquire);
    if ((before & 1u) != 0u) return false;
    for (std::size_t i = 0; i < kTickWords; ++i) {
        words[i] =
            word(memory_, HAPTICD_WORLD_TICK_OFFSET + i * kWord).load(std::memory_order_relaxed);
    }
    std::atomic_thread_fence(std::memory_order_acquire);
    if (tick_sequence.load(std::memory_order_relaxed) != before) return false;
    hapticd_world_tick step{};
    std::memcpy(static_cast<void*>(&step), words.data(), sizeof step);

    // The world: a god-object wall at x = 0, free side x < 0 (World.write([min(x, 0)],
    // world_time_s=step.time_s)).
    hapticd_world_update next{};
    next.update = ++update_;
    next.answers = 0;
    next.world_time_s = step.time_s;
    next.tool_position_m[0] = std::min(step.handle_position_m[0], 0.0);
    std::fill(std::begin(next.tool_velocity_mps), std::end(next.tool_velocity_mps),
              std::numeric_limits<double>::quiet_NaN());  // not given
    std::array<std::uint64_t, sizeof(hapticd_world_update) / kWord> out{};
    std::memcpy(out.data(), &next, sizeof next);
    auto sequence = word(memory_, HAPTICD_WORLD_UPDATE_OFFSET);
    sequence.store(sequence_ + 1, std::memory_order_relaxed);  // odd: a write in progress
    std::atomic_thread_fence(std::memory_order_release);
    for (std::size_t i = 1; i < out.size(); ++i) {
        word(memory_, HAPTICD_WORLD_UPDATE_OFFSET + i * kWord)
            .store(out[i], std::memory_order_relaxed);
    }
    sequence_ += 2;
    sequence.store(sequence_, std::memory_order_release);
    return true;
}

}  // namespace hapticd::bench
