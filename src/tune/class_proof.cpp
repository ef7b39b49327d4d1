#include "hapticd/tune/class_proof.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "hapticd/theory/passive_model.hpp"
#include "hapticd/theory/velocity_filter.hpp"
#include "hapticd/tune/input_checks.hpp"

namespace hapticd::tune {

using theory::DeviceModel;
using theory::SpringDamperCoupling;

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInfinity = std::numeric_limits<double>::infinity();
/// Aliases bounded one by one; the rest by the passive disk, -1/(π² (K - 1/2) b) in all.
constexpr int kAliases = 50;
/// The partition of [0, π]: [0, kLowestTheta], geometric steps of kGeometricRatio up to
/// kUniformFrom, then steps of kUniformStep; halvings down to kNarrowest.
constexpr double kLowestTheta = 1e-5;
constexpr double kGeometricRatio = 1.02;
constexpr double kUniformFrom = 0.05;
constexpr double kUniformStep = 1e-3;
constexpr double kNarrowest = 1e-9;
constexpr int kMaxHalvings = 24;
/// Bounds past this are treated as infinite (their squares stay finite).
constexpr double kHuge = 1e150;

struct Range {
    double lo = 0.0;
    double hi = 0.0;
    bool contains(double x) const { return lo <= x && x <= hi; }
};

Range operator+(Range a, Range b) { return {a.lo + b.lo, a.hi + b.hi}; }

/// A rectangle of the complex plane: Re in re, Im in im.
struct Rectangle {
    Range re;
    Range im;
};

double clamp_huge(double x) { return std::clamp(x, -kHuge, kHuge); }

/// The exact ranges of Re(1/z) and Im(1/z) over z in `z`, whose real part is >= 0 (a passive
/// immittance). u = x/(x² + y²) and v = -y/(x² + y²) are harmonic, so their extremes lie on
/// the edges: at the corners, at y = 0 and y = ±x on a vertical edge, at x = |y| on a
/// horizontal one. A rectangle that holds 0 has an unbounded reciprocal.
Rectangle reciprocal(const Rectangle& z) {
    if (z.re.lo <= 0.0 && z.im.contains(0.0)) return {{0.0, kInfinity}, {-kInfinity, kInfinity}};
    const double x[2] = {clamp_huge(z.re.lo), clamp_huge(z.re.hi)};
    const double y[2] = {clamp_huge(z.im.lo), clamp_huge(z.im.hi)};
    Rectangle out{{kInfinity, -kInfinity}, {kInfinity, -kInfinity}};
    const auto take = [&](double px, double py) {
        const double r2 = px * px + py * py;
        const double u = r2 > 0.0 ? px / r2 : 0.0;
        const double v = r2 > 0.0 ? -py / r2 : 0.0;
        out.re = {std::min(out.re.lo, u), std::max(out.re.hi, u)};
        out.im = {std::min(out.im.lo, v), std::max(out.im.hi, v)};
    };
    const Range xr{x[0], x[1]}, yr{y[0], y[1]};
    for (const double px : x) {
        for (const double py : y) take(px, py);
        if (yr.contains(0.0)) take(px, 0.0);
        if (yr.contains(px)) take(px, px);
        if (yr.contains(-px)) take(px, -px);
    }
    for (const double py : y) {
        if (xr.contains(std::abs(py))) take(std::abs(py), py);
    }
    return out;
}

/// An interval holding Im Z_h(jω) of every member of the class, and of hands-off (0), for
/// ω in `omega` (rad/s, > 0): step 1 of the file comment.
Range operator_reactance(const OperatorClass& c, Range omega) {
    const Rectangle grip{
        {c.grip_damping_n_s_per_m.min, c.grip_damping_n_s_per_m.max},
        {-c.grip_stiffness_n_per_m.max / omega.lo, -c.grip_stiffness_n_per_m.min / omega.hi}};
    const Rectangle hand{{c.arm_damping_n_s_per_m.min, c.arm_damping_n_s_per_m.max},
                         {c.hand_mass_kg.min * omega.lo - c.arm_stiffness_n_per_m.max / omega.lo,
                          c.hand_mass_kg.max * omega.hi - c.arm_stiffness_n_per_m.min / omega.hi}};
    const Rectangle grip_admittance = reciprocal(grip);
    const Rectangle hand_admittance = reciprocal(hand);
    const Rectangle admittance{grip_admittance.re + hand_admittance.re,
                               grip_admittance.im + hand_admittance.im};
    const Rectangle impedance = reciprocal(admittance);
    return {std::min(impedance.im.lo, 0.0), std::max(impedance.im.hi, 0.0)};
}

/// The real roots of A x² + B x + C (none when it is constant).
int quadratic_roots(double a, double b, double c, double (&roots)[2]) {
    if (a == 0.0) {
        if (b == 0.0) return 0;
        roots[0] = -c / b;
        return 1;
    }
    const double discriminant = b * b - 4.0 * a * c;
    if (discriminant < 0.0) return 0;
    const double q = -0.5 * (b + std::copysign(std::sqrt(discriminant), b));
    if (q == 0.0) {
        roots[0] = 0.0;
        return 1;
    }
    roots[0] = q / a;
    roots[1] = c / q;
    return 2;
}

/// min over W = r + jX, r >= damping, X in `reactance` (bounds may be infinite) of
/// Re(e^{-ja}/W) = (r cos a - X sin a)/(r² + X²): harmonic, so on the strip's edges, where
/// the derivative along the edge is a quadratic's root; 0 as r -> inf.
double strip_minimum(double a, double damping, Range reactance) {
    const double c = std::cos(a), s = std::sin(a);
    double least = 0.0;
    const auto take = [&](double r, double x) {
        if (std::isfinite(r) && std::isfinite(x)) {
            least = std::min(least, (r * c - x * s) / (r * r + x * x));
        }
    };
    double roots[2];
    // r = damping: s X² - 2 r c X - s r² = 0.
    take(damping, reactance.lo);
    take(damping, reactance.hi);
    for (int i = 0, n = quadratic_roots(s, -2.0 * damping * c, -s * damping * damping, roots);
         i < n; ++i) {
        if (reactance.contains(roots[i])) take(damping, roots[i]);
    }
    // X fixed, r >= damping: -c r² + 2 X s r + c X² = 0.
    for (const double x : {reactance.lo, reactance.hi}) {
        if (!std::isfinite(x)) continue;
        for (int i = 0, n = quadratic_roots(-c, 2.0 * x * s, c * x * x, roots); i < n; ++i) {
            if (roots[i] >= damping) take(roots[i], x);
        }
    }
    return least;
}

/// Whether cos a < 0 somewhere in [lo, hi].
bool cosine_negative_within(double lo, double hi) {
    if (hi - lo >= kPi || std::cos(lo) < 0.0 || std::cos(hi) < 0.0) return true;
    // cos is negative around π + 2πn; is such a point inside?
    return std::floor((hi - kPi) / (2.0 * kPi)) >= std::ceil((lo - kPi) / (2.0 * kPi));
}

/// The distance from 0 to an interval.
double distance_from_zero(Range r) {
    if (r.contains(0.0)) return 0.0;
    return std::min(std::abs(r.lo), std::abs(r.hi));
}

/// F_n(θ) = sin²(nθ/2)/sin²(θ/2), n² at θ = 0.
double fejer(int n, double theta) {
    const double s = std::sin(theta / 2.0);
    if (s == 0.0) return static_cast<double>(n) * n;
    const double r = std::sin(n * theta / 2.0) / s;
    return r * r;
}

}  // namespace

