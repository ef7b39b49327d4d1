// A lab's own environment (plugin_abi.h): a shared object loaded by name from a scene's
// [plugin] table, adapted to the two causalities of environment.hpp. The adapter is the
// boundary: whatever the plugin does wrong in the tick (an error code, a value that is not
// finite, an exception, too long a call) latches failed(), and the servo raises the fault
// `environment` at once (zero force); the world is not called again until it is reset (a
// fault reset restarts the environment). Nothing the plugin does wrong crashes hapticd.
//
// The time: the wall time of a tick's calls (CLOCK_MONOTONIC, through the vDSO: about 45 ns
// a reading; a CPU-time clock is a system call of about 1.7 us here). A host that stalls
// inside a call stretches one tick, not two: a world is over its time when the calls of two
// ticks in a row take longer than max_call_us each.
//
// Every call but load runs on the servo thread and allocates, locks and logs nothing: the
// reason is written into a fixed buffer, read off the thread once the fault is latched.
#pragma once

#include <array>
#include <cstdint>
#include <exception>
#include <memory>
#include <string>
#include <string_view>

#include "hapticd/env/environment.hpp"
#include "hapticd/env/plugin_abi.h"
#include "hapticd/servo/monotonic_clock.hpp"

namespace hapticd::env {

/// A scene's [plugin] table (docs/scenes.md, "Your own world").
struct PluginSpec {
    std::string name;           ///< a plugin name (libhapticd-env-NAME.so...) or a path with '/'
    double max_call_us = 0.0;   ///< the most a tick's calls may take, us (> 0)
    std::string settings_toml;  ///< [plugin.settings] as TOML text, handed to create()
};

/// The calls into one world, guarded: the library, the descriptor and the world's pointer,
/// destroyed by the plugin's own destroy() before the library is closed.
class PluginWorld {
  public:
    PluginWorld(std::shared_ptr<void> library, const hapticd_environment_plugin* plugin,
                void* world, double max_call_us);
    ~PluginWorld();
    PluginWorld(const PluginWorld&) = delete;
    PluginWorld& operator=(const PluginWorld&) = delete;

    const hapticd_environment_plugin& plugin() const noexcept { return *plugin_; }
    void* world() const noexcept { return world_; }

    /// Runs `call` (returning the plugin's int32_t) timed, with its exceptions caught; false
    /// (and failed()) on an error code, an exception, or once failed.
    template <typename Call>
    bool guarded(const char* what, Call&& call) const noexcept;
    /// Checks that `values` are finite; false (and failed()) when one is not.
    bool finite(const char* what, const double* values, int count) const noexcept;
    /// The end of a tick's calls: judges their time against max_call_us.
    void end_tick() const noexcept;
    /// Clears the failure (a reset of the world follows).
    void clear() noexcept;

    bool failed() const noexcept { return failed_; }
    /// Why, "" when not failed: "evaluate() returned 3", "step() threw: bad_alloc"...
    std::string_view failure() const noexcept { return failure_.data(); }

  private:
    void fail(const char* what, std::string_view why, std::string_view detail = {}) const noexcept;
    void fail_number(const char* what, std::string_view why, double value,
                     std::string_view unit) const noexcept;

    std::shared_ptr<void> library_;
    const hapticd_environment_plugin* plugin_;
    void* world_;
    std::int64_t max_call_ns_;
    mutable std::int64_t tick_ns_ = 0;
    mutable int slow_ticks_ = 0;
    mutable bool failed_ = false;
    mutable std::array<char, 256> failure_{};
};

/// An impedance plugin's world as an ImpedanceEnvironment.
class PluginImpedanceEnvironment final : public ImpedanceEnvironment {
  public:
    explicit PluginImpedanceEnvironment(std::unique_ptr<PluginWorld> world)
        : world_(std::move(world)) {}
    PenaltyForce evaluate(const Vec3& tool_position_m,
                          const Vec3& tool_velocity_mps) const noexcept override;
    void commit(const Vec3& tool_position_m, const Vec3& tool_velocity_mps) noexcept override;
    void reset(const Vec3& tool_position_m) noexcept override;
    bool failed() const noexcept override { return world_->failed(); }
    std::string_view failure() const noexcept override { return world_->failure(); }

  private:
    std::unique_ptr<PluginWorld> world_;
};

/// An admittance plugin's world as an AdmittanceEnvironment.
class PluginAdmittanceEnvironment final : public AdmittanceEnvironment {
  public:
    explicit PluginAdmittanceEnvironment(std::unique_ptr<PluginWorld> world)
        : world_(std::move(world)) {}
    Vec3 step(const Vec3& device_position_m, const Vec3& device_velocity_mps,
              const CouplingGains& gains, double period_s) noexcept override;
    void reset(const Vec3& position_m) noexcept override;
    bool failed() const noexcept override { return world_->failed(); }
    std::string_view failure() const noexcept override { return world_->failure(); }

  private:
    std::unique_ptr<PluginWorld> world_;
    Vec3 last_tool_position_m_{0.0};
};

template <typename Call>
bool PluginWorld::guarded(const char* what, Call&& call) const noexcept {
    if (failed_) return false;
    const std::int64_t start_ns = servo::monotonic_now_ns();
    std::int32_t status = 0;
    try {
        status = call();
    } catch (const std::exception& e) {
        fail(what, "threw: ", e.what());
        return false;
    } catch (...) {
        fail(what, "threw an exception that is no std::exception");
        return false;
    }
    tick_ns_ += servo::monotonic_now_ns() - start_ns;
    if (status != 0) {
        fail_number(what, "returned ", static_cast<double>(status), "");
        return false;
    }
    return true;
}

/// A plugin loaded for a scene: one of the two set, per `admittance`.
struct LoadedPlugin {
    std::string name;         ///< the descriptor's
    std::string description;  ///< the descriptor's
    std::string path;         ///< the shared object
    bool admittance = false;
    std::unique_ptr<ImpedanceEnvironment> impedance;
    std::unique_ptr<AdmittanceEnvironment> admittance_environment;
};

/// Loads `spec.name` (install/plugin_files.hpp, kind "env"), checks its ABI version and its
/// descriptor, and creates a world for a scene of `axes` at `rate_hz` read from `scene_file`.
/// Throws std::runtime_error naming the scene file, the plugin and why: not found (every file
/// tried), dlopen's text, no entry, another ABI version (both numbers), a null function for its
/// causality, create() refusing (the plugin's message) or throwing.
LoadedPlugin load_environment_plugin(const PluginSpec& spec, int axes, double rate_hz,
                                     const std::string& scene_file);

}  // namespace hapticd::env
