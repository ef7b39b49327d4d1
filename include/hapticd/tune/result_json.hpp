// The JSON of the tune layer's results, for every command that prints one (haptic-tune size,
// check, plot, autotune; hapticd's summary): nlohmann's to_json, found by argument-dependent
// lookup, so that `out["exact_check"] = check;` serialises a result one way everywhere. A
// command adds what it knows beyond the result (the device, the rate, the delay: the input
// it sized for).
#pragma once

#include <nlohmann/json.hpp>

#include "hapticd/theory/benchmark.hpp"
#include "hapticd/theory/coupling_check.hpp"
#include "hapticd/theory/force_sensor_filter.hpp"
#include "hapticd/tune/admittance_sizing.hpp"
#include "hapticd/tune/coupling_sizing.hpp"
#include "hapticd/tune/exact_admittance.hpp"
#include "hapticd/tune/exact_model.hpp"
#include "hapticd/tune/identification.hpp"
#include "hapticd/tune/stability_check.hpp"

namespace hapticd::theory {

/// {mass, damping}: the device model m, b of (21).
void to_json(nlohmann::ordered_json& json, const DeviceModel& device);
/// {cutoff_hz, damping_ratio, order, description}.
void to_json(nlohmann::ordered_json& json, const ForceSensorFilter& filter);
/// {unconditionally_stable, worst_margin, worst_frequency_hz}: (21) checked under one hold
/// model (haptic-tune plot's curves).
void to_json(nlohmann::ordered_json& json, const CouplingCheck& check);

}  // namespace hapticd::theory

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

/// {method, ceres_iterations, verify_points, solver_time_s}.
void to_json(nlohmann::ordered_json& json, const SizingReport& report);
/// (21) sized: {stiffness, damping, velocity_filter_hz, binding_frequency_hz, solver_time_s,
/// verified_worst_margin, solver}.
void to_json(nlohmann::ordered_json& json, const ImpedanceSizing& sizing);
/// (37) sized: {coupling_mass, damping (null: no series damper), binding_frequency_hz,
/// solver_time_s, verified_worst_margin, solver}.
void to_json(nlohmann::ordered_json& json, const AdmittanceSizing& sizing);
/// The passive admittance model sized: {coupling_mass (null: m_c = inf), damping,
/// binding_frequency_hz, binding_environment, worst_margin, finite_mass_fails_at_dc,
/// solver_time_s, solver, exact_check}.
void to_json(nlohmann::ordered_json& json, const PassiveAdmittanceSizing& sizing);
/// The exact admittance model sized: {coupling_mass, damping, binding_frequency_hz,
/// limit_coupling_mass, binding_operator, binding_environment, solver_time_s, solver,
/// exact_check}.
void to_json(nlohmann::ordered_json& json, const ExactAdmittanceSizing& sizing);
/// {unconditionally_stable, worst_margin, worst_frequency_hz, model, the exact model's worst
/// case or the scene's, holds_for, delay_s, verdict}: `verdict` is describe(), the line
/// hapticd logs for the design.
void to_json(nlohmann::ordered_json& json, const StabilityVerdict& verdict);

}  // namespace hapticd::tune
