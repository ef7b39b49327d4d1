#include "hapticd/tune/coupling_sizing.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <sstream>
#include <vector>

#include "hapticd/theory/frequency_grid.hpp"
#include "hapticd/tune/input_checks.hpp"

namespace hapticd::tune {
namespace {

using theory::HoldModel;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kScanPoints = 512;
constexpr int kVerifyPoints = 20000;
constexpr double kLowestTheta = 1e-6;  // the f -> 0 limit, to O(θ²) = 1e-12 relative
// The answer is backed off by this relative amount so that rounding (and the O(θ²) of the
// f -> 0 limit) never puts a design that touches the bound on its wrong side.
constexpr double kBackOff = 1e-11;

/// The coupling family W = β B(z) + α T z/(z - 1): B = 1 (16), (32), or the impedance
/// display's damper on a filtered velocity, B = (1 - a)/(1 - a z⁻¹) (velocity_filter.hpp).
struct Family {
    double period = 0.0;     ///< T
    double filter_hz = 0.0;  ///< f_c of the velocity filter; 0: B = 1
    double pole = 0.0;       ///< a = exp(-2π f_c T); 0: B = 1
    explicit Family(double period_s, double filter_hz_ = 0.0)
        : period(period_s),
          filter_hz(filter_hz_),
          pole(theory::velocity_filter_pole(filter_hz_, period_s)) {}
    bool filtered() const { return pole > 0.0; }
};

/// r(θ), the least Re(1/W) the display needs, and its slope dr/dθ.
struct ConductanceBound {
    std::function<double(double)> value;
    std::function<double(double)> slope;
    /// r on an increasing grid, when a table is cheaper than the values one by one.
    std::function<std::vector<double>(const std::vector<double>&)> table;
};

/// Largest α >= 0 with Re(1/W) >= r at θ, for W = β + α T z/(z - 1). Re(1/W) falls
/// monotonically with α (docs/sizing.md), so the feasible set is [0, α_max], where α_max is
/// the larger root of  r a²(1 + c²) α² + a(2rβ - 1) α + β(rβ - 1) = 0,  a = T/2,
/// c = cot(θ/2). With a velocity filter, W = β B + α A, A = a(1 - jc), and Re(1/W) >= r is
///   r |A|² α² + (2rβ Re(A conj B) - a) α + β(rβ |B|² - Re B) <= 0,
/// Re(A conj B) = a (Re B - c Im B); Re(1/W) still falls with α (docs/sizing.md), so the
/// feasible set is again [0, larger root]. Returns +inf when r <= 0 and a negative number
/// when even α = 0 fails.
double alpha_max(double theta, double beta, double r, const Family& family) {
    if (!(r > 0.0)) return r == 0.0 ? kInf : -1.0;  // NaN or negative r: treat as failing
    if (std::isinf(r)) return -1.0;
    const double a = family.period / 2.0;
    const double half_sine = std::sin(theta / 2.0);
    const double qa = r * a * a / (half_sine * half_sine);  // 1 + c² = 1/sin²(θ/2)
    double qb = a * (2.0 * r * beta - 1.0);
    double qc = beta * (r * beta - 1.0);
    if (family.filtered()) {
        const theory::FilterResponse<double> b =
            theory::velocity_filter_response(family.pole, theta);
        const double cot = 1.0 / std::tan(theta / 2.0);
        qb = a * (2.0 * r * beta * (b.re - cot * b.im) - 1.0);
        qc = beta * (r * beta * (b.re * b.re + b.im * b.im) - b.re);
    }
    if (qc > 0.0) return -1.0;  // Re(1/W) at α = 0 is Re(1/B)/β < r
    const double root = std::sqrt(qb * qb - 4.0 * qa * qc);
    // The larger root without cancellation: (-b + √d)/2a when b <= 0, else 2c/(-b - √d).
    return qb <= 0.0 ? (-qb + root) / (2.0 * qa)
                     : (qb + root > 0.0 ? -2.0 * qc / (qb + root) : 0.0);
}

/// Re(1/W) and its partial derivatives in α and θ, by forward-mode automatic differentiation.
struct ConductancePartials {
    double d_alpha = 0.0;
    double d_theta = 0.0;
};
ConductancePartials conductance_partials(double alpha, double beta, double theta,
                                         const Family& family) {
    using Jet = ceres::Jet<double, 2>;
    const Jet g = theory::coupling_conductance(Jet(alpha, 0), Jet(beta), Jet(theta, 1),
                                               family.period, family.filter_hz);
    return {g.v[0], g.v[1]};
}

/// dα_max/dθ at fixed β: zero where the coupling's conductance curve touches the bound.
/// From G(α_max(θ), θ) = r(θ):  dα_max/dθ = (r'(θ) - ∂G/∂θ) / ∂G/∂α.
struct TangencyResidual {
    const ConductanceBound* bound;
    double beta;
    Family family;
    bool operator()(const double* theta, double* residual) const {
        const double r = bound->value(theta[0]);
        const double alpha = alpha_max(theta[0], beta, r, family);
        if (!(alpha >= 0.0) || std::isinf(alpha)) return false;
        const ConductancePartials p = conductance_partials(alpha, beta, theta[0], family);
        residual[0] = (bound->slope(theta[0]) - p.d_theta) / p.d_alpha;
        return std::isfinite(residual[0]);
    }
};

/// The best pair (α, β) is a saddle of α_max(θ, β): a minimum over θ, a maximum over β.
/// For B = 1 (no velocity filter),
/// ∂G/∂β = 0 there, which is X = R: the coupling's phase is 45° at the binding frequency.
/// Along that curve α = κ(θ) = tan(θ/2)/(T r(θ)) and β = (1 - tan(θ/2))/(2 r(θ)), and the
/// saddle is a stationary point of κ:  d ln κ/dθ = 1/sin θ - r'(θ)/r(θ) = 0.
struct SaddleResidual {
    const ConductanceBound* bound;
    bool operator()(const double* theta, double* residual) const {
        const double r = bound->value(theta[0]);
        residual[0] = 1.0 / std::sin(theta[0]) - bound->slope(theta[0]) / r;
        return std::isfinite(residual[0]);
    }
};
double saddle_alpha(const ConductanceBound& bound, double theta, double period) {
    return std::tan(theta / 2.0) / (period * bound.value(theta));
}
double saddle_beta(const ConductanceBound& bound, double theta) {
    return (1.0 - std::tan(theta / 2.0)) / (2.0 * bound.value(theta));
}

/// Drives a one-parameter residual to zero with Ceres' trust-region solver, θ kept inside
/// [lo, hi]. The Jacobian is taken by central differences of the (analytic) residual.
template <typename Residual>
double solve_in_bracket(const Residual& residual, double lo, double hi, double start,
                        int* iterations) {
    double theta = start;
    ceres::Problem problem;
    problem.AddResidualBlock(
        new ceres::NumericDiffCostFunction<Residual, ceres::CENTRAL, 1, 1>(new Residual(residual)),
        nullptr, &theta);
    problem.SetParameterLowerBound(&theta, 0, lo);
    problem.SetParameterUpperBound(&theta, 0, hi);
    ceres::Solver::Options options;
    options.linear_solver_type = ceres::DENSE_QR;
    options.logging_type = ceres::SILENT;
    options.max_num_iterations = 100;
    options.function_tolerance = 1e-20;
    options.gradient_tolerance = 1e-30;
    options.parameter_tolerance = 1e-15;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    *iterations += summary.num_successful_steps + summary.num_unsuccessful_steps;
    return theta;
}

/// A frequency grid with the bound tabulated on it: r(θ) is computed once per sizing, not
/// once per damping tried (the passive model's M(θ) for a fraction of a period of delay is a
/// one-dimensional maximum at each frequency).
struct Grid {
    std::vector<double> theta;
    std::vector<double> r;
};

Grid tabulate(const ConductanceBound& bound, int points) {
    Grid grid{theory::frequency_grid(points, kLowestTheta), {}};
    if (bound.table) {
        grid.r = bound.table(grid.theta);
        return grid;
    }
    grid.r.reserve(grid.theta.size());
    for (double theta : grid.theta) grid.r.push_back(bound.value(theta));
    return grid;
}

struct FixedBetaSolution {
    double alpha = 0.0;
    double theta = 0.0;
    std::string method;
};

/// The largest α for a given β: the minimum over θ of α_max(θ), found on a scan grid,
/// refined with Ceres at the tangency point, and checked on a dense grid (a tangency the
/// scan missed is refined in turn) unless `check_dense` is false.
FixedBetaSolution size_fixed_beta(const ConductanceBound& bound, double beta, const Family& family,
                                  const Grid& scan, const Grid& dense, int* iterations,
                                  bool check_dense = true) {
    const auto solve_from = [&](const Grid& table) {
        const std::vector<double>& grid = table.theta;
        std::size_t best = 0;
        double best_alpha = kInf;
        for (std::size_t i = 0; i < grid.size(); ++i) {
            const double alpha = alpha_max(grid[i], beta, table.r[i], family);
            if (alpha < best_alpha) {
                best_alpha = alpha;
                best = i;
            }
        }
        FixedBetaSolution s{best_alpha, grid[best], "bracket"};
        if (best == 0) {
            s.method = "dc-limit";
            s.theta = 0.0;
        } else if (best + 1 == grid.size()) {
            s.method = "nyquist";
        } else if (std::isfinite(best_alpha) && best_alpha >= 0.0) {
            const double theta =
                solve_in_bracket(TangencyResidual{&bound, beta, family}, grid[best - 1],
                                 grid[best + 1], grid[best], iterations);
            const double alpha = alpha_max(theta, beta, bound.value(theta), family);
            if (alpha <= best_alpha) s = {alpha, theta, "tangency"};
        }
        return s;
    };
    FixedBetaSolution solution = solve_from(scan);
    if (solution.alpha < 0.0 || !check_dense) return solution;
    const FixedBetaSolution check = solve_from(dense);
    if (check.alpha < solution.alpha * (1.0 - 1e-10)) solution = check;
    return solution;
}

/// Smallest relative margin Re(1/W)/r - 1 of the final answer over the dense grid.
double verified_margin(double alpha, double beta, const Family& family, const Grid& dense) {
    double worst = kInf;
    for (std::size_t i = 0; i < dense.theta.size(); ++i) {
        worst = std::min(worst, theory::relative_margin(
                                    theory::coupling_conductance(alpha, beta, dense.theta[i],
                                                                 family.period, family.filter_hz),
                                    dense.r[i]));
    }
    return worst;
}

/// Where r(θ)/Re(1/B(θ)) is largest: the frequency that decides how much β may be (at α = 0,
/// Re(1/W) = Re(1/B)/β, and it only falls with α). Re(1/B) = 1 without a velocity filter.
struct BoundPeak {
    double value = 0.0;  ///< r/Re(1/B): 1/β_max
    double theta = 0.0;
    double bound = 0.0;  ///< r there
    double gain = 1.0;   ///< Re(1/B) there
};
BoundPeak bound_peak(const Grid& dense, const Family& family) {
    BoundPeak peak;
    for (std::size_t i = 0; i < dense.theta.size(); ++i) {
        const double r = dense.r[i];
        const double gain = family.filtered() ? theory::velocity_filter_conductance_gain(
                                                    family.pole, dense.theta[i])
                                              : 1.0;
        if (r / gain > peak.value) peak = {r / gain, dense.theta[i], r, gain};
    }
    return peak;
}

/// Re(1/W) of any coupling with α > 0 vanishes like θ² as θ -> 0 (X ~ 1/θ). A bound that
/// does not vanish as fast cannot be met there by any such coupling. Returns r(θ)/θ² growth
/// between θ = 1e-5 and 1e-6: about 1 for a bound ~ θ², about 100 for one that stays finite.
double low_frequency_growth(const ConductanceBound& bound) {
    const double q_low = bound.value(kLowestTheta) / (kLowestTheta * kLowestTheta);
    const double q_high = bound.value(10.0 * kLowestTheta) / (100.0 * kLowestTheta * kLowestTheta);
    return q_low / q_high;
}

struct PairSolution {
    double alpha = 0.0;
    double beta = 0.0;
    double theta = 0.0;
    std::string method;
};

/// The best (α, β): saddle points of α_max(θ, β), each confirmed by a fixed-β sizing at its
/// β; β = 0 is the boundary candidate. If no saddle is confirmed, a golden-section search
/// over β of the fixed-β answer decides.
///
/// With a velocity filter the saddle's closed forms (B = 1) do not hold, and the search
/// over β decides: the feasible (α, β) of each θ, r|αA + βB|² <= Re(αA + βB), is an
/// ellipse's interior, so their intersection is convex and the largest feasible α is a
/// concave (unimodal) function of β.
PairSolution size_best_pair(const ConductanceBound& bound, const Family& family, const Grid& scan,
                            const Grid& dense, double beta_limit, int* iterations) {
    const double period = family.period;
    const FixedBetaSolution at_zero = size_fixed_beta(bound, 0.0, family, scan, dense, iterations);
    PairSolution best{at_zero.alpha, 0.0, at_zero.theta, at_zero.method};
    bool confirmed = false;
    // β >= 0 needs tan(θ/2) <= 1, so saddles lie below half the Nyquist angle.
    std::vector<double> kappa;
    std::vector<double> thetas;
    for (std::size_t i = 0; i < scan.theta.size() && !family.filtered(); ++i) {
        const double theta = scan.theta[i];
        if (theta >= std::numbers::pi / 2.0) break;
        thetas.push_back(theta);
        kappa.push_back(std::tan(theta / 2.0) / (period * scan.r[i]));  // saddle_alpha
    }
    for (std::size_t i = 1; i + 1 < kappa.size(); ++i) {
        if (!(kappa[i] <= kappa[i - 1] && kappa[i] <= kappa[i + 1])) continue;
        const double theta = solve_in_bracket(SaddleResidual{&bound}, thetas[i - 1], thetas[i + 1],
                                              thetas[i], iterations);
        const double beta = saddle_beta(bound, theta);
        const double alpha = saddle_alpha(bound, theta, period);
        if (!(beta >= 0.0)) continue;
        const FixedBetaSolution fixed =
            size_fixed_beta(bound, beta, family, scan, dense, iterations);
        if (std::abs(fixed.alpha - alpha) > 1e-7 * alpha) continue;  // another θ binds first
        confirmed = true;
        if (fixed.alpha > best.alpha) best = {fixed.alpha, beta, theta, "saddle"};
    }
    if (confirmed) return best;
    // Golden-section over β in [0, beta_limit) on the fixed-β answer.
    const auto alpha_at = [&](double beta) {
        return size_fixed_beta(bound, beta, family, scan, dense, iterations, false).alpha;
    };
    const double inv_phi = (std::sqrt(5.0) - 1.0) / 2.0;
    double lo = 0.0;
    double hi = beta_limit;
    double b1 = hi - inv_phi * (hi - lo);
    double b2 = lo + inv_phi * (hi - lo);
    double a1 = alpha_at(b1);
    double a2 = alpha_at(b2);
    for (int i = 0; i < 60 && hi - lo > 1e-9 * beta_limit; ++i) {
        if (a1 > a2) {
            hi = b2, b2 = b1, a2 = a1, b1 = hi - inv_phi * (hi - lo), a1 = alpha_at(b1);
        } else {
            lo = b1, b1 = b2, a1 = a2, b2 = lo + inv_phi * (hi - lo), a2 = alpha_at(b2);
        }
    }
    const double beta = a1 > a2 ? b1 : b2;
    if (std::max(a1, a2) > best.alpha) {
        // The search compared scan-grid answers; the dense check may lower this one.
        const FixedBetaSolution s = size_fixed_beta(bound, beta, family, scan, dense, iterations);
        if (s.alpha > best.alpha) best = {s.alpha, beta, s.theta, "golden-section"};
    }
    return best;
}

ConductanceBound impedance_display_bound(const theory::DeviceModel& device,
                                         const theory::LoopModel& model) {
    const double b = device.damping_n_s_per_m;
    ConductanceBound bound{[=](double theta) { return theory::conductance_bound(model, b, theta); },
                           [=](double theta) {
                               using Jet = ceres::Jet<double, 1>;
                               return theory::conductance_bound(model, b, Jet(theta, 0)).v[0];
                           },
                           [=](const std::vector<double>& thetas) {
                               return theory::conductance_bounds(model, b, thetas);
                           }};
    return bound;
}

ConductanceBound admittance_display_bound(const theory::DeviceModel& device,
                                          const theory::PiVelocityLoop& loop, HoldModel model,
                                          double period) {
    const auto value = [=](double theta) {
        return theory::admittance_coupling_bound(device, loop, model, theta, period);
    };
    // (37) is complex arithmetic end to end; its slope is taken by a central difference.
    return {value,
            [=](double theta) {
                const double h = 1e-6 * std::max(theta, 1e-3);
                return (value(theta + h) - value(theta - h)) / (2.0 * h);
            },
            nullptr};
}

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

ImpedanceSizing size_impedance_coupling(const ImpedanceSizingRequest& request) {
    const auto start = std::chrono::steady_clock::now();
    check_device(request.device);
    check_rate(request.rate_hz);
    check_delay_periods(request.model.delay_periods);
    check_velocity_filter(request.velocity_filter_hz, request.rate_hz);
    if (request.coupling_damping_n_s_per_m) {
        check_non_negative("coupling damping b_c", *request.coupling_damping_n_s_per_m, "N s/m");
    }
    const double period = 1.0 / request.rate_hz;
    const Family family(period, request.velocity_filter_hz);
    const ConductanceBound bound = impedance_display_bound(request.device, request.model);
    const Grid scan = tabulate(bound, kScanPoints);
    const Grid dense = tabulate(bound, kVerifyPoints);
    const BoundPeak peak = bound_peak(dense, family);

    ImpedanceSizing result;
    int iterations = 0;
    if (request.coupling_damping_n_s_per_m) {
        const double b_c = *request.coupling_damping_n_s_per_m;
        if (b_c * peak.value >= 1.0) {
            std::ostringstream why;
            why << "coupling damping b_c = " << b_c << " N s/m is infeasible for model '"
                << theory::to_string(request.model.hold) << "'";
            if (family.filtered()) {
                why << " with a velocity filter at " << family.filter_hz << " Hz";
            }
            why << ": (21) needs Re(1/Z_c) >= " << peak.bound << " S at "
                << theory::frequency_hz(peak.theta, period)
                << " Hz, and a coupling with damping b_c"
                << (family.filtered() ? " on the filtered velocity" : "") << " has Re(1/Z_c) < ";
            if (family.filtered()) {
                why << peak.gain << "/b_c there (the filter's Re(1/B))";
            } else {
                why << "1/b_c";
            }
            why << " at any k_c > 0; b_c must be below " << 1.0 / peak.value << " N s/m";
            throw InfeasibleCoupling(why.str());
        }
        const FixedBetaSolution s = size_fixed_beta(bound, b_c, family, scan, dense, &iterations);
        if (!(s.alpha > 0.0)) {
            // At the edge of the feasible b_c (b_c = b with a delay) the solve returns k_c = 0
            // or -0: no stiffness is no design.
            std::ostringstream why;
            why << "coupling damping b_c = " << b_c << " N s/m leaves no stiffness for model '"
                << theory::to_string(request.model.hold) << "': (21) holds only at k_c = 0 (at "
                << theory::frequency_hz(s.theta, period) << " Hz); b_c must be below "
                << 1.0 / peak.value << " N s/m";
            throw InfeasibleCoupling(why.str());
        }
        result.coupling = {s.alpha, b_c, request.velocity_filter_hz};
        result.binding_frequency_hz = theory::frequency_hz(s.theta, period);
        result.report.method = s.method;
    } else {
        const PairSolution s =
            size_best_pair(bound, family, scan, dense, 1.0 / peak.value, &iterations);
        result.coupling = {s.alpha, s.beta, request.velocity_filter_hz};
        result.binding_frequency_hz = theory::frequency_hz(s.theta, period);
        result.report.method = s.method;
    }
    result.coupling.stiffness_n_per_m *= 1.0 - kBackOff;
    result.verified_worst_margin = verified_margin(
        result.coupling.stiffness_n_per_m, result.coupling.damping_n_s_per_m, family, dense);
    result.report.ceres_iterations = iterations;
    result.report.verify_points = kVerifyPoints;
    result.report.solver_time_s = seconds_since(start);
    return result;
}

AdmittanceSizing size_admittance_coupling(const AdmittanceSizingRequest& request) {
    const auto start = std::chrono::steady_clock::now();
    check_device(request.device);
    check_rate(request.rate_hz);
    check_non_negative("proportional gain k_p", request.loop.proportional_gain_n_s_per_m, "N s/m");
    check_non_negative("integral gain k_i", request.loop.integral_gain_n_per_m, "N/m");
    if (request.coupling_damping_n_s_per_m) {
        check_positive_or_infinite("coupling damping b_c", *request.coupling_damping_n_s_per_m,
                                   "N s/m");
    }
    const double period = 1.0 / request.rate_hz;
    const Family family(period);  // (32): β + α T z/(z - 1), no filter
    const ConductanceBound bound =
        admittance_display_bound(request.device, request.loop, request.model, period);
    const Grid scan = tabulate(bound, kScanPoints);
    const Grid dense = tabulate(bound, kVerifyPoints);

    // (35): the display's own conductance Re(1/Z_dA) must be >= 0 everywhere; where it is
    // negative the bound is infinite and no coupling can meet (37).
    for (double theta : dense.theta) {
        const double conductance = theory::admittance_display_conductance(
            request.device, request.loop, request.model, theta, period);
        if (conductance < 0.0) {
            std::ostringstream why;
            why << "(37) cannot be met with k_p = " << request.loop.proportional_gain_n_s_per_m
                << " N s/m, k_i = " << request.loop.integral_gain_n_per_m
                << " N/m: the velocity loop makes the display active at "
                << theory::frequency_hz(theta, period) << " Hz (Re(1/Z_dA) = " << conductance
                << " m/(N s) < 0, so (35) fails and no passive coupling restores unconditional "
                << "stability; lower the PI gains or raise the rate)";
            throw InfeasibleCoupling(why.str());
        }
    }
    if (const double growth = low_frequency_growth(bound); growth > 10.0) {
        std::ostringstream why;
        why << "(37) cannot be met as f -> 0 with k_i = " << request.loop.integral_gain_n_per_m
            << " N/m: with integral action the bound stays near " << bound.value(kLowestTheta)
            << " N s/m at " << theory::frequency_hz(kLowestTheta, period)
            << " Hz, while the series mass-damper coupling (32) has no resistance at DC "
            << "(Re(Z_cA) ~ f²); use k_i = 0 (proportional velocity feedback)";
        throw InfeasibleCoupling(why.str());
    }
    const BoundPeak peak = bound_peak(dense, family);
    AdmittanceSizing result;
    int iterations = 0;
    double alpha = 0.0;
    double beta = 0.0;
    double theta = 0.0;
    if (request.coupling_damping_n_s_per_m) {
        beta = 1.0 / *request.coupling_damping_n_s_per_m;
        if (beta * peak.value >= 1.0) {
            std::ostringstream why;
            why << "coupling damping b_c = " << *request.coupling_damping_n_s_per_m
                << " N s/m is infeasible: (37) needs Re(Z_cA) >= " << peak.value << " N s/m at "
                << theory::frequency_hz(peak.theta, period)
                << " Hz, and a series mass-damper has Re(Z_cA) < b_c; b_c must exceed "
                << peak.value << " N s/m";
            throw InfeasibleCoupling(why.str());
        }
        const FixedBetaSolution s = size_fixed_beta(bound, beta, family, scan, dense, &iterations);
        alpha = s.alpha;
        theta = s.theta;
        result.report.method = s.method;
    } else {
        const PairSolution s =
            size_best_pair(bound, family, scan, dense, 1.0 / peak.value, &iterations);
        alpha = s.alpha;
        beta = s.beta;
        theta = s.theta;
        result.report.method = s.method;
    }
    alpha *= 1.0 - kBackOff;
    result.coupling = {1.0 / alpha, beta > 0.0 ? 1.0 / beta : kInf};
    result.binding_frequency_hz = theory::frequency_hz(theta, period);
    result.verified_worst_margin = verified_margin(alpha, beta, family, dense);
    result.report.ceres_iterations = iterations;
    result.report.verify_points = kVerifyPoints;
    result.report.solver_time_s = seconds_since(start);
    return result;
}

}  // namespace hapticd::tune
