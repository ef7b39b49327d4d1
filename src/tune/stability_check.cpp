#include "hapticd/tune/stability_check.hpp"

#include <sstream>
#include <stdexcept>

#include "hapticd/theory/coupling_check.hpp"
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
        if (model == StabilityModel::exact) out << ", as far as the exact model's search reaches";
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

}  // namespace

StabilityVerdict check_stability(const StabilityDesign& design) {
    const theory::SpringDamperCoupling& coupling = design.coupling;
    check_coupling_gains(coupling);
    if (coupling.stiffness_n_per_m == 0.0 && coupling.damping_n_s_per_m == 0.0) {
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
        verdict.exact =
            check_exact(design.device, coupling, design.rate_hz, assumption, delay_periods);
        verdict.passed = verdict.exact->stable;
        verdict.worst_margin = verdict.exact->worst_margin;
        verdict.worst_frequency_hz = verdict.exact->worst_frequency_hz;
        verdict.worst_case = verdict.exact->worst_operator.describe() + " against " +
                             verdict.exact->worst_environment.describe();
        return verdict;
    }
    if (!assumption.environments.every_passive()) {
        verdict.scene = check_passive_scene(design.device, coupling, design.rate_hz,
                                            assumption.environments.scene, delay_periods);
        verdict.passed = verdict.scene->stable;
        verdict.worst_margin = verdict.scene->margin;
        verdict.worst_frequency_hz = verdict.scene->worst_frequency_hz;
        verdict.worst_case = verdict.scene->worst_environment;
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
