// One verdict on a coupling design under a named stability model (docs/stability-models.md).
// The daemon's start-up check (daemon/startup_check.hpp) and `haptic-tune check` both call
// check_stability(), so a config gets the same verdict, and the same line describing it,
// from each.
//
//   exact:            the passive port condition (against every passive environment or the
//                     scene's), or for a class the class's port condition
//                     (tune/class_proof.hpp); and check_exact() under the assumption, whose
//                     witness overrules a proof. A class the proofs do not cover fails.
//   passive, a scene: check_passive_scene() against the scene's linearised objects;
//   otherwise:        theory::check_coupling() with the model's hold (paper, encoder,
//                     passive against every passive environment).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "hapticd/theory/benchmark.hpp"
#include "hapticd/tune/class_check.hpp"
#include "hapticd/tune/environment_assumption.hpp"
#include "hapticd/tune/exact_model.hpp"

namespace hapticd::tune {

/// The models a design is checked with. passive and exact hold for a stated class of
/// operators and environments; paper and encoder keep one term of the hold's alias sum and
/// are no guarantee.
enum class StabilityModel { passive, exact, paper, encoder };
inline constexpr StabilityModel kStabilityModels[] = {
    StabilityModel::passive, StabilityModel::exact, StabilityModel::paper, StabilityModel::encoder};
/// "passive", "exact", "paper", "encoder": the names of --model and [coupling] check.
std::string_view to_string(StabilityModel model) noexcept;
std::optional<StabilityModel> parse_stability_model(std::string_view name) noexcept;
bool is_guarantee(StabilityModel model) noexcept;

/// Near z = 1 (|arg z| below kNearOneRadians) the eigenvalues of an almost defective pair (a
/// free hand on an almost free virtual mass) are good to about sqrt(machine ε), 1.5e-8, and a
/// search's growth there must pass kWitnessGrowthPerTick (|z| - 1) to overrule a proof.
/// Elsewhere any growth past kMarginalTolerance does (witnesses at 1.03 x the passive bound
/// grow by 3e-7 to 3e-4 per tick).
inline constexpr double kNearOneRadians = 0.01;
inline constexpr double kWitnessGrowthPerTick = 1e-6;

/// The proofs a verdict rests on (StabilityVerdict::proof, `haptic-tune size`'s "proof"):
/// Colgate and Schenkel's passive port condition, and the same condition bounded over a
/// declared class (tune/class_proof.hpp).
inline constexpr std::string_view kPassivePortCondition = "the passive port condition";
inline constexpr std::string_view kClassPortCondition = "the class's port condition";

/// What is checked.
struct StabilityDesign {
    theory::DeviceModel device;
    theory::SpringDamperCoupling coupling;  ///< k_c, b_c and the damper's velocity filter
    double rate_hz = 0.0;
    double delay_s = 0.0;  ///< sample to force, beyond the hold
    StabilityModel model = StabilityModel::passive;
    /// exact: a class and a scene; passive: a scene; paper and encoder: neither.
    StabilityAssumption assumption;
};

struct StabilityVerdict {
    StabilityModel model = StabilityModel::passive;
    bool passed = false;
    /// The verdict is a proof over the class it names (the passive port condition, for the
    /// exact model too when the condition holds); false for a search's verdict and for the
    /// paper and encoder models.
    bool proven = false;
    /// What proves it: kPassivePortCondition or kClassPortCondition; empty when not proven.
    std::string proof;
    bool guarantee = true;  ///< passive and exact; paper and encoder are not
    double delay_s = 0.0;
    double velocity_filter_hz = 0.0;
    double worst_margin = 0.0;
    double worst_frequency_hz = 0.0;
    /// exact: "OPERATOR against ENVIRONMENT"; passive with a scene: its worst environment.
    std::string worst_case;
    /// The class of operators and environments the verdict rests on.
    std::string holds_for;
    std::optional<ExactCheck> exact;  ///< the exact model's details
    std::optional<SceneCheck> scene;  ///< the passive model against a scene
    /// One line for a log: "stability check (passive model, loop delay 0 ms): unconditionally
    /// stable, worst margin 0.111 at 0 Hz; holds for every passive operator and every
    /// passive environment". The paper and encoder models' line says they are no guarantee.
    std::string describe() const;
};

/// Throws std::invalid_argument naming the value for non-physical input (the models' own
/// ranges), for a coupling of zero stiffness and damping, and for an assumption the model
/// cannot take (a class without the exact model, a scene with paper or encoder).
StabilityVerdict check_stability(const StabilityDesign& design);

}  // namespace hapticd::tune
