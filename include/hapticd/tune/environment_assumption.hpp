// What a stability verdict assumes about the virtual environment (docs/stability-models.md,
// "Scenes"): every passive environment (the default), or the environments a scene holds.
//
// The daemon's own environments are implicit Euler and so dissipative: a penalty object is
// a massless spring-damper solved with the coupling at the end of the step (17), a virtual
// mass is the implicit-Euler mass-spring of exact_model.hpp, a god-object in contact is a
// rigid wall. On the backward-difference velocity each has the impedance
//     Z_e(z) = m_e (1 - z⁻¹)/T + b_e + k_e T/(1 - z⁻¹),
// whose real part b_e + m_e (1 - cos θ)/T + k_e T/2 is positive at every frequency, so none
// of them is the lossless environment that the `passive` model must allow for. A scene
// made only of them is checked against its linearised objects: each alone, and all of
// them at once (every contact together). Z = 1/(1/Z_c + 1/Z_e) is then what the device
// port sees, and the passive model's port condition b >= λ(ζ) (passive_model.hpp) is
// evaluated with it directly instead of being worst-cased over every Y_e.
#pragma once

#include <string>
#include <vector>

#include "hapticd/theory/benchmark.hpp"
#include "hapticd/tune/exact_model.hpp"

namespace hapticd::tune {

/// One environment of a scene, with where it came from.
struct SceneEnvironment {
    EnvironmentModel model;
    std::string source;  ///< e.g. "[[wall]] #1", "all 3 penalty objects at once"
};

struct EnvironmentAssumption {
    /// Empty: every passive environment. Otherwise exactly these.
    std::vector<SceneEnvironment> scene;
    std::string scene_name;  ///< the scene's file or name, for messages

    bool every_passive() const { return scene.empty(); }
    /// "every passive environment", or "the scene demo-wall.toml's 2 environments:
    /// [[wall]] #1 (mass-spring (m_e = 0 kg, k_e = 3000 N/m, b_e = 0 N s/m)), ..."
    std::string describe() const;
};

/// The environment's impedance on the backward-difference velocity at z = e^{jθ} (the
/// coupling force per unit tool velocity). A rigid wall is +inf (returned as a flag).
struct EnvironmentImpedance {
    bool rigid = false;
    theory::Complex impedance{0.0, 0.0};
};
EnvironmentImpedance environment_impedance(const EnvironmentModel& environment, double theta,
                                           double sample_period_s);

/// What the device port sees through the coupling in series with the environment:
/// 1/(1/Z_c + 1/Z_e), and Z_c for a rigid wall.
theory::Complex port_impedance(const theory::SpringDamperCoupling& coupling,
                               const EnvironmentModel& environment, double theta,
                               double sample_period_s);

/// The passive model (every passive operator) against a scene's environments.
struct SceneCheck {
    bool stable = false;          ///< device damping >= damping_needed
    double damping_needed = 0.0;  ///< max over θ and environments of λ(ζ), N s/m
    double margin = 0.0;          ///< (b - damping_needed)/b
    double worst_frequency_hz = 0.0;
    std::string worst_environment;  ///< its source and model
    double delay_periods = 0.0;
};

/// b >= λ(ζ(θ)) for every θ in (0, π] and every environment of the scene (on
/// theory::frequency_grid(points), the worst point refined by golden section). Throws
/// std::invalid_argument for non-physical input or an empty scene.
SceneCheck check_passive_scene(const theory::DeviceModel& device,
                               const theory::SpringDamperCoupling& coupling, double rate_hz,
                               const std::vector<SceneEnvironment>& scene, double delay_periods,
                               int points = 2048);

}  // namespace hapticd::tune