ClassProver::ClassProver(const DeviceModel& device, const OperatorClass& operators, double rate_hz,
                         double delay_periods)
    : device_(device), operators_(operators) {
    check_device(device);
    check_rate(rate_hz);
    check_delay_periods(delay_periods);
    period_s_ = 1.0 / rate_hz;
    const theory::LoopDelay delay = theory::split_delay(delay_periods);
    whole_periods_ = delay.whole_periods;
    fraction_ = delay.fraction;
    std::vector<double> edges = {0.0, kLowestTheta};
    while (edges.back() * kGeometricRatio < kUniformFrom) {
        edges.push_back(edges.back() * kGeometricRatio);
    }
    const int uniform = static_cast<int>(std::ceil((kPi - edges.back()) / kUniformStep));
    const double from = edges.back(), step = (kPi - from) / uniform;
    for (int i = 1; i < uniform; ++i) edges.push_back(from + i * step);
    edges.push_back(kPi);
    partition_.reserve(edges.size() - 1);
    for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
        partition_.push_back({edges[i], edges[i + 1], alias_bound(edges[i], edges[i + 1])});
    }
}

double ClassProver::alias_bound(double lo, double hi) const {
    return std::max(class_alias_bound(lo, hi), passive_alias_bound(lo, hi));
}

