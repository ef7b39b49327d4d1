#include "hapticd/tune/stability_check.hpp"

#include <numbers>
#include <sstream>
#include <stdexcept>

#include "hapticd/theory/coupling_check.hpp"
#include "hapticd/tune/class_proof.hpp"
#include "hapticd/tune/input_checks.hpp"

namespace hapticd::tune {

std::string_view to_string(StabilityModel model) noexcept {
    switch (model) {
        case StabilityModel::passive:
            return "passive";
        case StabilityModel::exact:
            return "exact";
        case StabilityModel::paper:
            return "paper";
        case StabilityModel::encoder:
            return "encoder";
    }
    return "passive";
}

std::optional<StabilityModel> parse_stability_model(std::string_view name) noexcept {
    for (const StabilityModel model : kStabilityModels) {
        if (to_string(model) == name) return model;
    }
    return std::nullopt;
}

bool is_guarantee(StabilityModel model) noexcept {
    return model == StabilityModel::passive || model == StabilityModel::exact;
}

std::string StabilityVerdict::describe() const {
    std::ostringstream out;
    out << "stability check (" << to_string(model) << " model, loop delay " << delay_s * 1e3
        << " ms";
    if (velocity_filter_hz > 0.0) out << ", velocity filter " << velocity_filter_hz << " Hz";
    out << "): " << (passed ? "unconditionally stable" : "NOT unconditionally stable")
        << ", worst margin " << worst_margin << " at " << worst_frequency_hz << " Hz";
    if (!worst_case.empty()) out << " (" << worst_case << ")";
    if (guarantee) {
        out << "; holds for " << holds_for;
        if (model == StabilityModel::exact) {
            if (proven) out << ", proven by " << proof;
            if (exact && exact->marginal()) {
                out << "; the search's worst case is marginal: |z| - 1 = "
                    << exact->worst_spectral_radius - 1.0 << ", within the eigenvalues' "
                    << kMarginalTolerance << " tolerance";
            }
        }
    } else {
        out << ". The " << to_string(model)
            << " model is NOT a guarantee: it keeps one term of the hold's alias sum and "
               "misses operators with several modes (docs/stability-models.md); use check = "
               "\"passive\" (the default) or \"exact\" to arm hardware";
    }
    return out.str();
}

namespace {

theory::HoldModel hold_of(StabilityModel model) {
    switch (model) {
        case StabilityModel::paper:
            return theory::HoldModel::paper;
        case StabilityModel::encoder:
            return theory::HoldModel::encoder;
        case StabilityModel::passive:
        case StabilityModel::exact:
            break;
    }
    return theory::HoldModel::passive;
}

std::string precise(double value) {
    std::ostringstream out;
    out.precision(10);
    out << value;
    return out.str();
}

/// The passive model's verdict on the design, against every passive environment or the
/// scene's: the proof the exact model's verdict rests on when it claims every passive
/// operator (a class is a subset of them, so it holds for a class too).
void passive_proof(const StabilityDesign& design, double delay_periods, StabilityVerdict& into) {
    const StabilityAssumption& assumption = design.assumption;
    if (!assumption.environments.every_passive()) {
        into.scene = check_passive_scene(design.device, design.coupling, design.rate_hz,
                                         assumption.environments.scene, delay_periods);
        into.passed = into.scene->stable;
        into.worst_margin = into.scene->margin;
        into.worst_frequency_hz = into.scene->worst_frequency_hz;
        into.worst_case = into.scene->worst_environment;
        return;
    }
    const theory::CouplingCheck check =
        theory::check_coupling(design.device, design.coupling,
                               {theory::HoldModel::passive, delay_periods}, design.rate_hz);
    into.passed = check.unconditionally_stable;
    into.worst_margin = check.worst_margin;
    into.worst_frequency_hz = check.worst_frequency_hz;
}

/// The class's port condition against every passive environment (tune/class_proof.hpp), which
/// holds against a scene's environments too.
void class_proof(const StabilityDesign& design, double delay_periods, StabilityVerdict& into) {
    const ClassProof proof =
        ClassProver(design.device, *design.assumption.operators, design.rate_hz, delay_periods)
            .prove(design.coupling);
    into.worst_margin = proof.worst_margin;
    into.worst_frequency_hz = proof.worst_frequency_hz;
    into.worst_case.clear();
    if (proof.holds) {
        into.passed = true;
        into.proven = true;
        into.proof = kClassPortCondition;
    }
}

/// The exact model: a proof (the passive port condition, for every passive operator; for a
/// declared class also the class's port condition, docs/stability-models.md) and the exact
/// model's search for an operator that breaks the design. A search that finds one overrules
/// a proof (a contradiction is a defect, and the safe verdict is no); a class no proof covers
/// fails, whatever its search finds.
void exact_verdict(const StabilityDesign& design, double delay_periods, StabilityVerdict& into) {
    passive_proof(design, delay_periods, into);
    into.proven = into.passed;
    if (into.proven) into.proof = kPassivePortCondition;
    if (!into.proven && design.assumption.operators) class_proof(design, delay_periods, into);
    into.exact = check_exact(design.device, design.coupling, design.rate_hz, design.assumption,
                             delay_periods);
    const ExactCheck& search = *into.exact;
    if (!into.proven) {
        into.passed = false;
        if (!search.stable) {
            into.worst_case = search.worst_operator.describe() + " against " +
                              search.worst_environment.describe() +
                              " grows by |z| = " + precise(search.worst_spectral_radius) +
                              " per tick";
        } else {
            const std::string against = into.worst_case.empty() ? "" : ", " + into.worst_case;
            into.worst_case = "no proof covers it: the port condition's bound is below 0 at " +
                              precise(into.worst_frequency_hz) + " Hz" + against +
                              "; the exact model's search finds no unstable operator, which is "
                              "no proof (docs/stability-models.md)";
        }
        return;
    }
    // Near z = 1 (a free hand on an almost free virtual mass, a heavy device at a high rate)
    // the eigenvalues of an almost defective pair are only good to about sqrt(ε): a search's
    // growth that small cannot overrule a proof, and is reported as within that error.
    const bool near_one =
        search.worst_frequency_hz < kNearOneRadians * design.rate_hz / (2.0 * std::numbers::pi);
    if (into.proven && !search.stable && near_one &&
        search.worst_margin >= -kWitnessGrowthPerTick) {
        into.worst_case = "the exact model's search: " + search.worst_operator.describe() +
                          " against " + search.worst_environment.describe() +
                          " at |z| - 1 = " + precise(-search.worst_margin) +
                          ", within the eigenvalues' error near z = 1; the proof stands";
    } else if (into.proven && !search.stable) {
        into.passed = false;
        into.worst_case =
            "the exact model's search contradicts the proof: " + search.worst_operator.describe() +
            " against " + search.worst_environment.describe() +
            " grows by |z| = " + precise(search.worst_spectral_radius) + " per tick";
    }
}

}  // namespace

StabilityVerdict check_stability(const StabilityDesign& design) {
    const theory::SpringDamperCoupling& coupling = design.coupling;
    check_coupling_gains(coupling);
    if (coupling.renders_nothing()) {
        throw std::invalid_argument(
            "coupling stiffness and damping are both 0: no coupling to check");
    }
    const StabilityAssumption& assumption = design.assumption;
    if (assumption.operators && design.model != StabilityModel::exact) {
        throw std::invalid_argument("an operator class needs the exact model, not " +
                                    std::string(to_string(design.model)));
    }
    if (!assumption.environments.every_passive() && !is_guarantee(design.model)) {
        throw std::invalid_argument(
            "a scene's environments need the passive or the exact model, not " +
            std::string(to_string(design.model)));
    }
    StabilityVerdict verdict;
    verdict.model = design.model;
    verdict.guarantee = is_guarantee(design.model);
    verdict.delay_s = design.delay_s;
    verdict.velocity_filter_hz = coupling.velocity_filter_hz;
    verdict.holds_for = assumption.describe();
    const double delay_periods = design.delay_s * design.rate_hz;
    if (design.model == StabilityModel::exact) {
        exact_verdict(design, delay_periods, verdict);
        return verdict;
    }
    if (design.model == StabilityModel::passive) {
        passive_proof(design, delay_periods, verdict);
        verdict.proven = verdict.passed;
        if (verdict.proven) verdict.proof = kPassivePortCondition;
        return verdict;
    }
    const theory::CouplingCheck check = theory::check_coupling(
        design.device, coupling, {hold_of(design.model), delay_periods}, design.rate_hz);
    verdict.passed = check.unconditionally_stable;
    verdict.worst_margin = check.worst_margin;
    verdict.worst_frequency_hz = check.worst_frequency_hz;
    return verdict;
}

}  // namespace hapticd::tune
