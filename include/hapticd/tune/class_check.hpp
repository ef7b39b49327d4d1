// The exact model under a stated assumption (docs/stability-models.md, "Operator classes"
// and "Scenes"): every passive operator or a declared class (operator_class.hpp), against
// every passive environment or a scene's environments (environment_assumption.hpp).
//
//   every operator, every environment: check_exact with its synthesised adversaries.
//   every operator, a scene:           the default operators and alias-tuned multi-mode
//                                      grasps built for each of the scene's environments
//                                      (the passive bound with that environment is reached
//                                      by them, as it is for the rigid wall).
//   a class:                           a search of the class. Its 3^5 grid (corners, edge
//                                      midpoints, centre), hands-off, and members with two
//                                      modes on two aliases at once (each with the lossless
//                                      environment worst for it) meet the
//                                      environments; from the six worst pairs, and the
//                                      three worst in each band of arg z, a compass
//                                      search climbs the spectral radius over the five
//                                      parameters (and, against every passive environment,
//                                      over the lossless environment's frequency and
//                                      admittance too), halving its step to 2^-16 of each
//                                      range. The verdict names the worst member found,
//                                      or the first that grows by kDecisiveGrowthPerTick.
//                                      Probes and climbs are jobs that one thread per core
//                                      takes from a queue, merged in job order.
#pragma once

#include <optional>
#include <string>

#include "hapticd/tune/environment_assumption.hpp"
#include "hapticd/tune/exact_model.hpp"
#include "hapticd/tune/operator_class.hpp"

namespace hapticd::tune {

struct StabilityAssumption {
    std::optional<OperatorClass> operators;  ///< none: every passive operator
    EnvironmentAssumption environments;      ///< default: every passive environment

    /// "every passive operator and every passive environment", or the class and the scene.
    std::string describe() const;
};

/// The exact model's verdict under `assumption` (the file comment says what is searched).
/// A class search always ends at a witness (kDecisiveGrowthPerTick); a search of every
/// operator does when `search` asks for one (SearchFor). Throws std::invalid_argument naming
/// the value for non-physical input.
ExactCheck check_exact(const theory::DeviceModel& device,
                       const theory::SpringDamperCoupling& coupling, double rate_hz,
                       const StabilityAssumption& assumption, double delay_periods,
                       SearchFor search = SearchFor::worst_case);

/// The largest coupling stiffness k_c (N/m) at the given b_c that check_exact accepts under
/// `assumption`, by bisection to a relative `tolerance`: [lo, hi] brackets the limit with lo
/// accepted and hi rejected (hi up to kMaxCouplingStiffness; 0 when even k_c = 0 is
/// rejected). The bisection assumes one stable interval of k_c from 0, which the final
/// full check of lo confirms for the answer it returns.
struct StiffnessLimit {
    double stiffness_n_per_m = 0.0;  ///< lo: accepted
    double rejected_n_per_m = 0.0;   ///< hi: rejected (or kMaxCouplingStiffness)
    ExactCheck at_limit;             ///< the check of lo
    int checks = 0;                  ///< whole checks (a rejection by a past worst case is not one)
};
/// `coupling` gives b_c and the velocity filter; its stiffness is ignored.
StiffnessLimit exact_stiffness_limit(const theory::DeviceModel& device,
                                     const theory::SpringDamperCoupling& coupling, double rate_hz,
                                     const StabilityAssumption& assumption, double delay_periods,
                                     double tolerance = 2e-3);

}  // namespace hapticd::tune
