#include "hapticd/tune/result_json.hpp"

#include <cmath>

namespace hapticd {
namespace {

template <typename Check>
nlohmann::ordered_json exact_check_json(const Check& check) {
    return {{"stable", check.stable},
            {"worst_margin", check.worst_margin},
            {"worst_spectral_radius", check.worst_spectral_radius},
            {"worst_frequency_hz", check.worst_frequency_hz},
            {"worst_operator", check.worst_operator.describe()},
            {"worst_environment", check.worst_environment.describe()},
            {"cases_checked", check.cases_checked}};
}

/// JSON null for a number that is not finite: an infinite m_c or b_c (no mass, no series
/// damper), a residual the log cannot give. nlohmann would write null for NaN anyway; this
/// makes it explicit.
nlohmann::ordered_json number(double value) {
    return std::isfinite(value) ? nlohmann::ordered_json(value) : nlohmann::ordered_json(nullptr);
}

}  // namespace

namespace theory {

void to_json(nlohmann::ordered_json& json, const DeviceModel& device) {
    json = {{"mass", device.mass_kg}, {"damping", device.damping_n_s_per_m}};
}

void to_json(nlohmann::ordered_json& json, const ForceSensorFilter& filter) {
    json = {{"cutoff_hz", filter.cutoff_hz},
            {"damping_ratio", filter.damping_ratio},
            {"order", filter.order},
            {"description", filter.describe()}};
}

void to_json(nlohmann::ordered_json& json, const CouplingCheck& check) {
    json = {{"unconditionally_stable", check.unconditionally_stable},
            {"worst_margin", check.worst_margin},
            {"worst_frequency_hz", check.worst_frequency_hz}};
}

}  // namespace theory

namespace tune {

void to_json(nlohmann::ordered_json& json, const ExactCheck& check) {
    json = exact_check_json(check);
    json["marginal"] = check.marginal();
    json["marginal_tolerance"] = kMarginalTolerance;
}

void to_json(nlohmann::ordered_json& json, const AdmittanceExactCheck& check) {
    json = exact_check_json(check);
}

void to_json(nlohmann::ordered_json& json, const IdentifiedAxis& a) {
    json = {
        {"axis", a.axis},
        {"mass", a.estimate.mass_kg},
        {"mass_std_error", a.std_error.mass_kg},
        {"damping", a.estimate.damping_n_s_per_m},
        {"damping_std_error", a.std_error.damping_n_s_per_m},
        {"coulomb", a.estimate.coulomb_n},
        {"coulomb_std_error", a.std_error.coulomb_n},
        {"offset", a.estimate.offset_n},
        {"offset_std_error", a.std_error.offset_n},
        {"residual_rms_m", a.residual_rms_m},
        {"residual_rms_counts", number(a.residual_rms_counts)},
        {"stuck_fraction", a.stuck_fraction},
        {"resolution_m", a.resolution_m},
        {"resolution_source", a.resolution_estimated ? "log" : "option"},
        {"delay_s", a.delay_s},
        {"rate_hz", a.rate_hz},
        {"duration_s", a.duration_s},
        {"samples", a.samples},
        {"masked_samples", a.masked_samples},
        {"gaps", a.gaps},
        {"segments", a.segments},
        {"iterations", a.report.iterations},
        {"converged", a.report.converged},
        {"solve_time_s", a.report.solve_time_s},
    };
}

void to_json(nlohmann::ordered_json& json, const SizingReport& report) {
    json = {{"method", report.method},
            {"ceres_iterations", report.ceres_iterations},
            {"verify_points", report.verify_points},
            {"solver_time_s", report.solver_time_s}};
}

void to_json(nlohmann::ordered_json& json, const ImpedanceSizing& sizing) {
    json = {{"stiffness", sizing.coupling.stiffness_n_per_m},
            {"damping", sizing.coupling.damping_n_s_per_m},
            {"velocity_filter_hz", sizing.coupling.velocity_filter_hz},
            {"binding_frequency_hz", sizing.binding_frequency_hz},
            {"solver_time_s", sizing.report.solver_time_s},
            {"verified_worst_margin", sizing.verified_worst_margin},
            {"solver", sizing.report}};
}

void to_json(nlohmann::ordered_json& json, const AdmittanceSizing& sizing) {
    json = {{"coupling_mass", sizing.coupling.mass_kg},
            {"damping", number(sizing.coupling.damping_n_s_per_m)},
            {"binding_frequency_hz", sizing.binding_frequency_hz},
            {"solver_time_s", sizing.report.solver_time_s},
            {"verified_worst_margin", sizing.verified_worst_margin},
            {"solver", sizing.report}};
}

void to_json(nlohmann::ordered_json& json, const PassiveAdmittanceSizing& sizing) {
    json = {{"coupling_mass", number(sizing.coupling.mass_kg)},
            {"damping", number(sizing.coupling.damping_n_s_per_m)},
            {"binding_frequency_hz", sizing.binding_frequency_hz},
            {"binding_environment", sizing.binding_environment},
            {"worst_margin", sizing.worst_margin},
            {"finite_mass_fails_at_dc", sizing.finite_mass_fails_at_dc},
            {"solver_time_s", sizing.report.solver_time_s},
            {"solver", sizing.report},
            {"exact_check", sizing.exact}};
}

void to_json(nlohmann::ordered_json& json, const ExactAdmittanceSizing& sizing) {
    json = {{"coupling_mass", sizing.coupling.mass_kg},
            {"damping", number(sizing.coupling.damping_n_s_per_m)},
            {"binding_frequency_hz", sizing.binding_frequency_hz},
            {"limit_coupling_mass", sizing.limit_mass_kg},
            {"binding_operator", sizing.binding_operator.describe()},
            {"binding_environment", sizing.binding_environment.describe()},
            {"solver_time_s", sizing.report.solver_time_s},
            {"solver", sizing.report},
            {"exact_check", sizing.check}};
}

void to_json(nlohmann::ordered_json& json, const StabilityVerdict& verdict) {
    json = {{"unconditionally_stable", verdict.passed},
            {"worst_margin", verdict.worst_margin},
            {"worst_frequency_hz", verdict.worst_frequency_hz},
            {"model", std::string(to_string(verdict.model))},
            {"proven", verdict.proven}};
    if (verdict.proven) json["proof"] = verdict.proof;
    if (verdict.exact) {
        json["worst_operator"] = verdict.exact->worst_operator.describe();
        json["worst_environment"] = verdict.exact->worst_environment.describe();
        json["worst_spectral_radius"] = verdict.exact->worst_spectral_radius;
        json["cases_checked"] = verdict.exact->cases_checked;
        json["search"] = *verdict.exact;
    }
    if (verdict.scene) {
        json["worst_environment"] = verdict.scene->worst_environment;
        json["damping_needed"] = verdict.scene->damping_needed;
    }
    json["holds_for"] = verdict.holds_for;
    json["delay_s"] = verdict.delay_s;
    json["velocity_filter_hz"] = verdict.velocity_filter_hz;
    json["verdict"] = verdict.describe();
}

}  // namespace tune
}  // namespace hapticd
