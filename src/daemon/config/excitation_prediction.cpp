#include "config/excitation_prediction.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "hapticd/env/excitation.hpp"
#include "hapticd/tune/identification.hpp"
#include "hapticd/tune/open_loop_prediction.hpp"

namespace hapticd::daemon {
namespace {

std::string format(double value) {
    std::ostringstream out;
    out << std::setprecision(3) << value;
    return out.str();
}

std::string percent(double fraction) { return format(100.0 * fraction) + " %"; }

/// `value` to 3 significant digits, rounded towards zero (`up` false) or away from it: an
/// amplitude quoted as a limit must itself keep to it.
std::string format_rounded(double value, bool up) {
    if (!(value > 0.0 && std::isfinite(value))) return format(value);
    const double unit = std::pow(10.0, std::floor(std::log10(value)) - 2.0);
    return format((up ? std::ceil(value / unit) : std::floor(value / unit)) * unit);
}

/// The planned run's force on each axis at the plan's amplitude, one value per period.
struct PlannedForces {
    std::vector<std::vector<double>> per_axis;
    double period_s = 0.0;
};

PlannedForces planned_forces(const env::ExcitationEnvironment& excitation, double rate_hz,
                             double tail_s) {
    PlannedForces out;
    out.period_s = 1.0 / rate_hz;
    const std::int64_t wait = excitation.still_ticks();
    const std::int64_t tail = std::llround(tail_s * rate_hz);
    for (int axis = 0; axis < excitation.axes(); ++axis) {
        std::vector<double> force(static_cast<std::size_t>(wait), 0.0);
        for (std::int64_t j = 0; j < excitation.samples(); ++j) {
            force.push_back(excitation.scheduled_force_n(j)[axis]);
        }
        force.resize(force.size() + static_cast<std::size_t>(tail), 0.0);
        out.per_axis.push_back(std::move(force));
    }
    return out;
}

/// The worst axis: the largest excursion and the largest stuck fraction, the forces scaled
/// by `scale`.
tune::OpenLoopPrediction predict(const PlannedForces& forces, double scale,
                                 const DeviceModel& model) {
    tune::OpenLoopPrediction worst;
    for (const std::vector<double>& axis : forces.per_axis) {
        std::vector<double> scaled(axis);
        for (double& f : scaled) f *= scale;
        const tune::OpenLoopPrediction p =
            tune::predict_open_loop(scaled, *model.mass_kg, *model.damping_n_s_per_m,
                                    model.coulomb_n.value_or(0.0), forces.period_s);
        worst.max_excursion_m = std::max(worst.max_excursion_m, p.max_excursion_m);
        worst.stuck_fraction = std::max(worst.stuck_fraction, p.stuck_fraction);
    }
    return worst;
}

/// Bisection on the scale in [low, high] for where `good` turns: `good(low) != good(high)`;
/// returns the end of the bracket on `good`'s side, to 0.1 %.
template <typename Good>
double boundary(double low, double high, Good good) {
    const bool good_low = good(low);
    for (int i = 0; i < 60 && high - low > 1e-3 * high; ++i) {
        const double mid = 0.5 * (low + high);
        (good(mid) == good_low ? low : high) = mid;
    }
    return good_low ? low : high;
}

}  // namespace

void predict_excitation(const Config& config, IdentifyPlan& plan, double tail_s) {
    const DeviceModel& model = config.device.model;
    if (!(model.mass_kg && model.damping_n_s_per_m)) return;
    const env::ExcitationSettings& s = plan.excitation;
    std::optional<env::ExcitationEnvironment> excitation;
    try {
        excitation.emplace(s);
    } catch (const std::invalid_argument& e) {
        throw ConfigError(config.source + ": [identify]: " + e.what());
    }
    const PlannedForces forces = planned_forces(*excitation, config.servo.rate_hz, tail_s);
    const tune::OpenLoopPrediction planned = predict(forces, 1.0, model);
    plan.predicted_excursion_m = planned.max_excursion_m;
    if (model.coulomb_n) plan.predicted_stuck_fraction = planned.stuck_fraction;

    const double amplitude_n = s.signal.peak_force_n;
    const std::string where =
        config.source + ": [identify] force_amplitude = " + format(amplitude_n) +
        " N: [device.model] (m = " + format(*model.mass_kg) +
        " kg, b = " + format(*model.damping_n_s_per_m) + " N s/m" +
        (model.coulomb_n ? ", coulomb = " + format(*model.coulomb_n) + " N" : std::string()) +
        ") predicts ";
    // The largest scale the force limit allows (the plan already holds the amplitude to it).
    const double force_scale = s.force_limit_n / excitation->signal().peak_vector_norm_n();
    const auto inside = [&](double scale) {
        return predict(forces, scale, model).max_excursion_m <= s.workspace_half_width_m;
    };
    if (!inside(1.0)) {
        const double allowed = boundary(0.0, 1.0, inside);
        throw ConfigError(where + "the handle swings +-" + format(1e3 * planned.max_excursion_m) +
                          " mm from where it starts, beyond [identify] workspace = " +
                          format(s.workspace_half_width_m) +
                          " m: the run would stop at the workspace's edge. Lower force_amplitude "
                          "to <= " +
                          format_rounded(allowed * amplitude_n, false) +
                          " N, or raise [identify] band_low (now " + format(s.signal.band_low_hz) +
                          " Hz) or workspace");
    }
    const double max_stuck = tune::IdentificationOptions{}.max_stuck_fraction;
    const auto moving = [&](double scale) {
        return predict(forces, scale, model).stuck_fraction <= max_stuck;
    };
    if (model.coulomb_n && !moving(1.0)) {
        const double room = inside(force_scale) ? force_scale : boundary(1.0, force_scale, inside);
        std::string remedy;
        if (moving(room)) {
            remedy = "Raise force_amplitude to >= " +
                     format_rounded(boundary(1.0, room, moving) * amplitude_n, true) +
                     " N (the workspace and the force limit allow up to " +
                     format_rounded(room * amplitude_n, false) + " N)";
        } else {
            remedy = "No force_amplitude up to " + format_rounded(room * amplitude_n, false) +
                     " N (what the workspace and the force limit allow) keeps it moving: widen "
                     "[identify] workspace, or check [device.model] coulomb";
        }
        throw ConfigError(where + "Coulomb friction holds the handle still after " +
                          percent(planned.stuck_fraction) +
                          " of the periods: it barely moves, and haptic-tune identify refuses a "
                          "run stuck above " +
                          percent(max_stuck) + " (stick-slip biases the fit). " + remedy);
    }
}

}  // namespace hapticd::daemon
