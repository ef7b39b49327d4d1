#include "hapticd/tune/result_json.hpp"

#include <cmath>

namespace hapticd::tune {
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

/// JSON null for a number that is not finite (nlohmann writes null for NaN anyway; this
/// makes it explicit).
nlohmann::ordered_json number(double value) {
    return std::isfinite(value) ? nlohmann::ordered_json(value) : nlohmann::ordered_json(nullptr);
}

}  // namespace

void to_json(nlohmann::ordered_json& json, const ExactCheck& check) {
    json = exact_check_json(check);
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

}  // namespace hapticd::tune
