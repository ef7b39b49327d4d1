#include "hapticd/tune/open_loop_prediction.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hapticd/tune/identification_model.hpp"

namespace hapticd::tune {

namespace {

/// b/m for the exact hold, which needs a > 0 (a damping far below any device's is the same
/// motion); std::invalid_argument for a model that is no device.
double decay_rate_per_s(double mass_kg, double damping_n_s_per_m, double coulomb_n,
                        double period_s) {
    if (!(mass_kg > 0.0 && damping_n_s_per_m >= 0.0 && coulomb_n >= 0.0 && period_s > 0.0)) {
        throw std::invalid_argument(
            "open-loop prediction: needs mass > 0, damping >= 0, coulomb >= 0 and period > 0");
    }
    return std::max(damping_n_s_per_m / mass_kg, 1e-9);
}

}  // namespace

OpenLoopPrediction predict_open_loop(const std::vector<double>& force_n, double mass_kg,
                                     double damping_n_s_per_m, double coulomb_n, double period_s) {
    const double a = decay_rate_per_s(mass_kg, damping_n_s_per_m, coulomb_n, period_s);
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

std::vector<double> free_run_positions(const std::vector<double>& force_n,
                                       const FreeRunModel& model, double period_s, HoldDelay delay,
                                       double start_velocity_mps) {
    const double a =
        decay_rate_per_s(model.mass_kg, model.damping_n_s_per_m, model.coulomb_n, period_s);
    const double early_s = delay.fraction * period_s;
    const double late_s = period_s - early_s;
    const HoldConstants<double> early = hold_constants(a, early_s);
    const HoldConstants<double> late = hold_constants(a, late_s);
    const auto force_at = [&](std::size_t n, std::size_t back) {
        return n >= back ? force_n[n - back] + model.offset_n : model.offset_n;
    };
    std::vector<double> x(force_n.size());
    MotionState<double> state{0.0, start_velocity_mps};
    for (std::size_t n = 0; n + 1 < force_n.size(); ++n) {
        if (early_s > 0.0) {
            hold_step(state, model.mass_kg, a, model.coulomb_n,
                      force_at(n, delay.whole_periods + 1), early, early_s);
        }
        hold_step(state, model.mass_kg, a, model.coulomb_n, force_at(n, delay.whole_periods), late,
                  late_s);
        x[n + 1] = state.x;
    }
    return x;
}

}  // namespace hapticd::tune