/// Steps 1-3 of the file comment: a lower bound on Σ_k (2/o_k²) Re(e^{-j a_k} Y(jω_k)) over
/// θ in [lo, hi] and every member.
double ClassProver::class_alias_bound(double lo, double hi) const {
    if (lo <= 0.0) return -kInfinity;  // the k = 0 weight is unbounded: the passive bound only
    const double m = device_.mass_kg, b = device_.damping_n_s_per_m;
    const double slope = 1.0 + whole_periods_ + fraction_;  // da/dθ
    double sum = 0.0;
    for (int k = -kAliases; k <= kAliases; ++k) {
        const double o_lo = lo + 2.0 * kPi * k, o_hi = hi + 2.0 * kPi * k;
        const double o_near = std::min(std::abs(o_lo), std::abs(o_hi));
        const double o_far = std::max(std::abs(o_lo), std::abs(o_hi));
        const Range omega{o_near / period_s_, o_far / period_s_};
        const Range x = operator_reactance(operators_, omega);
        Range reactance{m * omega.lo + x.lo, m * omega.hi + x.hi};
        // Y(-jω) is the conjugate of Y(jω): the strip of W mirrored.
        if (o_lo < 0.0) reactance = {-reactance.hi, -reactance.lo};
        const double a_lo = slope * lo + 2.0 * kPi * fraction_ * k;
        const double a_hi = slope * hi + 2.0 * kPi * fraction_ * k;
        double least =
            std::min(strip_minimum(a_lo, b, reactance), strip_minimum(a_hi, b, reactance));
        if (cosine_negative_within(a_lo, a_hi)) {
            // -|Y| at worst, |Y| <= 1/|W| <= 1/dist(0, strip).
            least = std::min(least, -1.0 / std::hypot(b, distance_from_zero(reactance)));
        }
        sum += least * 2.0 / (least < 0.0 ? o_near * o_near : o_far * o_far);
    }
    return sum - 1.0 / (kPi * kPi * (kAliases - 0.5) * b);
}

/// Step 4: the passive condition, -M(θ)/(4b sin²(θ/2)) = -((1-φ) F_{1+q} + φ F_{2+q})/(2b),
/// bounded over [lo, hi] by its ends and |F_n'| <= (n³ - n)/3.
double ClassProver::passive_alias_bound(double lo, double hi) const {
    const double b = device_.damping_n_s_per_m, phi = fraction_;
    const int n1 = 1 + whole_periods_, n2 = 2 + whole_periods_;
    const auto h = [&](double theta) {
        return ((1.0 - phi) * fejer(n1, theta) + phi * fejer(n2, theta)) / (2.0 * b);
    };
    const double slope =
        ((1.0 - phi) * (n1 * n1 * n1 - n1) + phi * (n2 * n2 * n2 - n2)) / (3.0 * 2.0 * b);
    return -(std::max(h(lo), h(hi)) + slope * (hi - lo) / 2.0);
}

namespace {

/// Step 5: a lower bound on Re(1/Z_c)/(2 sin²(θ/2)) over θ in [lo, hi] (within [0, π]).
double coupling_bound(const SpringDamperCoupling& coupling, double period_s, double lo, double hi) {
    const double half_kt = coupling.stiffness_n_per_m * period_s / 2.0;
    const double bc = coupling.damping_n_s_per_m;
    const Range s{std::sin(lo / 2.0), std::sin(hi / 2.0)};  // increasing on [0, π/2]
    const Range c{std::cos(hi / 2.0), std::cos(lo / 2.0)};
    Range re_b{1.0, 1.0}, minus_im_b{0.0, 0.0};
    if (coupling.velocity_filter_hz > 0.0) {
        // B = (1-a)((1-a) + 2a h2)/((1-a)² + 4a h2) - j (1-a) a sin θ/((1-a)² + 4a h2),
        // h2 = sin²(θ/2): Re B is monotone in h2 (a ratio of linear functions).
        const double a = theory::velocity_filter_pole(coupling.velocity_filter_hz, period_s);
        const auto denominator = [&](double h2) { return (1.0 - a) * (1.0 - a) + 4.0 * a * h2; };
        const auto re = [&](double h2) {
            return (1.0 - a) * ((1.0 - a) + 2.0 * a * h2) / denominator(h2);
        };
        const double h2_lo = s.lo * s.lo, h2_hi = s.hi * s.hi;
        re_b = {std::min(re(h2_lo), re(h2_hi)), std::max(re(h2_lo), re(h2_hi))};
        const Range sine{
            std::min(std::sin(lo), std::sin(hi)),
            (lo <= kPi / 2.0 && kPi / 2.0 <= hi) ? 1.0 : std::max(std::sin(lo), std::sin(hi))};
        minus_im_b = {(1.0 - a) * a * sine.lo / denominator(h2_hi),
                      (1.0 - a) * a * sine.hi / denominator(h2_lo)};
    }
    const Range resistance{bc * re_b.lo + half_kt, bc * re_b.hi + half_kt};
    const Range reactance{half_kt * c.lo + bc * minus_im_b.lo * s.lo,
                          half_kt * c.hi + bc * minus_im_b.hi * s.hi};
    const double denominator =
        2.0 * resistance.hi * resistance.hi * s.hi * s.hi + 2.0 * reactance.hi * reactance.hi;
    if (denominator <= 0.0) return kInfinity;  // no coupling at all
    return resistance.lo / denominator;
}

}  // namespace

