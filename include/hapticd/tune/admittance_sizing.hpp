// Sizing the admittance display's coupling (32) where (37) is not to be trusted: the
// `passive` verdict of theory/admittance_passive.hpp, and a sizing on the exact admittance
// loop (exact_admittance.hpp). docs/sizing.md, "The admittance display".
//
// The passive model finds no coupling that holds for every passive operator (a force sensor
// sampled without an anti-aliasing filter weighs every alias of the handle's resonances
// alike), so it sizes nothing: passive_admittance_verdict says why, with the numbers. The
// sizing that produces a coupling is a bisection on the exact loop, for the operators and
// environments that loop checks, with a safety margin on the mass: it holds for that class
// and no wider one.
#pragma once

#include <limits>
#include <optional>
#include <string>

#include "hapticd/servo/rate.hpp"
#include "hapticd/theory/admittance.hpp"
#include "hapticd/tune/coupling_sizing.hpp"
#include "hapticd/tune/exact_admittance.hpp"

namespace hapticd::tune {

/// Why the passive model has no coupling for this display, with its numbers.
struct PassiveAdmittanceVerdict {
    /// (P1): the least device damping the velocity loop needs at a rigid wall.
    double velocity_loop_damping_needed = 0.0;
    bool velocity_loop_passive = false;  ///< b > velocity_loop_damping_needed
    /// (P2) in free space for the coupling asked about: where a passive operator with
    /// resonant aliases reaches the unit circle soonest (the fewest resonances), and how many.
    double alias_frequency_hz = 0.0;
    double resonant_aliases_needed = 0.0;
    std::string explanation;  ///< one paragraph, for an error message
};

/// The verdict for `coupling`, or with none given for pure-mass couplings of 1, 10 and 100
/// device masses (the fields hold the first).
PassiveAdmittanceVerdict passive_admittance_verdict(
    const theory::DeviceModel& device, const theory::PiVelocityLoop& loop, double rate_hz,
    double delay_periods, std::optional<theory::MassDamperCoupling> coupling = std::nullopt);

struct ExactAdmittanceSizingRequest {
    theory::DeviceModel device;
    theory::PiVelocityLoop loop;
    double rate_hz = servo::kDefaultRateHz;
    double delay_periods = 0.0;
    double coupling_damping_n_s_per_m = std::numeric_limits<double>::infinity();  ///< b_c
    double safety_factor = 1.1;  ///< the sized m_c is this times the exact limit (>= 1)
    std::optional<theory::ForceSensorFilter> force_filter =
        std::nullopt;  ///< none: the unfiltered sensor
};

struct ExactAdmittanceSizing {
    theory::MassDamperCoupling coupling;  ///< m_c = safety_factor x limit_mass_kg
    double limit_mass_kg = 0.0;           ///< the lightest m_c the exact check finds stable (1e-3)
    AdmittanceExactCheck check;           ///< the exact check of the sized coupling
    /// The worst case just below the limit: what the margin is kept from.
    OperatorModel binding_operator;
    AdmittanceEnvironment binding_environment;
    double binding_frequency_hz = 0.0;
    SizingReport report;  ///< method "exact-bisection"
};

/// The lightest coupling mass at b_c for which check_exact_admittance finds the loop stable,
/// times the safety factor. Cutting planes: the bisection checks the cases that were worst so
/// far, the full sweep confirms its answer (and adds its worst case when it does not).
/// Throws InfeasibleCoupling (naming the operator and environment) when even m_c = 1e4 m is
/// unstable, and std::invalid_argument for non-physical input.
ExactAdmittanceSizing size_admittance_coupling_exact(const ExactAdmittanceSizingRequest& request);

/// The passive model with an anti-aliasing filter on the force sensor (theory
/// check_filtered_admittance_passive): every passive operator and every passive environment.
struct PassiveAdmittanceSizingRequest {
    theory::DeviceModel device;
    theory::PiVelocityLoop loop;
    double rate_hz = servo::kDefaultRateHz;
    double delay_periods = 0.0;
    double coupling_damping_n_s_per_m = std::numeric_limits<double>::infinity();  ///< b_c
    std::optional<theory::ForceSensorFilter> force_filter = std::nullopt;
};

struct PassiveAdmittanceSizing {
    /// The lightest m_c at b_c for which (P2) holds (+inf: only the pure damper b_c holds; a
    /// finite mass fails at low frequency, theory filtered_alias_slope).
    theory::MassDamperCoupling coupling;
    double binding_frequency_hz = 0.0;
    theory::Complex binding_admittance;  ///< Y_v of the binding environment (m/(N s))
    std::string binding_environment;     ///< that Y_v as an environment impedance Z_e
    double worst_margin = 0.0;           ///< (P2)'s margin at the answer
    bool finite_mass_fails_at_dc = false;
    AdmittanceExactCheck exact;  ///< the answer held against the exact sweep
    SizingReport report;         ///< method "passive-filtered-bisection"
};

/// Throws InfeasibleCoupling with the explanation when no coupling holds: no filter or a
/// first-order one (passive_admittance_verdict's reasons, and the filter as the remedy), the
/// velocity loop failing (P1), the pure damper at b_c failing (naming the lightest that
/// holds), or a pure-mass coupling asked for (no finite m_c holds at DC: naming the lightest
/// pure damper instead). Bisection on log m_c and on log b_c to a relative 1e-4; both are
/// monotone (the environments' disks are nested).
PassiveAdmittanceSizing size_admittance_coupling_passive(const PassiveAdmittanceSizingRequest& r);

/// The lightest pure damper (m_c = inf) for which the filtered (P2) holds, to 1e-4, or +inf.
double lightest_passive_damper(const PassiveAdmittanceSizingRequest& r);

}  // namespace hapticd::tune
