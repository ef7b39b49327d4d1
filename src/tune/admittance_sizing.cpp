#include "hapticd/tune/admittance_sizing.hpp"

#include <chrono>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <sstream>
#include <vector>

#include "hapticd/theory/admittance_passive.hpp"
#include "hapticd/theory/passive_model.hpp"
#include "hapticd/tune/input_checks.hpp"

namespace hapticd::tune {
namespace {

constexpr double kHeaviestCouplingPerDeviceMass = 1e4;
constexpr double kBisectionTolerance = 1e-3;  // relative, on m_c

struct Case {
    OperatorModel human;
    AdmittanceEnvironment environment;
};

}  // namespace

PassiveAdmittanceVerdict passive_admittance_verdict(
    const theory::DeviceModel& device, const theory::PiVelocityLoop& loop, double rate_hz,
    double delay_periods, std::optional<theory::MassDamperCoupling> coupling) {
    check_device(device);
    check_rate(rate_hz);
    check_delay_periods(delay_periods);
    const double period = 1.0 / rate_hz;
    PassiveAdmittanceVerdict v;
    v.velocity_loop_damping_needed =
        theory::velocity_loop_damping_bound(loop, period, delay_periods);
    v.velocity_loop_passive = device.damping_n_s_per_m > v.velocity_loop_damping_needed;
    // (P2) in free space: the frequency that needs the fewest resonant aliases. A fraction of
    // a period of delay only makes it worse (the shifted hold rotates each alias's weight
    // differently); the whole periods give the form the derivation states.
    const int whole = theory::split_delay(delay_periods).whole_periods;
    const auto fewest_for = [&](const theory::MassDamperCoupling& c, double* frequency_hz) {
        double fewest = std::numeric_limits<double>::infinity();
        constexpr int kPoints = 128;
        for (int i = 1; i <= kPoints; ++i) {
            const double theta = std::numbers::pi * i / kPoints;
            const theory::AliasReach r =
                theory::free_space_alias_reach(device, loop, c, theta, period, whole);
            // Ties go to the higher frequency: nearer Nyquist the count is exact.
            if (r.reach >= 0.0 && r.resonant_aliases_needed <= fewest) {
                fewest = r.resonant_aliases_needed;
                *frequency_hz = theory::frequency_hz(theta, period);
            }
        }
        return fewest;
    };
    const double inf = std::numeric_limits<double>::infinity();
    std::ostringstream counts;
    if (coupling) {
        v.resonant_aliases_needed = fewest_for(*coupling, &v.alias_frequency_hz);
        counts << " (for m_c = " << coupling->mass_kg << " kg: " << v.resonant_aliases_needed
               << " resonant aliases of " << v.alias_frequency_hz << " Hz)";
    } else {
        // How the count grows with a pure-mass coupling of 1, 10 and 100 device masses.
        counts << " (with a pure-mass coupling of";
        for (const double ratio : {1.0, 10.0, 100.0}) {
            double frequency = 0.0;
            const double n = fewest_for({ratio * device.mass_kg, inf}, &frequency);
            if (ratio == 1.0) {
                v.resonant_aliases_needed = n;
                v.alias_frequency_hz = frequency;
            }
            counts << (ratio == 1.0 ? " " : ", ") << ratio * device.mass_kg << " kg: " << n
                   << " resonant aliases of " << frequency << " Hz";
        }
        counts << ")";
    }
    std::ostringstream why;
    why << "no coupling (32) makes this admittance display stable for every passive operator "
           "(the passive model, docs/stability-models.md): ";
    if (!v.velocity_loop_passive) {
        why << "at a rigid wall the PI velocity loop k_p = " << loop.proportional_gain_n_s_per_m
            << " N s/m, k_i = " << loop.integral_gain_n_per_m
            << " N/m is an impedance controller on the encoder and needs device damping b >= "
            << v.velocity_loop_damping_needed << " N s/m (b = " << device.damping_n_s_per_m
            << "; (35) with the whole alias sum), whatever the coupling; and ";
    }
    why << "the force sensor, sampled with no anti-aliasing filter, weighs every alias of a "
           "free-handle resonance alike, so in free space a passive operator with enough "
           "lossless resonances on the aliases of some frequency reaches the unit circle for "
           "every coupling mass and damping";
    why << counts.str();
    why << ". Size for the operators the exact admittance model checks with --model exact, or "
           "filter the force sensor before it is sampled";
    v.explanation = why.str();
    return v;
}

ExactAdmittanceSizing size_admittance_coupling_exact(const ExactAdmittanceSizingRequest& request) {
    const auto start = std::chrono::steady_clock::now();
    check_positive_or_infinite("coupling damping b_c", request.coupling_damping_n_s_per_m, "N s/m");
    check_in_range("safety factor", request.safety_factor, 1.0, 100.0, "");
    const auto design_with = [&](double mass) {
        return AdmittanceDesign{
            request.device,  request.loop,          {mass, request.coupling_damping_n_s_per_m},
            request.rate_hz, request.delay_periods, request.force_filter};
    };
    const double heaviest = kHeaviestCouplingPerDeviceMass * request.device.mass_kg;
    const std::vector<OperatorModel> operators =
        default_operator_sweep(request.device, request.rate_hz);
    const std::vector<AdmittanceEnvironment> environments =
        default_admittance_environment_sweep(request.device);
    ExactAdmittanceSizing result;
    const auto full = [&](double mass) {
        return check_exact_admittance(design_with(mass), operators, environments);
    };
    // The heaviest coupling first: if it is unstable, no mass is stable (a heavier mass only
    // brings v_com closer to the rigid wall's 0, or to the damper's F/b_c).
    AdmittanceExactCheck at_heaviest = full(heaviest);
    if (!at_heaviest.stable) {
        std::ostringstream why;
        why << "no coupling mass up to " << heaviest << " kg";
        if (std::isfinite(request.coupling_damping_n_s_per_m)) {
            why << " with b_c = " << request.coupling_damping_n_s_per_m << " N s/m";
        }
        why << " is stable in the exact admittance model: " << at_heaviest.worst_operator.describe()
            << " against " << at_heaviest.worst_environment.describe()
            << " grows by |z| = " << at_heaviest.worst_spectral_radius << " per tick at "
            << at_heaviest.worst_frequency_hz << " Hz";
        const double needed = theory::velocity_loop_damping_bound(
            request.loop, 1.0 / request.rate_hz, request.delay_periods);
        if (request.device.damping_n_s_per_m <= needed) {
            why << " (the PI loop alone needs b >= " << needed
                << " N s/m at a rigid wall: lower k_p, k_i)";
        } else if (std::isfinite(request.coupling_damping_n_s_per_m)) {
            why << " (raise b_c, or leave the damper out)";
        }
        throw InfeasibleCoupling(why.str());
    }
    // Bracket [lo, hi], lo unstable, hi stable: geometric steps of 4 from the device mass.
    std::vector<Case> active;
    double hi = heaviest;
    double lo = 0.0;
    const double lightest = 1e-6 * request.device.mass_kg;
    const AdmittanceExactCheck at_device = full(request.device.mass_kg);
    if (at_device.stable) {
        hi = request.device.mass_kg;
        // The k-th step is the device mass times 4^-k (exact in binary).
        for (int k = 1; std::ldexp(request.device.mass_kg, -2 * k) >= lightest; ++k) {
            const double mass = std::ldexp(request.device.mass_kg, -2 * k);
            const AdmittanceExactCheck c = full(mass);
            if (!c.stable) {
                lo = mass;
                active.push_back({c.worst_operator, c.worst_environment});
                break;
            }
            hi = mass;
        }
        if (lo == 0.0) lo = hi;  // stable down to a millionth of the device mass
    } else {
        lo = request.device.mass_kg;
        active.push_back({at_device.worst_operator, at_device.worst_environment});
        for (int k = 1; std::ldexp(request.device.mass_kg, 2 * k) < heaviest; ++k) {
            const double mass = std::ldexp(request.device.mass_kg, 2 * k);
            const AdmittanceExactCheck c = full(mass);
            if (c.stable) {
                hi = mass;
                break;
            }
            lo = mass;
            active.push_back({c.worst_operator, c.worst_environment});
        }
    }
    const auto active_stable = [&](double mass) {
        for (const Case& c : active) {
            const ClosedLoopPoles p =
                admittance_closed_loop_poles(design_with(mass), c.human, c.environment);
            if (p.spectral_radius > 1.0 + kMarginalTolerance) return false;
        }
        return true;
    };
    while (lo < hi) {
        // Bisect in log(m_c) on the active cases, then confirm on the full sweep.
        double a = lo, b = hi;
        while (b > a * (1.0 + kBisectionTolerance)) {
            const double mid = std::sqrt(a * b);
            (active_stable(mid) ? b : a) = mid;
        }
        const AdmittanceExactCheck c = full(b);
        if (c.stable) {
            hi = b;
            break;
        }
        active.push_back({c.worst_operator, c.worst_environment});
        lo = b;
    }
    result.limit_mass_kg = hi;
    const AdmittanceExactCheck below = full(hi / (1.0 + kBisectionTolerance));
    result.binding_operator = below.worst_operator;
    result.binding_environment = below.worst_environment;
    result.binding_frequency_hz = below.worst_frequency_hz;
    result.coupling = {request.safety_factor * hi, request.coupling_damping_n_s_per_m};
    result.check = full(result.coupling.mass_kg);
    result.report.method = "exact-bisection";
    result.report.verify_points = result.check.cases_checked;
    result.report.ceres_iterations = 0;
    result.report.solver_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

namespace {

bool passive_holds(const PassiveAdmittanceSizingRequest& r, const theory::MassDamperCoupling& c) {
    return theory::check_filtered_admittance_passive(r.device, r.loop, *r.force_filter, c,
                                                     1.0 / r.rate_hz, r.delay_periods,
                                                     /*stop_at_failure=*/true)
        .holds;
}

constexpr double kPassiveTolerance = 1e-4;  // relative, on m_c and b_c

void check_passive_request(const PassiveAdmittanceSizingRequest& r) {
    check_device(r.device);
    check_rate(r.rate_hz);
    check_delay_periods(r.delay_periods);
    check_positive_or_infinite("coupling damping b_c", r.coupling_damping_n_s_per_m, "N s/m");
    if (r.force_filter) theory::check_force_sensor_filter(*r.force_filter, r.rate_hz);
}

}  // namespace

double lightest_passive_damper(const PassiveAdmittanceSizingRequest& r) {
    check_passive_request(r);
    const double inf = std::numeric_limits<double>::infinity();
    if (!r.force_filter || r.force_filter->order != 2) return inf;
    double lo = 1e-3, hi = 1e7;  // N s/m
    if (!passive_holds(r, {inf, hi})) return inf;
    if (passive_holds(r, {inf, lo})) return lo;
    while (hi > lo * (1.0 + kPassiveTolerance)) {
        const double mid = std::sqrt(lo * hi);
        (passive_holds(r, {inf, mid}) ? hi : lo) = mid;
    }
    return hi;
}

PassiveAdmittanceSizing size_admittance_coupling_passive(const PassiveAdmittanceSizingRequest& r) {
    const auto start = std::chrono::steady_clock::now();
    check_passive_request(r);
    const double inf = std::numeric_limits<double>::infinity();
    const double period = 1.0 / r.rate_hz;
    if (!r.force_filter || r.force_filter->order != 2) {
        std::string why =
            passive_admittance_verdict(r.device, r.loop, r.rate_hz, r.delay_periods).explanation;
        if (r.force_filter) {
            why +=
                ". A first-order filter is not enough: its alias weights fall like 1/k, so "
                "Σ|β_k| still diverges (logarithmically); give a second-order one "
                "(--force-filter-order 2)";
        } else {
            why += " (--force-filter HZ: a second-order low-pass makes Σ|β_k| converge)";
        }
        throw InfeasibleCoupling(why);
    }
    // The homotopy from hands-off needs the hands-off loop stable (the PI loop on the device).
    const AdmittanceDesign probe{r.device,  r.loop,          {inf, 1.0},
                                 r.rate_hz, r.delay_periods, r.force_filter};
    const ClosedLoopPoles hands_off = admittance_closed_loop_poles(
        probe, OperatorModel::hands_off(), AdmittanceEnvironment::free_space());
    if (hands_off.spectral_radius > 1.0 + kMarginalTolerance) {
        std::ostringstream why;
        why << "the PI velocity loop is unstable hands-off (|z| = " << hands_off.spectral_radius
            << "): lower k_p, k_i";
        throw InfeasibleCoupling(why.str());
    }
    const double b_c = r.coupling_damping_n_s_per_m;
    PassiveAdmittanceSizing out;
    const auto lightest_damper_text = [&] {
        const double lightest = lightest_passive_damper(r);
        std::ostringstream s;
        if (std::isfinite(lightest)) {
            s << "the lightest pure damper that holds is b_c = " << lightest
              << " N s/m (--coupling-damping " << lightest << ": m_c = inf)";
        } else {
            s << "no pure damper up to 1e7 N s/m holds either";
            const double needed =
                theory::velocity_loop_damping_bound(r.loop, period, r.delay_periods);
            if (r.device.damping_n_s_per_m <= needed) {
                s << " (the PI loop alone needs b >= " << needed << " N s/m at a rigid wall)";
            }
        }
        return s.str();
    };
    const std::string holds_for = r.force_filter->describe();
    if (std::isinf(b_c)) {
        // A pure mass: the DC law (theory filtered_alias_slope) or the grid decides.
        const double heaviest = kHeaviestCouplingPerDeviceMass * r.device.mass_kg;
        if (!passive_holds(r, {heaviest, inf})) {
            std::ostringstream why;
            why << "no pure-mass coupling up to " << heaviest
                << " kg holds for every passive operator and environment with the " << holds_for
                << ": a virtual spring resonating with m_c at low frequency (where the "
                   "coupling's implicit Euler barely dissipates, Re Z_cA ~ m_c θ²/(2T)) meets "
                   "the force sample's aliases near multiples of the servo rate, a negative "
                   "resistance ~ θ (docs/stability-models.md); "
                << lightest_damper_text();
            throw InfeasibleCoupling(why.str());
        }
    } else if (!passive_holds(r, {inf, b_c})) {
        std::ostringstream why;
        why << "with b_c = " << b_c
            << " N s/m no coupling mass holds for every passive operator and environment with "
               "the "
            << holds_for << " (not even m_c = inf); " << lightest_damper_text();
        throw InfeasibleCoupling(why.str());
    }
    // Bisection on log m_c between the heaviest (holds, or the pure damper) and the lightest.
    double hi = kHeaviestCouplingPerDeviceMass * r.device.mass_kg;
    if (!passive_holds(r, {hi, b_c})) hi = inf;
    if (std::isfinite(hi)) {
        double lo = 1e-6 * r.device.mass_kg;
        if (passive_holds(r, {lo, b_c})) {
            hi = lo;
        } else {
            while (hi > lo * (1.0 + kPassiveTolerance)) {
                const double mid = std::sqrt(lo * hi);
                (passive_holds(r, {mid, b_c}) ? hi : lo) = mid;
            }
        }
    }
    out.coupling = {hi, b_c};
    out.finite_mass_fails_at_dc = std::isinf(hi);
    // The binding case: the full check just below the answer (for m_c = inf, just below b_c).
    const theory::MassDamperCoupling below =
        std::isfinite(hi) ? theory::MassDamperCoupling{hi / (1.0 + kPassiveTolerance), b_c}
                          : theory::MassDamperCoupling{inf, b_c};
    const theory::FilteredPassiveCheck at = theory::check_filtered_admittance_passive(
        r.device, r.loop, *r.force_filter, below, period, r.delay_periods);
    out.binding_frequency_hz = at.worst_frequency_hz;
    out.binding_admittance = at.worst_admittance;
    out.worst_margin = at.worst_margin;
    {
        const double theta = theory::normalized_frequency(at.worst_frequency_hz, period);
        std::ostringstream env;
        if (std::abs(at.worst_admittance) < 1e-12) {
            env << "rigid wall";
        } else {
            const theory::Complex z_e =
                1.0 / at.worst_admittance -
                1.0 / theory::coupling_admittance(out.coupling, theta, period);
            env << "Z_e = " << z_e.real() << (z_e.imag() < 0 ? " - " : " + ")
                << std::abs(z_e.imag()) << "j N s/m at " << at.worst_frequency_hz << " Hz";
            if (std::abs(z_e) < 1e-6 * std::abs(1.0 / at.worst_admittance)) env << " (free space)";
        }
        out.binding_environment = env.str();
    }
    out.exact = check_exact_admittance(
        {r.device, r.loop, out.coupling, r.rate_hz, r.delay_periods, r.force_filter});
    out.report.method = "passive-filtered-bisection";
    out.report.verify_points = at.frequencies;
    out.report.solver_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

}  // namespace hapticd::tune
