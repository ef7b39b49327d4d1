#include "identify_chart.hpp"

#include <cmath>
#include <string>

#include "chart_series.hpp"
#include "hapticd/tune/open_loop_prediction.hpp"

namespace hapticd::tools {
namespace {

/// Backward differences (x[n] - x[n-1]) / T for n >= 1; the first is the second's.
std::vector<double> backward_difference(const std::vector<double>& x, double period_s) {
    std::vector<double> v(x.size(), 0.0);
    for (std::size_t n = 1; n < x.size(); ++n) v[n] = (x[n] - x[n - 1]) / period_s;
    if (v.size() > 1) v[0] = v[1];
    return v;
}

}  // namespace

nlohmann::ordered_json identify_fit_chart(const tune::TelemetryLog& log,
                                          const std::vector<tune::IdentifiedAxis>& axes,
                                          std::vector<FreeRunFit>& fits) {
    nlohmann::ordered_json per_axis = nlohmann::ordered_json::array();
    fits.clear();
    const std::vector<double>& t = *log.column("t_s");
    for (const tune::IdentifiedAxis& a : axes) {
        const std::string axis = std::to_string(a.axis);
        const std::vector<double>& x = *log.column("x" + axis + "_m");
        const std::vector<double>& f = *log.column("f" + axis + "_n");
        const double period_s = 1.0 / a.rate_hz;
        const std::vector<double> measured = backward_difference(x, period_s);
        const tune::FreeRunModel model{a.estimate.mass_kg, a.estimate.damping_n_s_per_m,
                                       a.estimate.coulomb_n, a.estimate.offset_n};
        const std::vector<double> predicted = backward_difference(
            tune::free_run_positions(f, model, period_s,
                                     tune::split_hold_delay(a.delay_s, period_s), measured[0]),
            period_s);
        std::vector<double> error(measured.size());
        double mean = 0.0;
        for (const double v : measured) mean += v / static_cast<double>(measured.size());
        double error_sq = 0.0;
        double spread_sq = 0.0;
        for (std::size_t n = 0; n < measured.size(); ++n) {
            error[n] = predicted[n] - measured[n];
            error_sq += error[n] * error[n];
            spread_sq += (measured[n] - mean) * (measured[n] - mean);
        }
        FreeRunFit fit;
        fit.velocity_rms_error_mps = std::sqrt(error_sq / static_cast<double>(measured.size()));
        fit.explained_fraction = spread_sq > 0.0 ? 1.0 - error_sq / spread_sq : 0.0;
        fits.push_back(fit);
        per_axis.push_back({{"axis", a.axis},
                            {"estimate",
                             {{"mass_kg", a.estimate.mass_kg},
                              {"damping_n_s_per_m", a.estimate.damping_n_s_per_m},
                              {"coulomb_n", a.estimate.coulomb_n},
                              {"offset_n", a.estimate.offset_n}}},
                            {"delay_s", a.delay_s},
                            {"measured_velocity", chart_series(t, measured)},
                            {"predicted_velocity", chart_series(t, predicted)},
                            {"velocity_error", chart_series(t, error)},
                            {"velocity_rms_error_mps", fit.velocity_rms_error_mps},
                            {"explained_fraction", fit.explained_fraction}});
    }
    return {{"kind", "identify-fit"}, {"axes", per_axis}};
}

}  // namespace hapticd::tools
