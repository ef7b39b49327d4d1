#include "socket/scene_switch.hpp"

#include <chrono>
#include <exception>
#include <thread>
#include <utility>

#include "hapticd/env/external_environment.hpp"
#include "run/run_setup.hpp"

namespace hapticd::daemon {
namespace {

// How long a load waits for a tick to take the scene: a tick comes every period, but a lockstep
// run waits for its device, and a run that is ending takes nothing.
constexpr auto kTakeTimeout = std::chrono::seconds(2);

Config with_gains(Config config, const servo::CouplingGains& gains) {
    config.coupling.stiffness_n_per_m = gains.stiffness_n_per_m;
    config.coupling.damping_n_s_per_m = gains.damping_n_s_per_m;
    return config;
}

SceneLoadResult refused(const std::string& path, std::string why) {
    return {.ok = false, .message = std::move(why), .path = path};
}

}  // namespace

SceneSwitch::SceneSwitch(const Config& config, const env::Scene& initial,
                         std::string initial_source, env::SceneOptions options, SceneLoopPort port)
    : config_(config),
      options_(std::move(options)),
      port_(std::move(port)),
      current_(&initial),
      in_force_{.name = initial.name, .source = std::move(initial_source)} {}

SceneLoadResult SceneSwitch::load(const std::string& path, const servo::CouplingGains& gains,
                                  const input::FileCheck& may_load) {
    const std::lock_guard lock(mutex_);
    auto scene = std::make_unique<env::Scene>();
    const Config candidate = with_gains(config_, gains);
    StartupCheck check;
    try {
        *scene = env::parse_scene(
            input::read_text_file(path, "the scene file", input::kMaxTomlBytes, may_load), path,
            config_.device.axes, options_);
        if (scene->causality != current_->causality) {
            return refused(path, path + " (scene \"" + scene->name + "\") is an " +
                                     env::to_string(scene->causality) +
                                     " scene; this run renders " +
                                     env::to_string(current_->causality) +
                                     " scenes: restart hapticd with it in [scene] file");
        }
        check_scene_renderable(*scene, candidate, path);
        check = check_coupling_at_startup(candidate, *scene, path);
    } catch (const std::exception& e) {  // the scene file, or the check's own range checks
        return refused(path, e.what());
    }
    if (!check.skipped && !check.passed) {
        return refused(path,
                       "the stability check fails with the gains in force: " + check.describe());
    }
    if (!port_.offer(*scene)) return refused(path, "another scene is waiting to be taken");
    const auto deadline = std::chrono::steady_clock::now() + kTakeTimeout;
    while (!port_.taken() && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (!port_.taken() && port_.withdraw(*scene)) {
        return refused(path, "the servo loop took no tick within 2 s (is the run ending?)");
    }
    // Taken: no tick reaches the scene it replaced any more. An external world's channel made
    // beside the one in force takes its path now (external_channel.hpp).
    std::string channel_note;
    if (auto* world = dynamic_cast<env::ExternalEnvironment*>(scene->admittance.get())) {
        channel_note = world->channel().claim_path();
    }
    current_ = scene.get();
    loaded_ = std::move(scene);  // frees the one before, if a load made it
    {
        const std::lock_guard in_force_lock(in_force_mutex_);
        in_force_ = {.name = current_->name, .source = path};
    }
    return {.ok = true,
            .message = "scene \"" + current_->name + "\" from " + path +
                       " from the next tick, through the soft start; " + check.describe() +
                       (channel_note.empty() ? "" : "; " + channel_note),
            .name = current_->name,
            .path = path,
            .verdict = check.describe()};
}

StartupCheck SceneSwitch::check_coupling(const servo::CouplingGains& gains) const {
    const std::lock_guard lock(mutex_);
    return check_coupling_at_startup(with_gains(config_, gains), *current_, in_force().source);
}

SceneInForce SceneSwitch::in_force() const {
    const std::lock_guard lock(in_force_mutex_);
    return in_force_;
}

}  // namespace hapticd::daemon
