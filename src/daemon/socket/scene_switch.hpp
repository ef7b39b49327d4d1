// A control socket's `scene_load PATH` (docs/control.md, "scene_load"): another scene file
// rendered from a tick boundary on, through the soft start, without restarting hapticd.
//
// load() runs off the servo thread, on the control server's worker. It reads and builds the
// scene and refuses, with the reason, one of the other causality (the loop was built for
// the run's: restart hapticd for the other), one the coupling cannot render (a detent
// stiffer than -k_c between its notches, as at start-up) and one that fails the stability
// check with the gains in force ([coupling] check and environments, as at start-up). Then it
// offers the scene's environment to the loop (ServoLoop::offer_environment), which takes it
// at the start of a tick; the scene it replaced is freed here once no tick can reach it. A
// coupling request is checked against the scene in force (check_coupling).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/startup_check.hpp"
#include "hapticd/env/scene.hpp"
#include "hapticd/input/text_input.hpp"
#include "hapticd/servo/environment_port.hpp"

namespace hapticd::daemon {

/// What a load came to.
struct SceneLoadResult {
    bool ok = false;
    std::string message{};  ///< why not, or what was done (for the journal)
    std::string name{};     ///< the scene's [scene] name
    std::string path{};
    std::string verdict{};  ///< the stability check's line for the new scene
};

/// The scene the loop renders: its name and where it came from.
struct SceneInForce {
    std::string name;
    std::string source;  ///< the file, or "<embedded demo-wall scene>"
};

/// What the switch needs of the servo loop: run_loop adapts ServoLoop, handing it the scene's
/// environment of the run's causality.
struct SceneLoopPort {
    std::function<bool(env::Scene&)> offer;     ///< ServoLoop::offer_environment
    std::function<bool()> taken;                ///< ServoLoop::offer_taken
    std::function<bool(env::Scene&)> withdraw;  ///< ServoLoop::withdraw_environment
};

class SceneSwitch {
  public:
    /// `config` is the run's; `initial` the scene the run started with, from `initial_source`
    /// (it must outlive the switch: the loop renders it until a load).
    /// Scenes are read with `options` (the initial one's).
    SceneSwitch(const Config& config, const env::Scene& initial, std::string initial_source,
                env::SceneOptions options, SceneLoopPort port);

    /// Loads `path` and has the loop render it, checked against `gains` (the gains in force).
    /// `may_load` sees the opened file's status first and may refuse it (a client's file:
    /// regular, and one the client could read itself; docs/control.md, "Paths and strings"). One
    /// load at a time; the worker's.
    SceneLoadResult load(const std::string& path, const servo::CouplingGains& gains,
                         const input::FileCheck& may_load);
    /// The start-up check of the config with `gains`, against the scene in force (throws as
    /// check_coupling_at_startup does).
    StartupCheck check_coupling(const servo::CouplingGains& gains) const;
    /// Any thread, cheap: for `status`.
    SceneInForce in_force() const;

  private:
    Config config_;
    env::SceneOptions options_;
    SceneLoopPort port_;
    mutable std::mutex mutex_;           // one load or check at a time
    mutable std::mutex in_force_mutex_;  // never held while loading: status reads it
    const env::Scene* current_;          // the initial scene or *loaded_
    SceneInForce in_force_;
    std::unique_ptr<env::Scene> loaded_;  // the last scene loaded, if any
};

}  // namespace hapticd::daemon
