// Scenes: a TOML file lists the objects of one virtual environment; the loader validates it
// and builds only what it needs (docs/architecture.md §2.5, §4.2): penalty objects make a
// PenaltyScene (an ImpedanceEnvironment), constraint objects a GodObject or a VirtualMass
// (an AdmittanceEnvironment). One scene has one causality.
//
// Schema (docs/scenes.md has the full reference with examples). Units SI; a "vector" is an
// array of exactly `axes` numbers (components beyond the scene's axes are zero); integers
// are accepted wherever a number is; every key not listed is an error.
//
//   [scene]                    required
//   name = "demo-wall"         required, non-empty string
//   axes = 1                   required, 1..3
//
//   Penalty (impedance) objects, any number of each:
//   [[wall]]      normal (vector, into free space, non-zero; normalised), offset (m, the
//                 plane normal·x = offset; default 0), stiffness (N/m, > 0),
//                 damping (N s/m, >= 0, default 0)
//   [[spring]]    anchor (vector, default 0), stiffness (N/m, > 0)
//   [[damper]]    damping (N s/m, > 0)
//   [[detent]]    axis (vector, non-zero; normalised), center (vector, default 0),
//                 period (m, > 0), peak_force (N, > 0), periodic (bool, default true)
//   [[friction]]  normal_force (N, > 0), static_coefficient (> 0),
//                 kinetic_coefficient (> 0, <= static_coefficient), stiffness (N/m, > 0)
//
//   Constraint (admittance) objects: either a god-object ...
//   [[proxy_plane]]   normal (vector, into free space), offset (m, default 0)
//   [[proxy_sphere]]  center (vector, default 0), radius (m, > 0),
//                     side ("outside": a solid ball, default | "inside": a cavity)
//   ... or one virtual mass:
//   [virtual_mass]    mass (kg, > 0), stiffness (N/m, >= 0, default 0),
//                     damping (N s/m, >= 0, default 0), anchor (vector, default 0; must be
//                     in free space)
//   [[virtual_mass.plane]]   as [[proxy_plane]]
//   [[virtual_mass.sphere]]  as [[proxy_sphere]]
//
//   Or a world of the lab's own, alone in its scene (plugin_environment.hpp):
//   [plugin]          name (a plugin name or a path with '/'), max_call_us (us, > 0 and <=
//                     the period; default a quarter of it)
//   [plugin.settings] anything: handed to the plugin's create() as TOML text
//
//   Or a world another process renders at its own rate, alone in its scene
//   (external_environment.hpp; an admittance):
//   [external]        between_updates ("extrapolate" default | "hold"), stale_after (s, > 0
//                     and > lockstep_every / rate_hz, <= 10; default 0.1), ramp (s, 0..10;
//                     default 0.2), lockstep_every (ticks, 0..100000; default 0: free-running),
//                     lockstep_timeout (s, > 0, <= 600; default 10), passivity ("control"
//                     default | "observe" | "off")
//
// Upper bounds catch typos: stiffness <= 1e7 N/m, damping <= 1e5 N s/m, forces <= 1e4 N,
// lengths and coordinates within ±100 m, mass <= 1e3 kg, coefficients <= 10.
// A scene with no objects is a free-space PenaltyScene.
//
// Errors are SceneError, from the one field reader (input/table_reader.hpp), with the file,
// the line, the table and its 1-based index, the key, the value and the allowed range, e.g.
//   config/scenes/x.toml:7: [[wall]] #2 stiffness = -5 is out of range: allowed > 0 and
//   <= 1e+07 (N/m)
#pragma once

#include <atomic>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hapticd/env/environment.hpp"
#include "hapticd/input/config_error.hpp"

namespace hapticd::env {

enum class Causality { impedance, admittance };

[[nodiscard]] const char* to_string(Causality causality) noexcept;

/// A bad scene file or text; what() names the file, key, value and allowed range. A scene
/// error is a config error (the one ConfigError of every file hapticd reads).
using SceneError = input::ConfigError;

/// One object of a scene, linearised in contact, for the stability check's scene model
/// (tune/environment_assumption.hpp): a penalty object is a massless spring-damper solved
/// with the coupling (implicit), a virtual mass the implicit-Euler mass-spring, a
/// constraint in contact a rigid wall.
struct LinearObject {
    std::string source;  ///< e.g. "[[wall]] #2", "all 3 objects at once"
    double mass_kg = 0.0;
    double stiffness_n_per_m = 0.0;
    double damping_n_s_per_m = 0.0;
    bool rigid = false;
};

/// A built scene. Exactly one of `impedance` and `admittance` is set, per `causality`.
struct Scene {
    std::string name;
    int axes = 0;
    Causality causality = Causality::impedance;
    std::unique_ptr<ImpedanceEnvironment> impedance;
    std::unique_ptr<AdmittanceEnvironment> admittance;
    /// Each object linearised, and for several penalty objects all of them at once (their
    /// stiffnesses and dampings add). Free space needs no entry: the tool follows the
    /// device and the coupling carries no force.
    std::vector<LinearObject> linear_objects;
    /// Empty, or why the scene has no linear model (its first detent or friction).
    std::string unmodelled;
    /// The object whose stiffness falls lowest, a detent between its notches (stiffness
    /// -2π peak_force/period); none when no object's stiffness is negative. The coupling
    /// stiffness must exceed its magnitude, or the series solve (17) of a massless tool has
    /// no stable balance there (docs/scenes.md).
    std::optional<LinearObject> most_negative_stiffness;
    /// A [plugin] scene's world: "NAME (PATH)"; empty for hapticd's own objects.
    std::string plugin;
    /// An [external] scene's channel (external_channel.hpp): its path ("" for a private one);
    /// none for other scenes. And why it could not be given to its group, if it could not.
    std::optional<std::string> external;
    std::string external_note;
};

/// How a scene is read: the servo's rate, which a [plugin] world is created for.
struct SceneOptions {
    double rate_hz = 1000.0;
    /// False: a [plugin] scene is refused, saying `why_no_plugins` (a reader that only
    /// checks, and would not load code).
    bool load_plugins = true;
    std::string why_no_plugins{};
    /// Where an [external] scene's channel goes (channel_beside() the control socket); "": a
    /// private mapping no other process can reach (a reader that only checks the scene).
    std::string external_channel{};
    /// The group the channel is given to, as the control socket is.
    std::string external_group = "hapticd";
    /// A lockstep wait of an [external] world ends when this is set (the daemon's stop flag).
    const std::atomic<bool>* stop = nullptr;
};

/// Reads and builds the scene in `path`. `axes` is the device's axis count: the scene's
/// [scene] axes may not exceed it (a 1-axis scene runs on the first axis of a 3-axis
/// device). Throws SceneError.
[[nodiscard]] Scene load_scene(const std::string& path, int axes, const SceneOptions& options = {});

/// The same from text; `source_name` stands for the file in messages.
[[nodiscard]] Scene parse_scene(std::string_view text, const std::string& source_name, int axes,
                                const SceneOptions& options = {});

}  // namespace hapticd::env
