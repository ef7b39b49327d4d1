#include "hapticd/tune/open_loop_prediction.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hapticd/tune/identification_model.hpp"

namespace hapticd::tune {

OpenLoopPrediction predict_open_loop(const std::vector<double>& force_n, double mass_kg,
                                     double damping_n_s_per_m, double coulomb_n, double period_s) {
    if (!(mass_kg > 0.0 && damping_n_s_per_m >= 0.0 && coulomb_n >= 0.0 && period_s > 0.0)) {
        throw std::invalid_argument(
            "open-loop prediction: needs mass > 0, damping >= 0, coulomb >= 0 and period > 0");
    }
    // The exact hold needs a = b/m > 0; a damping far below any device's is the same motion.
    const double a = std::max(damping_n_s_per_m / mass_kg, 1e-9);
    const HoldConstants<double> full = hold_constants(a, period_s);
    MotionState<double> state{0.0, 0.0};
    OpenLoopPrediction out;
    std::size_t at_rest = 0;
    for (const double f : force_n) {
        hold_step(state, mass_kg, a, coulomb_n, f, full, period_s);
        out.max_excursion_m = std::max(out.max_excursion_m, std::abs(state.x));
        at_rest += state.v == 0.0;
    }
    if (!force_n.empty()) {
        out.stuck_fraction = static_cast<double>(at_rest) / static_cast<double>(force_n.size());
    }
    return out;
}

}  // namespace hapticd::tune