double ClassProver::interval_margin(const SpringDamperCoupling& coupling, double lo, double hi,
                                    double alias_bound) const {
    return (coupling_bound(coupling, period_s_, lo, hi) + alias_bound) * 2.0 *
           device_.damping_n_s_per_m;
}

double ClassProver::frequency_hz(const Interval& interval) const {
    return (interval.lo + interval.hi) / 2.0 / (2.0 * kPi * period_s_);
}

bool ClassProver::prove_interval(const SpringDamperCoupling& coupling, double lo, double hi,
                                 double bound, int depth, ClassProof& worst) const {
    const double margin = interval_margin(coupling, lo, hi, bound);
    if (margin > 0.0 || depth >= kMaxHalvings || hi - lo <= kNarrowest) {
        if (margin < worst.worst_margin) {
            worst.worst_margin = margin;
            worst.worst_frequency_hz = frequency_hz({lo, hi, bound});
        }
        return margin > 0.0;
    }
    const double mid = (lo + hi) / 2.0;
    return prove_interval(coupling, lo, mid, alias_bound(lo, mid), depth + 1, worst) &&
           prove_interval(coupling, mid, hi, alias_bound(mid, hi), depth + 1, worst);
}

ClassProof ClassProver::prove(const SpringDamperCoupling& coupling) const {
    check_coupling_gains(coupling);
    ClassProof proof;
    proof.worst_margin = kInfinity;
    proof.holds = true;
    for (const Interval& interval : partition_) {
        if (!prove_interval(coupling, interval.lo, interval.hi, interval.alias_bound, 0, proof)) {
            proof.holds = false;
            break;
        }
    }
    if (!proof.holds) {
        // Where it fails, the least of the partition's own bounds: how far below 0 it goes,
        // not the edge of the failing band that the halving stopped at.
        for (const Interval& interval : partition_) {
            const double margin =
                interval_margin(coupling, interval.lo, interval.hi, interval.alias_bound);
            if (margin < proof.worst_margin) {
                proof.worst_margin = margin;
                proof.worst_frequency_hz = frequency_hz(interval);
            }
        }
    }
    return proof;
}

ClassProver::Limit ClassProver::stiffness_limit(const SpringDamperCoupling& shape,
                                                double known_n_per_m) const {
    Limit limit;
    const auto proven = [&](double k) {
        ++limit.proofs;
        SpringDamperCoupling trial = shape;
        trial.stiffness_n_per_m = k;
        return prove(trial).holds;
    };
    double lo = known_n_per_m;
    double hi = std::max(2.0 * lo, 2.0 * device_.damping_n_s_per_m / period_s_);
    if (lo == 0.0 && !proven(0.0)) return limit;
    while (proven(hi)) {
        lo = hi;
        if (hi >= kMaxCouplingStiffness) {
            limit.stiffness_n_per_m = limit.rejected_n_per_m = kMaxCouplingStiffness;
            return limit;
        }
        hi = std::min(2.0 * hi, kMaxCouplingStiffness);
    }
    while (hi - lo > 1e-4 * hi) (proven(0.5 * (lo + hi)) ? lo : hi) = 0.5 * (lo + hi);
    limit.stiffness_n_per_m = lo;
    limit.rejected_n_per_m = hi;
    return limit;
}

}  // namespace hapticd::tune
