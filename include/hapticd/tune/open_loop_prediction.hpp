// What the identification model (identification_model.hpp) predicts an open-loop run will
// do: the handle driven from rest by a known force sequence, one value per period held over
// the period (zero-order hold), through m dv/dt + b v = F - F_c sign(v) with the exact hold.
// `hapticd --identify` asks it before it moves anything (make_identify_plan): will the
// excitation leave the workspace, and will friction hold the handle still for so much of
// the run that `haptic-tune identify` must refuse it (IdentificationOptions::
// max_stuck_fraction)?
#pragma once

#include <vector>

#include "hapticd/tune/identification_model.hpp"

namespace hapticd::tune {

struct OpenLoopPrediction {
    double max_excursion_m = 0.0;  ///< max over the run of |x - x(0)|
    /// Fraction of the periods after which the handle is at rest, held by Coulomb friction:
    /// what haptic-tune identify's stuck_fraction measures on the log.
    double stuck_fraction = 0.0;
};

/// The handle at rest at t = 0 under `force_n[n]` over [nT, (n+1)T). mass > 0, damping >= 0,
/// coulomb >= 0, period > 0 (std::invalid_argument otherwise).
OpenLoopPrediction predict_open_loop(const std::vector<double>& force_n, double mass_kg,
                                     double damping_n_s_per_m, double coulomb_n, double period_s);

/// The model (10)+ m dv/dt + b v = F - F_c sign(v) + F_0 run free under a logged force:
/// period n, [nT, (n+1)T), holds F[n - q - 1] for its first `delay.fraction` of T and
/// F[n - q] for the rest (forces before the log are 0), from position 0 and `start_velocity`.
/// Returns the position at the start of every period, x[0] = 0: the backward difference of
/// it is the average velocity the model predicts over each period, the quantity a logged
/// position's difference measures. What `haptic-tune identify --chart` draws against the
/// log (simulation error: no state is refitted along the way). Throws std::invalid_argument
/// for mass <= 0, damping < 0, coulomb < 0 or period <= 0.
struct FreeRunModel {
    double mass_kg = 0.0;
    double damping_n_s_per_m = 0.0;
    double coulomb_n = 0.0;
    double offset_n = 0.0;
};
std::vector<double> free_run_positions(const std::vector<double>& force_n,
                                       const FreeRunModel& model, double period_s, HoldDelay delay,
                                       double start_velocity_mps);

}  // namespace hapticd::tune
