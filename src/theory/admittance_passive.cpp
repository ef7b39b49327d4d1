#include "hapticd/theory/admittance_passive.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <queue>
#include <stdexcept>
#include <vector>

#include "hapticd/theory/passive_model.hpp"

namespace hapticd::theory {

double velocity_loop_damping_needed(const PiVelocityLoop& loop, double theta,
                                    double sample_period_s, double delay_periods) {
    return port_damping_needed(pi_gain(loop, theta, sample_period_s), theta, delay_periods);
}

double velocity_loop_damping_bound(const PiVelocityLoop& loop, double sample_period_s,
                                   double delay_periods) {
    const LoopDelay d = split_delay(delay_periods);
    if (d.whole_periods == 0 && d.fraction == 0.0) {
        // Re ζ = -k_p cos θ + k_i T/2 (Re(-e^{-jθ}/(1 - e^{-jθ})) = 1/2): largest at Nyquist.
        return loop.proportional_gain_n_s_per_m +
               loop.integral_gain_n_per_m * sample_period_s / 2.0;
    }
    constexpr int kPoints = 4096;
    double worst = 0.0;
    for (int i = 1; i <= kPoints; ++i) {
        const double theta = std::numbers::pi * i / kPoints;
        worst = std::max(worst,
                         velocity_loop_damping_needed(loop, theta, sample_period_s, delay_periods));
    }
    return worst;
}

AliasReach free_space_alias_reach(const DeviceModel& device, const PiVelocityLoop& loop,
                                  const MassDamperCoupling& coupling, double theta,
                                  double sample_period_s, int whole_periods) {
    const double t = sample_period_s;
    const double m = device.mass_kg, b = device.damping_n_s_per_m;
    const Complex z_inv = std::polar(1.0, -theta);
    const Complex delay = std::polar(1.0, -whole_periods * theta);
    const Complex k_pi = pi_gain(loop, theta, t);
    const Complex y_v = coupling_admittance(coupling, theta, t);  // free space: Y_v = Y_cA
    const Complex g = k_pi * y_v * delay;
    const Complex c_h = (1.0 + z_inv) / 2.0;  // μ = 0
    const Complex r = 1.0 + g * c_h;
    const Complex beta_inf = g * (1.0 - z_inv) * (m / t);
    const Complex direction = beta_inf / std::abs(beta_inf);
    const double half_sine = std::sin(theta / 2.0);
    // δ = Σ_k (|β_k| - Re(conj(β̂_∞) β_k)): its terms fall like 1/k², so 2·10^4 + 1 of them
    // leave a relative 1e-4 of it. A resonant alias (u_k = 1/b) moves Σ β_k u_k by
    // Re(conj(β̂_∞) β_k)/b along β̂_∞; the fewest that reach R take the largest first.
    constexpr int kTerms = 10000;
    double defect = 0.0;
    std::vector<double> along_each;
    along_each.reserve(2 * kTerms + 1);
    for (int k = -kTerms; k <= kTerms; ++k) {
        const double theta_k = theta + 2.0 * std::numbers::pi * k;
        const double s_k = 4.0 * half_sine * half_sine / (theta_k * theta_k);
        const Complex beta =
            k_pi * delay *
            (y_v * (1.0 - z_inv) * (m / t + b / Complex(0.0, theta_k)) - z_inv * s_k);
        const double projection = (std::conj(direction) * beta).real();
        defect += std::abs(beta) - projection;
        along_each.push_back(projection);
    }
    const double along = (std::conj(direction) * r).real();
    AliasReach out;
    out.reach = along + defect / (2.0 * b);
    if (along > 0.0) {
        // The largest first, off a heap: the count is small next to the terms.
        std::make_heap(along_each.begin(), along_each.end());
        double sum = 0.0;
        std::size_t n = 0;
        for (auto end = along_each.end(); end != along_each.begin() && sum < b * along; --end) {
            std::pop_heap(along_each.begin(), end);
            sum += *(end - 1);
            ++n;
        }
        out.resonant_aliases_needed = static_cast<double>(n);
    }
    return out;
}

EnvironmentAdmittanceDisk environment_admittance_disk(const MassDamperCoupling& coupling,
                                                      double theta, double sample_period_s) {
    // Y_v = 1/(Z_cA + Z_e), Re Z_e >= 0: 1/v over Re v >= a = Re Z_cA is |Y - 1/(2a)| <= 1/(2a).
    const double resistance = (1.0 / coupling_admittance(coupling, theta, sample_period_s)).real();
    const double half = 1.0 / (2.0 * resistance);
    return {half, half};
}

namespace {

/// The affine pieces at θ: f(Y) = |α Y + γ| - Σ_k |A_k Y + B_k|/(2b), β_k = A_k Y + B_k, and
/// the tails beyond |k| = N: Σ_{|k|>N} |β_k| <= |Y| tail_a + tail_b.
struct AliasTerms {
    Complex alpha, gamma;
    std::vector<Complex> a, b;
    double sum_abs_a = 0.0;  ///< Σ |A_k| (the Lipschitz part of ρ)
    double tail_a = 0.0, tail_b = 0.0;
    double two_b = 0.0;
};

int alias_terms_for(const ForceSensorFilter& filter, double sample_period_s) {
    // Enough aliases that the tail bound applies (ω_N >= 2 ω_a) and is small.
    const double per_rate = filter.cutoff_hz * sample_period_s;
    return std::max(64, static_cast<int>(std::ceil(4.0 * per_rate)) + 2);
}

AliasTerms alias_terms(const DeviceModel& device, const PiVelocityLoop& loop,
                       const ForceSensorFilter& filter, double theta, double t,
                       double delay_periods) {
    if (filter.order != 2 && filter.order != 1) {
        throw std::invalid_argument("force-sensor filter order must be 1 or 2");
    }
    const LoopDelay d = split_delay(delay_periods);
    const double m = device.mass_kg, b = device.damping_n_s_per_m;
    const Complex z_inv = std::polar(1.0, -theta);
    const Complex k_pi = pi_gain(loop, theta, t) * std::polar(1.0, -d.whole_periods * theta);
    const double half_sine = std::sin(theta / 2.0);
    const int n = alias_terms_for(filter, t);
    AliasTerms out;
    out.two_b = 2.0 * b;
    out.a.reserve(2 * n + 1);
    out.b.reserve(2 * n + 1);
    Complex sum_a = 0.0, sum_b = 0.0;
    double sum_s = 0.0;
    for (int k = -n; k <= n; ++k) {
        const double theta_k = theta + 2.0 * std::numbers::pi * k;
        const Complex shift = std::polar(1.0, -theta_k * d.fraction);  // e_k
        const double s_k = 4.0 * half_sine * half_sine / (theta_k * theta_k);
        const Complex h_k = force_filter_response(filter, theta_k / t);
        const Complex a_k =
            k_pi * shift * (1.0 - z_inv) * h_k * (m / t + b / Complex(0.0, theta_k));
        const Complex b_k = -k_pi * shift * z_inv * s_k;
        out.a.push_back(a_k);
        out.b.push_back(b_k);
        out.sum_abs_a += magnitude(a_k);
        sum_a += a_k;
        sum_b += b_k;
        sum_s += s_k;
    }
    const Complex hold = force_filter_hold_equivalent(filter, theta, t, d.fraction);
    out.alpha = k_pi * hold - sum_a / out.two_b;
    out.gamma = 1.0 - sum_b / out.two_b;
    const FilterAliasTail tail = force_filter_alias_tail(filter, t, n);
    out.tail_a = std::abs(k_pi) * std::abs(1.0 - z_inv) *
                 ((m / t) * tail.response + b * tail.response_per_alias);
    // Σ_k s_k = 1 exactly: the encoder's tail is what the first N leave (and its rounding).
    out.tail_b = std::abs(k_pi) * (std::max(0.0, 1.0 - sum_s) + 1e-15 * (2 * n + 1));
    return out;
}

/// ρ(Y) without the tails: Σ_k |A_k Y + B_k|.
double alias_sum(const AliasTerms& terms, Complex y) {
    double rho = 0.0;
    for (std::size_t i = 0; i < terms.a.size(); ++i) rho += magnitude(terms.a[i] * y + terms.b[i]);
    return rho;
}

double value_at(const AliasTerms& terms, Complex y) {
    return magnitude(terms.alpha * y + terms.gamma) - alias_sum(terms, y) / terms.two_b;
}

/// Twice the tails' ρ at |Y| <= y (|R - c| loses one, ρ gains one).
double tail_allowance(const AliasTerms& terms, double y) {
    return 2.0 * (y * terms.tail_a + terms.tail_b) / terms.two_b;
}

}  // namespace

FilteredAliasMargin filtered_alias_margin(const DeviceModel& device, const PiVelocityLoop& loop,
                                          const ForceSensorFilter& filter,
                                          const EnvironmentAdmittanceDisk& disk, double theta,
                                          double sample_period_s, double delay_periods,
                                          bool decide_only, double tolerance, int max_evaluations) {
    const AliasTerms terms =
        alias_terms(device, loop, filter, theta, sample_period_s, delay_periods);
    FilteredAliasMargin out;
    if (!std::isfinite(terms.tail_a)) {  // first order: ρ = ∞
        out.margin = out.value_at_worst = -std::numeric_limits<double>::infinity();
        out.worst_admittance = disk.centre;
        return out;
    }
    // Branch and bound on squares (centre, half-side h) covering the disk.
    struct Box {
        double x, y, h, bound;
        bool operator>(const Box& o) const { return bound > o.bound; }
    };
    const double lipschitz_fit = std::abs(terms.alpha);
    const auto lower_bound = [&](double x, double y, double h) {
        const Complex centre(x, y);
        const double r = h * std::numbers::sqrt2;
        const double fit =
            std::max(0.0, magnitude(terms.alpha * centre + terms.gamma) - lipschitz_fit * r);
        const double rho = alias_sum(terms, centre) + terms.sum_abs_a * r;
        return fit - rho / terms.two_b - tail_allowance(terms, std::abs(centre) + r);
    };
    const auto in_disk = [&](double x, double y) {
        // The point of the disk nearest (x, y).
        const Complex p(x - disk.centre, y);
        const double d = std::abs(p);
        if (d <= disk.radius) return Complex(x, y);
        return Complex(disk.centre) + p * (disk.radius / d);
    };
    const auto meets_disk = [&](double x, double y, double h) {
        const double dx = std::max(0.0, std::abs(x - disk.centre) - h);
        const double dy = std::max(0.0, std::abs(y) - h);
        return dx * dx + dy * dy <= disk.radius * disk.radius;
    };
    std::priority_queue<Box, std::vector<Box>, std::greater<Box>> boxes;
    double best = std::numeric_limits<double>::infinity();
    Complex best_at = disk.centre;
    const auto visit = [&](double x, double y, double h) {
        if (!meets_disk(x, y, h)) return;
        const Complex p = in_disk(x, y);
        const double v = value_at(terms, p);
        ++out.evaluations;
        if (v < best) best = v, best_at = p;
        boxes.push({x, y, h, lower_bound(x, y, h)});
    };
    // The disk's ends on the real axis first (the rigid wall 0 and the far point, where a
    // lossless environment cancels the coupling's reactance): the usual binding points.
    for (const Complex y :
         {Complex(disk.centre - disk.radius), Complex(disk.centre + disk.radius)}) {
        const double v = value_at(terms, y);
        ++out.evaluations;
        if (v < best) best = v, best_at = y;
    }
    visit(disk.centre, 0.0, disk.radius);
    double certified = -std::numeric_limits<double>::infinity();
    while (!boxes.empty()) {
        const Box top = boxes.top();
        certified = top.bound;
        if (decide_only) {
            if (top.bound > 0.0) break;
            if (best + tail_allowance(terms, std::abs(best_at)) <= 0.0) break;
        } else if (top.bound >= best - tolerance) {
            break;
        }
        if (out.evaluations >= max_evaluations || top.h < 1e-12 * disk.radius) break;
        boxes.pop();
        const double q = top.h / 2.0;
        for (const double dx : {-q, q}) {
            for (const double dy : {-q, q}) visit(top.x + dx, top.y + dy, q);
        }
        if (boxes.empty()) certified = best;
    }
    out.margin = std::min(certified, best);
    out.value_at_worst = best;
    out.worst_admittance = best_at;
    return out;
}

double filtered_alias_slope(const DeviceModel& device, const PiVelocityLoop& loop,
                            const ForceSensorFilter& filter, double theta, double sample_period_s,
                            double delay_periods) {
    const AliasTerms terms =
        alias_terms(device, loop, filter, theta, sample_period_s, delay_periods);
    return std::abs(terms.alpha) - (terms.sum_abs_a + terms.tail_a) / terms.two_b;
}

FilteredPassiveCheck check_filtered_admittance_passive(const DeviceModel& device,
                                                       const PiVelocityLoop& loop,
                                                       const ForceSensorFilter& filter,
                                                       const MassDamperCoupling& coupling,
                                                       double sample_period_s, double delay_periods,
                                                       bool stop_at_failure) {
    FilteredPassiveCheck out;
    out.worst_margin = std::numeric_limits<double>::infinity();
    double worst_theta = 0.0;
    const auto at = [&](double theta, double tolerance = 1e-4, int evaluations = 400) {
        const FilteredAliasMargin r = filtered_alias_margin(
            device, loop, filter, environment_admittance_disk(coupling, theta, sample_period_s),
            theta, sample_period_s, delay_periods, /*decide_only=*/stop_at_failure, tolerance,
            stop_at_failure ? 20000 : evaluations);
        ++out.frequencies;
        if (r.margin < out.worst_margin) {
            out.worst_margin = r.margin;
            out.worst_frequency_hz = frequency_hz(theta, sample_period_s);
            out.worst_admittance = r.worst_admittance;
            worst_theta = theta;
        }
        return r.margin;
    };
    // DC: with a finite coupling mass the disk's radius grows like 1/θ², so a negative slope
    // there fails at some frequency below the grid (filtered_alias_slope).
    constexpr double kDcTheta = 1e-6;
    if (std::isfinite(coupling.mass_kg) &&
        filtered_alias_slope(device, loop, filter, kDcTheta, sample_period_s, delay_periods) <
            0.0) {
        out.fails_at_dc = true;
        if (stop_at_failure) {
            out.worst_margin = -std::numeric_limits<double>::infinity();
            out.worst_frequency_hz = frequency_hz(0.0, sample_period_s);
            return out;
        }
    }
    constexpr int kUniform = 4096, kLow = 256, kRefine = 64;
    std::vector<double> thetas;
    thetas.reserve(kLow + kUniform);
    const double first = std::numbers::pi / kUniform;
    for (int i = 0; i < kLow; ++i)
        thetas.push_back(kDcTheta * std::pow(first / kDcTheta, double(i) / kLow));
    for (int i = 1; i <= kUniform; ++i) thetas.push_back(std::numbers::pi * i / kUniform);
    std::size_t worst = 0;
    double worst_margin = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < thetas.size(); ++i) {
        const double m = at(thetas[i]);
        if (m < worst_margin) worst_margin = m, worst = i;
        if (stop_at_failure && m <= 0.0) break;
    }
    if (!(stop_at_failure && worst_margin <= 0.0)) {
        const double lo = thetas[worst == 0 ? 0 : worst - 1];
        const double hi = thetas[std::min(worst + 1, thetas.size() - 1)];
        for (int i = 1; i < kRefine; ++i) {
            const double m = at(lo + (hi - lo) * i / kRefine);
            if (stop_at_failure && m <= 0.0) break;
        }
        if (!stop_at_failure) {
            // The worst once more, tightly.
            out.worst_margin = std::numeric_limits<double>::infinity();
            at(worst_theta, 1e-7, 20000);
        }
    }
    out.holds = out.worst_margin > 0.0 && !out.fails_at_dc;
    return out;
}

}  // namespace hapticd::theory
