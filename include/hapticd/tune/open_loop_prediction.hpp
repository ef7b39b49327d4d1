// What the identification model (identification_model.hpp) predicts an open-loop run will
// do: the handle driven from rest by a known force sequence, one value per period held over
// the period (zero-order hold), through m dv/dt + b v = F - F_c sign(v) with the exact hold.
// `hapticd --identify` asks it before it moves anything (make_identify_plan): will the
// excitation leave the workspace, and will friction hold the handle still for so much of
// the run that `haptic-tune identify` must refuse it (IdentificationOptions::
// max_stuck_fraction)?
#pragma once

#include <vector>

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

}  // namespace hapticd::tune
