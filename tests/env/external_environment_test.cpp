// An external world (env/external_environment.hpp) through its channel (external_channel.hpp),
// with the world's side played by the test through its own mapping of the file: before an
// update the tool follows the handle; an update is held or extrapolated; a world that stops is
// stale after its time, and the tool is led onto the handle over the ramp; values that are not
// finite are refused; lockstep waits for the answer, and after a timeout asks on without
// waiting until the world answers again; the tick allocates nothing. The channel's file: 0660,
// removed when the world lets go, a dead daemon's replaced, anything else refused by name.
#include "hapticd/env/external_environment.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "alloc_guard.hpp"
#include "hapticd/env/scene.hpp"
#include "scratch_dir.hpp"

namespace hapticd::env {
namespace {

using hapticd::testing::ScratchDir;

constexpr double kT = 1.0 / 1024.0;  // exact in binary: the tick counts below are exact
const CouplingGains kGains{.stiffness_n_per_m = 2000.0, .damping_n_s_per_m = 0.0};
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The world's side: its own mapping of the channel, writing its block as a world would.
class WorldSide {
  public:
    explicit WorldSide(const std::string& path) {
        const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
        if (fd < 0) throw std::runtime_error("open " + path);
        memory_ = ::mmap(nullptr, HAPTICD_WORLD_SIZE, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
        ::close(fd);
        if (memory_ == MAP_FAILED) throw std::runtime_error("mmap " + path);
    }
    ~WorldSide() { ::munmap(memory_, HAPTICD_WORLD_SIZE); }
    WorldSide(const WorldSide&) = delete;
    WorldSide& operator=(const WorldSide&) = delete;

    // The block's words as atomics, as the daemon reads and writes them (a test thread plays
    // the world while the servo's runs: no data race for TSan to see).
    void write(const Vec3& tool_m, const Vec3& velocity_mps = Vec3(kNaN),
               std::uint64_t answers = 0) {
        hapticd_world_update u{};
        u.update = ++update_;
        u.answers = answers;
        u.world_time_s = kNaN;
        for (int i = 0; i < 3; ++i) {
            u.tool_position_m[i] = tool_m[i];
            u.tool_velocity_mps[i] = velocity_mps[i];
        }
        std::array<std::uint64_t, sizeof u / 8> words{};
        std::memcpy(words.data(), &u, sizeof u);
        auto sequence = word(HAPTICD_WORLD_UPDATE_OFFSET);
        const std::uint64_t before = sequence.load();
        sequence.store(before + 1);
        std::atomic_thread_fence(std::memory_order_release);
        for (std::size_t i = 1; i < words.size(); ++i) {
            word(HAPTICD_WORLD_UPDATE_OFFSET + 8 * i).store(words[i], std::memory_order_relaxed);
        }
        sequence.store(before + 2, std::memory_order_release);
    }
    hapticd_world_tick tick() const {
        std::array<std::uint64_t, sizeof(hapticd_world_tick) / 8> words{};
        for (;;) {
            const std::uint64_t before = word(HAPTICD_WORLD_TICK_OFFSET).load();
            for (std::size_t i = 0; i < words.size(); ++i) {
                words[i] = word(HAPTICD_WORLD_TICK_OFFSET + 8 * i).load(std::memory_order_relaxed);
            }
            std::atomic_thread_fence(std::memory_order_acquire);
            if (before % 2 == 0 && word(HAPTICD_WORLD_TICK_OFFSET).load() == before) break;
        }
        hapticd_world_tick t{};
        std::memcpy(&t, words.data(), sizeof t);
        return t;
    }
    hapticd_world_header header() const {
        hapticd_world_header h{};
        std::memcpy(&h, memory_, sizeof h);
        return h;
    }

  private:
    std::atomic_ref<std::uint64_t> word(std::size_t offset) const {
        return std::atomic_ref<std::uint64_t>(
            *reinterpret_cast<std::uint64_t*>(static_cast<char*>(memory_) + offset));
    }
    void* memory_ = nullptr;
    std::uint64_t update_ = 0;
};

struct Fixture {
    explicit Fixture(ExternalSpec spec = {}, const std::atomic<bool>* stop = nullptr)
        : path(dir.file("d.world")) {
        std::string note;
        environment = std::make_unique<ExternalEnvironment>(
            spec,
            std::make_unique<ExternalChannel>(path,
                                              ChannelShape{.axes = 1,
                                                           .lockstep_every = spec.lockstep_every,
                                                           .stale_after_s = spec.stale_after_s},
                                              "", note),
            1, stop);
        world = std::make_unique<WorldSide>(path);
        environment->reset(Vec3(0.0));
    }
    Vec3 step(const Vec3& x_d, const Vec3& v_d = Vec3(0.0)) {
        return environment->step(x_d, v_d, kGains, kT);
    }
    ScratchDir dir;
    std::string path;
    std::unique_ptr<ExternalEnvironment> environment;
    std::unique_ptr<WorldSide> world;
};

ExternalSpec without_controller(ExternalSpec spec = {}) {
    spec.passivity = PassivityMode::off;
    return spec;
}

TEST(EnvExternalWorld, BeforeAnyUpdateTheToolFollowsTheHandleAndTheStepsArePublished) {
    Fixture f;
    EXPECT_EQ(f.world->header().axes, 1u);
    EXPECT_EQ(std::memcmp(f.world->header().magic, HAPTICD_WORLD_MAGIC, 8), 0);
    EXPECT_EQ(f.world->header().daemon_pid, ::getpid());
    for (int n = 1; n <= 5; ++n) {
        const Vec3 x_d(0.001 * n, 0.0, 0.0);
        EXPECT_EQ(f.step(x_d, Vec3(1.0, 0.0, 0.0)), x_d);
        const hapticd_world_tick t = f.world->tick();
        EXPECT_EQ(t.step, static_cast<std::uint64_t>(n));
        EXPECT_EQ(t.handle_position_m[0], x_d.x);
        EXPECT_EQ(t.handle_velocity_mps[0], 1.0);
        EXPECT_EQ(t.tool_position_m[0], x_d.x);
        EXPECT_EQ(t.state, HAPTICD_WORLD_WAITING);
        EXPECT_NEAR(t.time_s, n * kT, 1e-15);
        EXPECT_EQ(t.stiffness_n_per_m, 2000.0);
        EXPECT_EQ(t.sequence % 2, 0u);
    }
    EXPECT_EQ(f.environment->port_report().world_state, 0u);
}

TEST(EnvExternalWorld, AnUpdateIsHeldOrExtrapolatedAlongItsVelocity) {
    for (const BetweenUpdates between : {BetweenUpdates::hold, BetweenUpdates::extrapolate}) {
        SCOPED_TRACE(to_string(between));
        ExternalSpec spec = without_controller();
        spec.between_updates = between;
        Fixture f(spec);
        f.world->write(Vec3(0.002, 0.0, 0.0), Vec3(0.5, 0.0, 0.0));
        for (int n = 0; n < 10; ++n) {
            const Vec3 tool = f.step(Vec3(0.01, 0.0, 0.0));
            const double expected = between == BetweenUpdates::hold ? 0.002 : 0.002 + 0.5 * n * kT;
            EXPECT_NEAR(tool.x, expected, 1e-15) << n;
        }
        EXPECT_EQ(f.environment->state(), WorldState::live);
        EXPECT_EQ(f.world->tick().update_in_force, 1u);
        EXPECT_EQ(f.world->tick().state, HAPTICD_WORLD_LIVE);
        // The coupling's force on the tool, published: k_c (x_d - x_e) (b_c = 0 here).
        EXPECT_NEAR(f.world->tick().coupling_force_n[0],
                    2000.0 * (0.01 - f.world->tick().tool_position_m[0]), 1e-12);
    }
}

TEST(EnvExternalWorld, WithoutAVelocityTheLastTwoUpdatesGiveIt) {
    Fixture f(without_controller());
    f.world->write(Vec3(0.001, 0.0, 0.0));
    for (int n = 0; n < 4; ++n) (void)f.step(Vec3(0.0));
    f.world->write(Vec3(0.003, 0.0, 0.0));  // 2 mm in the 4 ticks between
    EXPECT_NEAR(f.step(Vec3(0.0)).x, 0.003, 1e-15);
    EXPECT_NEAR(f.step(Vec3(0.0)).x, 0.003 + 0.002 / 4.0, 1e-12);
}

TEST(EnvExternalWorld, AWorldThatStopsIsStaleAfterItsTimeAndTheToolIsLedOntoTheHandle) {
    ExternalSpec spec = without_controller();
    spec.between_updates = BetweenUpdates::hold;
    spec.stale_after_s = 10 * kT;
    spec.ramp_s = 20 * kT;
    Fixture f(spec);
    const Vec3 x_d(0.01, 0.0, 0.0);
    f.world->write(Vec3(0.0));
    std::vector<Vec3> tools;
    for (int n = 1; n <= 40; ++n) tools.push_back(f.step(x_d));
    // Step 1 takes the update; steps 2..11 are within stale_after of it; step 12 finds it
    // stale and holds the tool; steps 13..32 lead it onto the handle, linearly, and the force
    // falls with it; from step 32 on the tool is on the handle: no force.
    for (int n = 1; n <= 12; ++n) EXPECT_EQ(tools[n - 1].x, 0.0) << "step " << n;
    for (int n = 13; n <= 31; ++n) {
        EXPECT_NEAR(tools[n - 1].x, 0.01 * (n - 12) / 20.0, 1e-15) << "step " << n;
    }
    for (int n = 32; n <= 40; ++n) EXPECT_EQ(tools[n - 1], x_d) << "step " << n;
    EXPECT_EQ(f.environment->state(), WorldState::stale);
    EXPECT_EQ(f.environment->port_report().stale_episodes, 1u);
    EXPECT_EQ(f.world->tick().state, HAPTICD_WORLD_STALE);
    EXPECT_EQ(f.step(Vec3(0.02, 0.0, 0.0)), Vec3(0.02, 0.0, 0.0));  // it follows the handle
    EXPECT_EQ(f.environment->port_report().since_update_s, 40 * kT);
    // An update brings it back.
    f.world->write(Vec3(0.005, 0.0, 0.0));
    EXPECT_EQ(f.step(x_d).x, 0.005);
    EXPECT_EQ(f.environment->state(), WorldState::live);
    EXPECT_EQ(f.environment->port_report().stale_episodes, 1u);
}

TEST(EnvExternalWorld, AnUpdateWithAValueThatIsNotFiniteIsRefused) {
    Fixture f(without_controller());
    f.world->write(Vec3(0.001, 0.0, 0.0), Vec3(0.0));
    EXPECT_EQ(f.step(Vec3(0.0)).x, 0.001);
    f.world->write(Vec3(kNaN, 0.0, 0.0));
    EXPECT_EQ(f.step(Vec3(0.0)).x, 0.001);
    f.world->write(Vec3(0.002, 0.0, 0.0), Vec3(std::numeric_limits<double>::infinity(), 0.0, 0.0));
    EXPECT_EQ(f.step(Vec3(0.0)).x, 0.001);
    EXPECT_EQ(f.environment->port_report().rejected_updates, 2u);
    // Components past the scene's axes are not the world's: ignored, zero.
    f.world->write(Vec3(0.003, kNaN, 7.0), Vec3(0.0, kNaN, 1.0));
    EXPECT_EQ(f.step(Vec3(0.0)), Vec3(0.003, 0.0, 0.0));
    EXPECT_EQ(f.environment->port_report().rejected_updates, 2u);
}

TEST(EnvExternalWorld, TheControllerKeepsAWorldThatPullsFromRestFromDeliveringEnergy) {
    Fixture f;                                         // passivity = "control"
    f.world->write(Vec3(-0.01, 0.0, 0.0), Vec3(0.0));  // 1 cm from a still handle, from rest
    const Vec3 tool = f.step(Vec3(0.0));
    EXPECT_EQ(tool, Vec3(0.0));  // the port has absorbed nothing: the tool may not move away
    EXPECT_GT(f.environment->port_report().energy_removed_j, 0.0);
    EXPECT_EQ(f.environment->port_report().energy_j, 0.0);
}

TEST(EnvExternalWorld, LockstepWaitsForTheAnswerToItsStepAndUsesIt) {
    ExternalSpec spec = without_controller();
    spec.between_updates = BetweenUpdates::hold;
    spec.lockstep_every = 5;
    Fixture f(spec);
    std::atomic<bool> done{false};
    std::thread world([&] {
        std::uint64_t answered = 0;
        while (!done.load()) {
            const hapticd_world_tick t = f.world->tick();
            if (t.answer_for > answered) {
                answered = t.answer_for;
                f.world->write(Vec3(0.001 * static_cast<double>(answered), 0.0, 0.0), Vec3(0.0),
                               answered);
            }
            std::this_thread::yield();
        }
    });
    for (int n = 1; n <= 20; ++n) {
        const Vec3 tool = f.step(Vec3(0.5, 0.0, 0.0));
        // Step n renders the answer to the last multiple of 5 up to n: it waited for it.
        const int asked = n - n % 5;
        EXPECT_EQ(tool.x, asked == 0 ? 0.5 : 0.001 * asked) << "step " << n;
    }
    done = true;
    world.join();
    EXPECT_EQ(f.world->tick().answer_for, 0u);
}

TEST(EnvExternalWorld, AfterATimeoutLockstepAsksWithoutWaitingUntilTheWorldAnswersAgain) {
    ExternalSpec spec = without_controller();
    spec.between_updates = BetweenUpdates::hold;
    spec.lockstep_every = 2;
    spec.lockstep_timeout_s = 0.001;
    Fixture f(spec);
    (void)f.step(Vec3(0.0));
    (void)f.step(Vec3(0.0));  // asks, nobody answers: times out
    for (int n = 3; n <= 8; ++n) (void)f.step(Vec3(0.0));
    EXPECT_EQ(f.world->tick().answer_for, 8u);  // still asking, at every second step
    // A late answer to the step asking brings the waits back: the next asking step waits for
    // its own answer, which a thread gives.
    f.world->write(Vec3(0.004, 0.0, 0.0), Vec3(0.0), 8);
    EXPECT_EQ(f.step(Vec3(0.0)).x, 0.004);
    EXPECT_EQ(f.world->tick().answer_for, 0u);
    std::thread world([&] {
        while (f.world->tick().answer_for != 10) std::this_thread::yield();
        f.world->write(Vec3(0.007, 0.0, 0.0), Vec3(0.0), 10);
    });
    spec.lockstep_timeout_s = 0.0;  // (the fixture's copy is what counts: 1 ms)
    const Vec3 tool = f.step(Vec3(0.0));
    world.join();
    // Either it waited and rendered the answer, or the host stalled the thread past 1 ms and it
    // timed out: both are right; which one is not the test's (no timing assumed). In the first
    // case the answer is in force now, in the second at the next step at the latest.
    EXPECT_TRUE(tool.x == 0.007 || f.step(Vec3(0.0)).x == 0.007);
}

TEST(EnvExternalWorld, ALockstepWaitEndsWhenTheDaemonStops) {
    std::atomic<bool> stop{true};
    ExternalSpec spec = without_controller();
    spec.lockstep_every = 1;
    spec.lockstep_timeout_s = 600.0;
    Fixture f(spec, &stop);
    EXPECT_EQ(f.step(Vec3(0.001, 0.0, 0.0)).x, 0.001);  // returned: no world ever answers
}

TEST(EnvExternalWorld, TheTickAllocatesNothing) {
    Fixture f;
    f.world->write(Vec3(0.001, 0.0, 0.0));
    (void)f.step(Vec3(0.0));
    const hapticd::testing::AllocationGuard guard;
    for (int n = 0; n < 5000; ++n) {
        if (n % 10 == 0) f.world->write(Vec3(0.001 * std::sin(n * 1e-3), 0.0, 0.0));
        (void)f.step(Vec3(0.002 * std::sin(n * 2e-3), 0.0, 0.0), Vec3(0.004, 0.0, 0.0));
    }
    (void)f.environment->port_report();
    EXPECT_EQ(guard.allocations(), 0u);
}

// ---- the channel's file ----

std::string refusal(const std::string& path) {
    try {
        std::string note;
        ExternalChannel channel(path, {}, "", note);
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return "";
}

void write_header(const std::string& path, std::int32_t pid, std::uint32_t closed) {
    hapticd_world_header h{};
    std::memcpy(h.magic, HAPTICD_WORLD_MAGIC, 8);
    h.version = HAPTICD_WORLD_VERSION;
    h.size = HAPTICD_WORLD_SIZE;
    h.daemon_pid = pid;
    h.closed = closed;
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(&h), sizeof h);
}

TEST(EnvExternalChannel, ItIsTheSocketsNameWith_world_Mode0660AndGoneWhenLetGo) {
    EXPECT_EQ(channel_beside("/run/hapticd/sim.sock"), "/run/hapticd/sim.world");
    EXPECT_EQ(channel_beside("/tmp/d"), "/tmp/d.world");
    EXPECT_EQ(channel_beside(".sock"), ".sock.world");
    const ScratchDir dir;
    const std::string path = dir.file("d.world");
    const mode_t old_mask = ::umask(0027);  // the unit's: the group keeps its write access
    {
        std::string note;
        const ExternalChannel channel(path, {}, "", note);
        struct stat st {};
        ASSERT_EQ(::stat(path.c_str(), &st), 0);
        EXPECT_EQ(st.st_mode & 0777, 0660u);
        EXPECT_EQ(st.st_size, static_cast<off_t>(HAPTICD_WORLD_SIZE));
        EXPECT_EQ(note, "");
    }
    ::umask(old_mask);
    EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(EnvExternalChannel, ADeadDaemonsChannelIsReplacedAndAnythingElseIsRefusedByName) {
    const ScratchDir dir;
    const std::string path = dir.file("d.world");
    // Its daemon let go (closed), or is gone (a pid no process has): replaced.
    write_header(path, 1, 1);
    EXPECT_EQ(refusal(path), "");
    write_header(path, 2147483647, 0);
    EXPECT_EQ(refusal(path), "");
    EXPECT_FALSE(std::filesystem::exists(path));
    // A live daemon's (pid 1 stands for one): in use.
    write_header(path, 1, 0);
    EXPECT_EQ(refusal(path), "external world channel " + path +
                                 ": is in use: hapticd pid 1 renders a world through it (one "
                                 "channel per instance)");
    // Not a channel at all: never removed.
    std::ofstream(path) << "someone's notes\n";
    EXPECT_EQ(refusal(path), "external world channel " + path +
                                 ": exists and is not an external world's channel: remove it, "
                                 "or give the control socket another name");
    EXPECT_TRUE(std::filesystem::exists(path));
    // A symbolic link is not followed.
    std::filesystem::remove(path);
    std::filesystem::create_symlink(dir.file("elsewhere"), path);
    EXPECT_NE(refusal(path).find("exists, and cannot be read to see whose it is (Too many levels "
                                 "of symbolic links): remove it"),
              std::string::npos)
        << refusal(path);
    EXPECT_FALSE(std::filesystem::exists(dir.file("elsewhere")));
}

TEST(EnvExternalChannel, ASceneLoadedBesideOneInForceTakesThePathOnlyOnceClaimed) {
    const ScratchDir dir;
    const std::string path = dir.file("d.world");
    std::string note;
    auto in_force = std::make_unique<ExternalChannel>(path, ChannelShape{}, "", note);
    {
        // A scene loaded and refused (hapticctl scene): the world in force keeps its file.
        const ExternalChannel refused(path, ChannelShape{.axes = 3}, "", note);
        EXPECT_TRUE(std::filesystem::exists(path + ".next"));
        EXPECT_EQ(WorldSide(path).header().axes, 1u);
    }
    EXPECT_FALSE(std::filesystem::exists(path + ".next"));
    ASSERT_TRUE(std::filesystem::exists(path));
    EXPECT_EQ(WorldSide(path).header().axes, 1u);
    // A scene loaded and taken: claimed, its file moves into the path; the one it replaced,
    // let go of later, leaves it alone.
    ExternalChannel taken(path, ChannelShape{.axes = 2}, "", note);
    EXPECT_EQ(taken.path(), path);
    EXPECT_EQ(taken.claim_path(), "");
    EXPECT_FALSE(std::filesystem::exists(path + ".next"));
    EXPECT_EQ(WorldSide(path).header().axes, 2u);
    in_force.reset();
    ASSERT_TRUE(std::filesystem::exists(path));
    EXPECT_EQ(WorldSide(path).header().axes, 2u);
    EXPECT_EQ(WorldSide(path).header().closed, 0u);
    EXPECT_EQ(taken.claim_path(), "");  // once is enough
}

// ---- the scene's table ----

std::string scene_refusal(const std::string& body, const std::string& channel) {
    try {
        (void)parse_scene("[scene]\nname = \"x\"\naxes = 1\n" + body, "x.toml", 1,
                          {.rate_hz = 1000.0, .external_channel = channel});
    } catch (const SceneError& e) {
        return e.what();
    }
    return "";
}

TEST(EnvExternalWorld, AScenesExternalTableIsReadAsDocumented) {
    const ScratchDir dir;
    const std::string path = dir.file("s.world");
    const Scene scene = parse_scene(
        "[scene]\nname = \"py\"\naxes = 1\n[external]\nlockstep_every = 10\nstale_after = 0.5\n"
        "ramp = 0.3\nbetween_updates = \"hold\"\npassivity = \"observe\"\nlockstep_timeout = 2\n",
        "py.toml", 1, {.rate_hz = 1000.0, .external_channel = path});
    EXPECT_EQ(scene.causality, Causality::admittance);
    ASSERT_TRUE(scene.external.has_value());
    EXPECT_EQ(*scene.external, path);
    const auto* world = dynamic_cast<const ExternalEnvironment*>(scene.admittance.get());
    ASSERT_NE(world, nullptr);
    EXPECT_EQ(world->spec().lockstep_every, 10u);
    EXPECT_EQ(world->spec().stale_after_s, 0.5);
    EXPECT_EQ(world->spec().ramp_s, 0.3);
    EXPECT_EQ(world->spec().between_updates, BetweenUpdates::hold);
    EXPECT_EQ(world->spec().passivity, PassivityMode::observe);
    EXPECT_EQ(world->spec().lockstep_timeout_s, 2.0);
    EXPECT_EQ(WorldSide(path).header().lockstep_every, 10u);
    EXPECT_EQ(WorldSide(path).header().stale_after_s, 0.5);
    // The defaults, in a private channel.
    const Scene plain = parse_scene("[scene]\nname = \"py\"\naxes = 1\n[external]\n", "py.toml", 1);
    const auto* defaults = dynamic_cast<const ExternalEnvironment*>(plain.admittance.get());
    ASSERT_NE(defaults, nullptr);
    EXPECT_EQ(*plain.external, "");
    EXPECT_EQ(defaults->spec().between_updates, BetweenUpdates::extrapolate);
    EXPECT_EQ(defaults->spec().passivity, PassivityMode::control);
    EXPECT_EQ(defaults->spec().lockstep_every, 0u);
    EXPECT_NE(plain.unmodelled.find("the passivity controller on its port keeps it passive"),
              std::string::npos);
}

TEST(EnvExternalWorld, ABadExternalTableIsRefusedNamingTheKeyAndTheRange) {
    EXPECT_EQ(scene_refusal("[external]\nlockstep_every = 100\nstale_after = 0.1\n", ""),
              "x.toml: [external] stale_after = 0.1 is out of range: allowed > lockstep_every / "
              "rate_hz = 0.1 s (a world in lockstep answers once in that long)");
    EXPECT_NE(scene_refusal("[external]\nramp = -1\n", "").find("ramp = -1"), std::string::npos);
    EXPECT_NE(scene_refusal("[external]\npassivity = \"maybe\"\n", "").find("passivity"),
              std::string::npos);
    EXPECT_NE(scene_refusal("[external]\nrate = 3\n", "").find("rate"), std::string::npos);
    EXPECT_EQ(scene_refusal("[external]\n[[wall]]\nnormal = [1.0]\nstiffness = 1.0\n", ""),
              "x.toml: [external] is the whole scene, but this one also has [[wall]]: put the "
              "objects in the external world, or in a scene of their own");
    EXPECT_EQ(scene_refusal("[external]\n[plugin]\nname = \"x\"\n", ""),
              "x.toml: [plugin] and [external] are each a whole scene: keep one");
    EXPECT_NE(scene_refusal("[external]\n", "/nonexistent-dir/d.world")
                  .find("x.toml: [external]: external world channel /nonexistent-dir/d.world: "
                        "cannot be created: No such file or directory"),
              std::string::npos);
}

}  // namespace
}  // namespace hapticd::env
