// The JSON of the tune layer's results, for every command that prints one (haptic-tune size,
// autotune): nlohmann's to_json, found by argument-dependent lookup, so that
// `out["exact_check"] = check;` serialises a check one way everywhere.
#pragma once

#include <nlohmann/json.hpp>

#include "hapticd/tune/exact_admittance.hpp"
#include "hapticd/tune/exact_model.hpp"
#include "hapticd/tune/identification.hpp"

namespace hapticd::tune {

/// {stable, worst_margin, worst_spectral_radius, worst_frequency_hz, worst_operator,
/// worst_environment, cases_checked}: the worst case the exact impedance loop found.
void to_json(nlohmann::ordered_json& json, const ExactCheck& check);
/// The same fields for the exact admittance loop.
void to_json(nlohmann::ordered_json& json, const AdmittanceExactCheck& check);
/// One identified axis (haptic-tune identify, and each of autotune's axes): the estimates
/// with their standard errors, the residual, the log's rate (`rate_hz`) and the solve
/// (docs/identification.md, "Output").
void to_json(nlohmann::ordered_json& json, const IdentifiedAxis& axis);

}  // namespace hapticd::tune
