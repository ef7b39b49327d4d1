// The `exact` stability model, held against closed forms derived by hand, an independent
// time-domain simulation of the servo tick, and the known bounds of Colgate & Schenkel
// and of the paper's (21).
#include "hapticd/tune/exact_model.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <functional>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "hapticd/theory/coupling_check.hpp"
#include "hapticd/tune/operator_synthesis.hpp"

namespace hapticd::tune {
namespace {

using theory::DeviceModel;
using theory::SpringDamperCoupling;
using Complex = std::complex<double>;
constexpr double kPi = std::numbers::pi;

// The typical device of the brief: m = 0.1 kg, b = 2 N s/m, 1 kHz.
const DeviceModel kDevice{0.1, 2.0};
constexpr double kRateHz = 1000.0;
constexpr double kPeriodS = 1.0 / kRateHz;
const double kColgateStiffness = 2.0 * kDevice.damping_n_s_per_m / kPeriodS;  // 2b/T = 4000

double radius(const SpringDamperCoupling& c, const OperatorModel& h, const EnvironmentModel& e) {
    return closed_loop_poles(kDevice, c, kRateHz, h, e).spectral_radius;
}

/// Largest x in [lo, hi] with stable(x), for a stable(x) that holds below one threshold.
double bisect(double lo, double hi, const std::function<bool(double)>& stable) {
    while (hi - lo > 1e-9 * hi) {
        const double mid = 0.5 * (lo + hi);
        (stable(mid) ? lo : hi) = mid;
    }
    return lo;
}

/// The Nyquist-tuned steel grip: a spring to ground that makes the handle resonate at π/T.
OperatorModel nyquist_grip() {
    const double omega = kPi / kPeriodS;
    return OperatorModel::stiff_grasp(0.0, kDevice.mass_kg * omega * omega, 0.0);
}

// ---- Closed forms ----------------------------------------------------------------------

// Hands-off device, b_c = 0, rigid wall. With a = b/m and E = e^{-aT}, the ZOH equivalent
// of x/F_d = -1/(s (m s + b)) is (standard table for 1/(s(s+a)), times -1/m)
//   P(z) = -[(aT - 1 + E) z + (1 - E - aT E)] / (m a² (z - 1)(z - E)),
// and F = k_c x closes the loop: 1 - P(z) k_c = 0, i.e.
//   (z - 1)(z - E) + (k_c/(m a²)) [(aT - 1 + E) z + (1 - E - aT E)] = 0.
// The state x_d[n-1] is not used when b_c = 0 and adds an eigenvalue at 0.
struct SampledMassDamper {
    double gain;  // 1/(m a²)
    double n1;    // aT - 1 + E
    double n0;    // 1 - E - aT E
    double e;     // E
};

SampledMassDamper sampled_mass_damper(const DeviceModel& d, double period) {
    const double a = d.damping_n_s_per_m / d.mass_kg;
    const double e = std::exp(-a * period);
    return {1.0 / (d.mass_kg * a * a), a * period - 1.0 + e, 1.0 - e - a * period * e, e};
}

std::vector<Complex> sorted(std::vector<Complex> v) {
    std::sort(v.begin(), v.end(), [](Complex p, Complex q) {
        return p.real() != q.real() ? p.real() < q.real() : p.imag() < q.imag();
    });
    return v;
}

TEST(exactClosedForm, HandsOffRigidWallMatchesHandDerivedQuadratic) {
    for (double kc : {500.0, 3000.0, 6000.0}) {
        const SampledMassDamper p = sampled_mass_damper(kDevice, kPeriodS);
        // z² + c1 z + c0 = 0
        const double c1 = -(1.0 + p.e) + kc * p.gain * p.n1;
        const double c0 = p.e + kc * p.gain * p.n0;
        const Complex root = std::sqrt(Complex(c1 * c1 - 4.0 * c0, 0.0));
        const std::vector<Complex> expected = sorted({0.0, (-c1 + root) / 2.0, (-c1 - root) / 2.0});

        const ClosedLoopPoles poles =
            closed_loop_poles(kDevice, {kc, 0.0}, kRateHz, OperatorModel::hands_off(),
                              EnvironmentModel::rigid_wall());
        const std::vector<Complex> actual = sorted(poles.eigenvalues);
        ASSERT_EQ(actual.size(), 3u);
        for (std::size_t i = 0; i < 3; ++i) {
            EXPECT_NEAR(actual[i].real(), expected[i].real(), 1e-11) << "k_c = " << kc;
            EXPECT_NEAR(std::abs(actual[i].imag()), std::abs(expected[i].imag()), 1e-11);
        }
        EXPECT_NEAR(poles.spectral_radius, std::abs(expected[2]), 1e-11);
        EXPECT_NEAR(poles.dominant_frequency_hz,
                    std::abs(std::arg(expected[2])) / (2.0 * kPi * kPeriodS), 1e-6);
    }
}

// With b_c > 0, F = [k_c + b_c (1 - z⁻¹)/T] x, and with x_d[n-1] as a state the
// characteristic polynomial is the cubic
//   z (z - 1)(z - E) + (1/(m a²)) [(k_c + b_c/T) z - b_c/T] [(aT - 1 + E) z + (1 - E - aT E)].
TEST(exactClosedForm, CouplingDampingGivesHandDerivedCubic) {
    const double kc = 2500.0, bc = 0.7;
    const SampledMassDamper p = sampled_mass_damper(kDevice, kPeriodS);
    const double f1 = kc + bc / kPeriodS, f0 = -bc / kPeriodS;
    const std::array<double, 4> coeff = {p.gain * f0 * p.n0,                      // z⁰
                                         p.e + p.gain * (f1 * p.n0 + f0 * p.n1),  // z¹
                                         -(1.0 + p.e) + p.gain * f1 * p.n1,       // z²
                                         1.0};                                    // z³
    const ClosedLoopPoles poles = closed_loop_poles(
        kDevice, {kc, bc}, kRateHz, OperatorModel::hands_off(), EnvironmentModel::rigid_wall());
    ASSERT_EQ(poles.eigenvalues.size(), 3u);
    for (Complex z : poles.eigenvalues) {
        Complex value = 0.0;
        double scale = 0.0;
        for (int k = 3; k >= 0; --k) {
            value = value * z + coeff[static_cast<std::size_t>(k)];
            scale += std::abs(coeff[static_cast<std::size_t>(k)]) * std::pow(std::abs(z), k);
        }
        EXPECT_LT(std::abs(value), 1e-12 * scale) << "eigenvalue " << z;
    }
    // The three roots multiply to -c0 (Vieta): catches a missing or duplicated root.
    Complex product = 1.0;
    for (Complex z : poles.eigenvalues) product *= z;
    EXPECT_NEAR(product.real(), -coeff[0], 1e-12);
}

// ---- An independent simulation of the servo tick ---------------------------------------

/// One hold period `t` of a 4-state plant under a constant force: `substeps` classical RK4
/// steps of ds/dt = derivative(s, force). The independent simulations' continuous half.
template <typename Derivative>
void hold_with_rk4(std::array<double, 4>& s, double force, double t, int substeps,
                   const Derivative& derivative) {
    using State = std::array<double, 4>;
    const auto add = [](const State& x, const State& dx, double w) {
        return State{x[0] + w * dx[0], x[1] + w * dx[1], x[2] + w * dx[2], x[3] + w * dx[3]};
    };
    const double h = t / substeps;
    for (int k = 0; k < substeps; ++k) {
        const State k1 = derivative(s, force);
        const State k2 = derivative(add(s, k1, h / 2), force);
        const State k3 = derivative(add(s, k2, h / 2), force);
        const State k4 = derivative(add(s, k3, h), force);
        for (std::size_t i = 0; i < 4; ++i)
            s[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
}

/// The force's growth per tick from the RMS over ticks [2000, 3000) to [3000, 4000): the
/// dominant mode has taken over by then.
double late_growth_per_tick(const std::vector<double>& force_history) {
    const auto rms = [&](int from, int to) {
        double sum = 0.0;
        for (int n = from; n < to; ++n)
            sum += force_history[std::size_t(n)] * force_history[std::size_t(n)];
        return std::sqrt(sum / (to - from));
    };
    return std::pow(rms(3000, 4000) / rms(2000, 3000), 1.0 / 1000.0);
}

// Device (10) with a two-mass grasp, integrated by RK4 with 100 substeps under the held
// force; the tick computes v_d by backward difference, the mass-spring environment by the
// implicit update documented in the header, and the coupling force (16). The growth of the
// response per tick must equal the spectral radius.
TEST(exactSimulation, GrowthPerTickEqualsSpectralRadius) {
    const OperatorModel h = OperatorModel::two_mass_grasp(1000.0, 1.0, 0.5, 100.0, 2.0);
    const EnvironmentModel env = EnvironmentModel::mass_spring(0.05, 1e5, 1.0);
    const SpringDamperCoupling c{9000.0, 0.5};  // beyond 2(b + b_c)/T: unstable
    const ClosedLoopPoles poles = closed_loop_poles(kDevice, c, kRateHz, h, env);
    ASSERT_GT(poles.spectral_radius, 1.002);  // 1.00296 at 48 Hz

    const double m = kDevice.mass_kg, b = kDevice.damping_n_s_per_m, t = kPeriodS;
    using State = std::array<double, 4>;  // x_d, v_d, x_h, v_h
    auto derivative = [&](const State& s, double force) {
        const double skin =
            h.skin_stiffness_n_per_m * (s[0] - s[2]) + h.skin_damping_n_s_per_m * (s[1] - s[3]);
        const double arm = h.arm_stiffness_n_per_m * s[2] + h.arm_damping_n_s_per_m * s[3];
        return State{s[1], (-b * s[1] - skin - force) / m, s[3], (skin - arm) / h.hand_mass_kg};
    };
    State s{1e-3, 0.0, 0.0, 0.0};
    double x_prev = 0.0, xe = 0.0, ve = 0.0;
    std::vector<double> force_history;
    constexpr int kTicks = 4000, kSub = 100;
    for (int n = 0; n < kTicks; ++n) {
        const double xd = s[0];
        const double vd = (xd - x_prev) / t;
        const double ve_prev = ve;
        const double d = env.mass_kg + t * (c.damping_n_s_per_m + env.damping_n_s_per_m) +
                         t * t * (c.stiffness_n_per_m + env.stiffness_n_per_m);
        ve = (env.mass_kg * ve + t * (c.stiffness_n_per_m * (xd - xe) + c.damping_n_s_per_m * vd -
                                      env.stiffness_n_per_m * xe)) /
             d;
        xe += t * ve;
        const double force = c.stiffness_n_per_m * (xd - xe) + c.damping_n_s_per_m * (vd - ve);
        // The update is implicit Euler of the environment under the coupling force F[n].
        ASSERT_NEAR(env.mass_kg * (ve - ve_prev) / t,
                    force - env.stiffness_n_per_m * xe - env.damping_n_s_per_m * ve,
                    1e-9 * (1.0 + std::abs(force)));
        force_history.push_back(force);
        x_prev = xd;
        hold_with_rk4(s, force, t, kSub, derivative);
    }
    EXPECT_NEAR(late_growth_per_tick(force_history), poles.spectral_radius, 2e-5);
}

// ---- The damper on a filtered velocity (theory/velocity_filter.hpp) ----------------------

TEST(exactVelocityFilter, AgreesWithAnIndependentLoop) {
    // tools/scripts/velocity_filter_loop.py: the same loop written from scratch with scipy.
    struct Case {
        OperatorModel hand;
        SpringDamperCoupling coupling;
        EnvironmentModel environment;
        double radius, frequency_hz;
    };
    const Case cases[] = {
        {OperatorModel::heavy_hand(0.5, 1.0),
         {3600.0, 0.5, 100.0},
         EnvironmentModel::rigid_wall(),
         0.998591422294282,
         12.33076936},
        {OperatorModel::heavy_hand(0.5, 1.0),
         {3600.0, 0.5, 0.0},
         EnvironmentModel::rigid_wall(),
         0.998585279527818,
         12.3249996},
        {OperatorModel::heavy_hand(2.0, 0.0),
         {1500.0, 1.0, 30.0},
         EnvironmentModel::rigid_wall(),
         0.999468246299843,
         4.258321381},
        {OperatorModel::heavy_hand(0.5, 1.0),
         {3000.0, 0.5, 100.0},
         EnvironmentModel::mass_spring(0.01, 1e4, 0.0),
         0.998218501716343,
         9.864003582},
        {OperatorModel::heavy_hand(1.0, 0.3),
         {2500.0, 2.0, 300.0},
         EnvironmentModel::mass_spring(0.1, 1e3, 1.0),
         0.998842580256954,
         3.959630965},
    };
    for (const Case& c : cases) {
        const ClosedLoopPoles poles =
            closed_loop_poles(kDevice, c.coupling, kRateHz, c.hand, c.environment);
        EXPECT_NEAR(poles.spectral_radius, c.radius, 1e-12) << c.hand.describe();
        EXPECT_NEAR(poles.dominant_frequency_hz, c.frequency_hz, 1e-7) << c.hand.describe();
    }
}

TEST(exactVelocityFilter, TheServosUpdateGrowsAtTheSpectralRadius) {
    // The servo tick of the file comment with the filter, simulated: the implicit-Euler
    // mass-spring with D = m_e + T((1 - a) b_c + b_e) + T²(k_c + k_e) and the memory a b_c u.
    const OperatorModel h = OperatorModel::two_mass_grasp(1000.0, 1.0, 0.5, 100.0, 2.0);
    const EnvironmentModel env = EnvironmentModel::mass_spring(0.05, 1e5, 1.0);
    const SpringDamperCoupling c{9000.0, 0.5, 100.0};
    const ClosedLoopPoles poles = closed_loop_poles(kDevice, c, kRateHz, h, env);
    ASSERT_GT(poles.spectral_radius, 1.002);

    const double m = kDevice.mass_kg, b = kDevice.damping_n_s_per_m, t = kPeriodS;
    const double a = std::exp(-2.0 * kPi * c.velocity_filter_hz * t);
    const double kc = c.stiffness_n_per_m, bc = c.damping_n_s_per_m;
    using State = std::array<double, 4>;  // x_d, v_d, x_h, v_h
    auto derivative = [&](const State& s, double force) {
        const double skin =
            h.skin_stiffness_n_per_m * (s[0] - s[2]) + h.skin_damping_n_s_per_m * (s[1] - s[3]);
        const double arm = h.arm_stiffness_n_per_m * s[2] + h.arm_damping_n_s_per_m * s[3];
        return State{s[1], (-b * s[1] - skin - force) / m, s[3], (skin - arm) / h.hand_mass_kg};
    };
    State s{1e-3, 0.0, 0.0, 0.0};
    double x_prev = 0.0, xe = 0.0, ve = 0.0, u = 0.0;
    std::vector<double> force_history;
    constexpr int kTicks = 4000, kSub = 100;
    for (int n = 0; n < kTicks; ++n) {
        const double xd = s[0];
        const double vd = (xd - x_prev) / t;
        const double ve_prev = ve;
        const double d = env.mass_kg + t * ((1.0 - a) * bc + env.damping_n_s_per_m) +
                         t * t * (kc + env.stiffness_n_per_m);
        ve = (env.mass_kg * ve + t * (kc * (xd - xe) + (1.0 - a) * bc * vd + a * bc * u -
                                      env.stiffness_n_per_m * xe)) /
             d;
        xe += t * ve;
        u = a * u + (1.0 - a) * (vd - ve);
        const double force = kc * (xd - xe) + bc * u;
        ASSERT_NEAR(env.mass_kg * (ve - ve_prev) / t,
                    force - env.stiffness_n_per_m * xe - env.damping_n_s_per_m * ve,
                    1e-9 * (1.0 + std::abs(force)));
        force_history.push_back(force);
        x_prev = xd;
        hold_with_rk4(s, force, t, kSub, derivative);
    }
    EXPECT_NEAR(late_growth_per_tick(force_history), poles.spectral_radius, 2e-5);
}

// ---- The low-frequency bound: Colgate & Schenkel, and the paper's 8b/T -----------------

TEST(exactColgate, JustBelowTwoBOverTIsStableForTheWholeSweep) {
    const ExactCheck check = check_exact(kDevice, {0.99 * kColgateStiffness, 0.0}, kRateHz);
    EXPECT_TRUE(check.stable) << check.worst_operator.describe() << " | "
                              << check.worst_environment.describe();
    // The lossless adversaries leave eigenvalues within rounding of the unit circle.
    EXPECT_GE(check.worst_margin, -kMarginalTolerance);
}

// At 20 kHz the passive model's own k_c, 2b/T = 80000 N/m, meets a synthesised lossless
// operator whose modes fold onto z = -1: a cluster of eigenvalues whose moduli scatter on both
// sides of 1 by about 2e-8 per tick, past the 1e-8 tolerance. That excess does not move when
// the coupling's gains drop by 1 %, so it is no growth of the design: the check says marginal.
// A real growth nearly as small (k_c a tenth of a percent past 2b/T at 1 kHz: |z| - 1 under
// the 1e-6 of a decisive growth) moves with the gains, and stays unstable.
TEST(exactColgate, AnExcessTheGainsDoNotMoveIsRoundingAndARealOneIsNot) {
    constexpr double kFastRateHz = 20000.0;
    const double bound = 2.0 * kDevice.damping_n_s_per_m * kFastRateHz;
    const ExactCheck at_bound = check_exact(kDevice, {bound * (1.0 - 1e-11), 0.0}, kFastRateHz);
    EXPECT_GT(at_bound.worst_spectral_radius, 1.0 + kMarginalTolerance);
    EXPECT_TRUE(at_bound.stable);
    EXPECT_TRUE(at_bound.marginal());
    const double moved = closed_loop_poles(kDevice, {0.99 * bound, 0.0}, kFastRateHz,
                                           at_bound.worst_operator, at_bound.worst_environment)
                             .spectral_radius;
    EXPECT_NEAR(moved, at_bound.worst_spectral_radius,
                1e-3 * (at_bound.worst_spectral_radius - 1.0));

    const ExactCheck past = check_exact(kDevice, {1.001 * kColgateStiffness, 0.0}, kRateHz);
    EXPECT_FALSE(past.stable) << past.worst_operator.describe();
    EXPECT_LT(past.worst_spectral_radius, 1.0 + kDecisiveGrowthPerTick);
    EXPECT_GT(past.worst_spectral_radius, 1.0 + kMarginalTolerance);
}

// The paper's model: (21) with ZOH = (1/2)(z+1)/z has |ZOH| = cos(θ/2), ∠ZOH = -θ/2, so its
// right side is sin²(θ/4) cos(θ/2)/b, while at b_c = 0, Re(1/Z_c) = 2 sin²(θ/2)/(k_c T).
// Their ratio 8b cos²(θ/4)/(k_c T cos(θ/2)) is smallest at θ -> 0, where it is 8b/(k_c T):
// (13) allows k_c up to 8b/T = 16000 N/m, four times Colgate's bound.
TEST(exactColgate, ThePaperModelsEightBOverTIsUnstable) {
    const double paper_limit = 8.0 * kDevice.damping_n_s_per_m / kPeriodS;
    EXPECT_TRUE(theory::check_coupling(kDevice, {0.999 * paper_limit, 0.0},
                                       theory::HoldModel::paper, kRateHz)
                    .unconditionally_stable);
    EXPECT_FALSE(theory::check_coupling(kDevice, {1.001 * paper_limit, 0.0},
                                        theory::HoldModel::paper, kRateHz)
                     .unconditionally_stable);

    EXPECT_GT(radius({paper_limit, 0.0}, OperatorModel::heavy_hand(10.0, 0.0),
                     EnvironmentModel::rigid_wall()),
              1.0);

    // The sweep's worst case is hands-off, not the heavy hand: below the hold's Nyquist
    // effects the delay T/2 turns k_c into a negative damping k_c T/2 - b = 3b acting on
    // the whole moving mass M, which grows like e^{3b t/(2M)}; the lightest M (the device
    // alone) grows fastest, ρ ≈ e^{3bT/(2m)} = 1.030 (exact: 1.0291), at about
    // √(k_c/m)/2π = 64 Hz.
    const ExactCheck check = check_exact(kDevice, {paper_limit, 0.0}, kRateHz);
    EXPECT_FALSE(check.stable);
    EXPECT_EQ(check.worst_operator.family, OperatorFamily::hands_off);
    EXPECT_EQ(check.worst_environment.kind, EnvironmentModel::Kind::rigid_wall);
    EXPECT_NEAR(check.worst_spectral_radius, 1.0291, 1e-4);
    EXPECT_LT(check.worst_margin, -0.02);
    EXPECT_NEAR(check.worst_frequency_hz, std::sqrt(paper_limit / kDevice.mass_kg) / (2 * kPi),
                0.05 * 63.7);
}

// For a heavy hand of total mass M the loop is M s² + b s + k_c e^{-sT/2} ≈
// M s² + (b - k_c T/2) s + k_c at the low frequency √(k_c/M): stable iff k_c < 2b/T, more
// exactly so the heavier the hand.
TEST(exactColgate, HeavyHandLimitApproachesTwoBOverT) {
    double previous_excess = 1.0;
    for (double hand_mass_kg : {0.1, 1.0, 10.0}) {
        const OperatorModel h = OperatorModel::heavy_hand(hand_mass_kg, 0.0);
        const double limit = bisect(0.0, 10.0 * kColgateStiffness, [&](double kc) {
            return radius({kc, 0.0}, h, EnvironmentModel::rigid_wall()) < 1.0;
        });
        const double excess = limit / kColgateStiffness - 1.0;
        EXPECT_GT(excess, 0.0) << "m_h = " << hand_mass_kg;  // approached from above
        EXPECT_LT(excess, previous_excess) << "m_h = " << hand_mass_kg;
        previous_excess = excess;
    }
    // Measured: 1.0017, 1.0003, 1.00003 times 2b/T.
    EXPECT_LT(previous_excess, 1e-4);
}

// With coupling damping the low-frequency damping is b + b_c - k_c T/2: k_c < 2(b + b_c)/T.
TEST(exactColgate, CouplingDampingRaisesTheLowFrequencyLimit) {
    const double bc = 0.2;
    const OperatorModel h = OperatorModel::heavy_hand(10.0, 0.0);
    const double limit = bisect(0.0, 10.0 * kColgateStiffness, [&](double kc) {
        return radius({kc, bc}, h, EnvironmentModel::rigid_wall()) < 1.0;
    });
    EXPECT_NEAR(limit, 2.0 * (kDevice.damping_n_s_per_m + bc) / kPeriodS, 1e-3 * limit);
}

// ---- The Nyquist bound on the coupling damping -----------------------------------------

// The steel grip k_h = m (π/T)² cancels the device's mass reactance at Nyquist, leaving
// Z_handle(jπ/T) = b. At z = -1 the ZOH equivalent of x/F_d = -1/(s Z_handle) is the alias sum
//   P(-1) = (1/T) Σ_n G(jω_n) (1 - e^{-jω_n T})/(jω_n),  ω_n = (2n + 1)π/T,
// where 1 - e^{-jω_n T} = 2 and G(jω_n)/(jω_n) = 1/(ω_n² Z_handle(jω_n)). The branches
// n = 0, -1 (ω = ±π/T, where Z_handle = b) give 2T/(π² b) each; the others have Z_handle
// nearly imaginary and their pairs add up to O((bT/m)²). The coupling at z = -1 is
// C(-1) = k_c + 2 b_c/T, and the loop has a root at z = -1 when P(-1) C(-1) = 1:
//   b_c + k_c T/2 = (π²/8) b.
TEST(exactNyquist, SteelGripLimitOnCouplingDampingIsPiSquaredOverEightB) {
    for (double kc : {100.0, 2000.0}) {
        const double limit = bisect(0.0, 20.0, [&](double bc) {
            return radius({kc, bc}, nyquist_grip(), EnvironmentModel::rigid_wall()) < 1.0;
        });
        const double expected = kPi * kPi / 8.0 * kDevice.damping_n_s_per_m - kc * kPeriodS / 2.0;
        EXPECT_NEAR(limit, expected, 1e-3 * expected) << "k_c = " << kc;
        const ClosedLoopPoles above = closed_loop_poles(
            kDevice, {kc, 1.01 * limit}, kRateHz, nyquist_grip(), EnvironmentModel::rigid_wall());
        EXPECT_NEAR(above.dominant_frequency_hz, kRateHz / 2.0, 1e-6);  // a real root at -1
    }
}

// The (π²/8) b limit holds only for an operator with a single resonance. Damping beyond
// Colgate and Schenkel's b > k_c T/2 + b_c but inside (π²/8) b passes the single Nyquist
// grip, and an operator with free-handle modes on several odd harmonics of Nyquist (the
// aliases of 500 Hz) destabilises it: Colgate's condition is the bound
// (docs/stability-models.md, "Why a sweep is not enough").
TEST(exactNyquist, DampingBeyondColgateFallsToAMultiModeOperator) {
    const double kc = 1000.0;
    const double colgate_bc = kDevice.damping_n_s_per_m - kc * kPeriodS / 2.0;  // 1.5
    const double nyquist_bc = kPi * kPi / 8.0 * kDevice.damping_n_s_per_m - kc * kPeriodS / 2.0;
    ASSERT_LT(colgate_bc, 1.8);
    ASSERT_GT(nyquist_bc, 1.8);
    EXPECT_LT(radius({kc, 1.8}, nyquist_grip(), EnvironmentModel::rigid_wall()), 1.0);

    const ExactCheck beyond_colgate = check_exact(kDevice, {kc, 1.8}, kRateHz);
    EXPECT_FALSE(beyond_colgate.stable);
    EXPECT_EQ(beyond_colgate.worst_operator.family, OperatorFamily::multi_mode);
    EXPECT_GE(beyond_colgate.worst_operator.modes.size(), 2u);
    EXPECT_NEAR(beyond_colgate.worst_frequency_hz, kRateHz / 2.0, 1e-3);
    EXPECT_NE(beyond_colgate.worst_operator.describe().find("aliases of 500 Hz"), std::string::npos)
        << beyond_colgate.worst_operator.describe();

    EXPECT_TRUE(check_exact(kDevice, {kc, 0.99 * colgate_bc}, kRateHz).stable);
}

// ---- Environments ----------------------------------------------------------------------

TEST(exactEnvironment, FreeSpaceLikeEnvironmentIsStableWhereTheWallIsNot) {
    const double kc = 8.0 * kDevice.damping_n_s_per_m / kPeriodS;  // unstable on the wall
    const EnvironmentModel air = EnvironmentModel::mass_spring(1e-3, 1e-2);
    for (const OperatorModel& h :
         {OperatorModel::hands_off(), OperatorModel::heavy_hand(10.0, 0.0)}) {
        EXPECT_GT(radius({kc, 0.0}, h, EnvironmentModel::rigid_wall()), 1.0) << h.describe();
        EXPECT_LT(radius({kc, 0.0}, h, air), 1.0) << h.describe();
    }
}

// A stiff heavy environment is a wall: the implicit update tends to x_e = v_e = 0.
TEST(exactEnvironment, StiffMassSpringTendsToTheRigidWall) {
    const SpringDamperCoupling c{3000.0, 0.5};
    const OperatorModel h = OperatorModel::stiff_grasp(0.5, 300.0, 1.0);
    const double wall = radius(c, h, EnvironmentModel::rigid_wall());
    EXPECT_NEAR(radius(c, h, EnvironmentModel::mass_spring(1.0, 1e12)), wall, 1e-8);
    // ...and a soft heavy one is not (0.999998 against the wall's 0.998335).
    EXPECT_GT(radius(c, h, EnvironmentModel::mass_spring(1e3, 1e3)) - wall, 1e-3);
}

// ---- The default sweep -----------------------------------------------------------------

// Measured in Release on the development machine: about 0.3 s for the 67522 cases.
TEST(exactSweep, TypicalDeviceChecksEveryCase) {
    const ExactCheck check = check_exact(kDevice, {3000.0, 0.2}, kRateHz);
    const std::size_t operators = default_operator_sweep(kDevice, kRateHz).size();
    const std::size_t environments = default_environment_sweep(kDevice).size();
    EXPECT_EQ(operators, 637u);
    EXPECT_EQ(environments, 106u);
    // The default sweep meets the synthesised environments too, and the synthesised
    // operators meet the rigid wall and those environments.
    const Adversaries adversaries = synthesize_adversaries(kDevice, {3000.0, 0.2}, kRateHz, 0.0);
    const std::size_t tuned_operators = adversaries.operators.size();
    const std::size_t tuned_environments = adversaries.environments.size();
    EXPECT_GE(tuned_operators, 50u);
    EXPECT_GE(tuned_environments, 5u);
    EXPECT_EQ(check.cases_checked,
              static_cast<int>(operators * (environments + tuned_environments) +
                               tuned_operators * (1 + tuned_environments)));
    EXPECT_GT(check.cases_checked, 1000);
    EXPECT_TRUE(check.stable);
    EXPECT_NEAR(check.worst_margin, 1.0 - check.worst_spectral_radius, 1e-15);
}

// k_c = b_c = 0 leaves the hands-off handle free: a simple eigenvalue at z = 1, marginal,
// which Definition 1 counts as stable.
TEST(exactSweep, FreeHandleIsMarginallyStable) {
    EXPECT_NEAR(radius({0.0, 0.0}, OperatorModel::hands_off(), EnvironmentModel::rigid_wall()), 1.0,
                1e-12);
    const ExactCheck check =
        check_exact(kDevice, {0.0, 0.0}, kRateHz, {OperatorModel::hands_off()},
                    {EnvironmentModel::rigid_wall(), EnvironmentModel::mass_spring(0.1, 100.0)});
    EXPECT_TRUE(check.stable);
    EXPECT_NEAR(check.worst_margin, 0.0, 1e-12);
    EXPECT_EQ(check.cases_checked, 2);
}

// Regression: Eigen's real Schur iteration did not converge on this loop matrix (a 0.1 g
// hand on a 1e6 N/m arm; the exact grid values, in hex) until it was balanced first.
TEST(exactSweep, BadlyScaledLoopStillGetsItsEigenvalues) {
    const OperatorModel h =
        OperatorModel::two_mass_grasp(0x1.13e2e0923847ap+17, 0.0, 0x1.e459c57e28a48p-14, 1e6, 0.0);
    const ClosedLoopPoles poles =
        closed_loop_poles(kDevice, {3000.0, 1.0}, kRateHz, h, EnvironmentModel::rigid_wall());
    EXPECT_EQ(poles.eigenvalues.size(), 5u);
    EXPECT_NEAR(poles.spectral_radius, std::abs(Complex(0.437874, 0.899036)), 1e-5);
}

// Regression (found by a hostile tester): with one period of delay at 4000 N/m the
// adversary for θ = π/2 had a reactance of 2.8e-7 N s/m, whose tan/cot series became modes of
// 1e-13 kg on 1e-3 N/m springs, and the eigenvalue solver stalled on them; such a reactance
// is now zero, and the check gives its verdict.
TEST(exactSweep, ANegligibleReactanceBuildsNoDegenerateModes) {
    const OperatorModel tuned =
        alias_tuned_operator(kDevice, std::numbers::pi / 2.0, kRateHz, 16, 2.81429e-07);
    for (const OperatorMode& mode : tuned.modes) EXPECT_GT(mode.mass_kg, 1e-6) << tuned.describe();
    const ExactCheck check = check_exact(kDevice, {4000.0, 0.0}, kRateHz, 1.0);
    EXPECT_FALSE(check.stable);
    EXPECT_GT(check.worst_spectral_radius, 1.01);
}

// ---- Input -----------------------------------------------------------------------------

template <typename F>
std::string invalid_argument_message(F&& f) {
    try {
        f();
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "(no std::invalid_argument thrown)";
}

TEST(exactVelocityFilter, NoFilterIsTheUnfilteredLoopAndTheCutoffIsChecked) {
    const OperatorModel h = OperatorModel::two_mass_grasp(1000.0, 1.0, 0.5, 100.0, 2.0);
    const EnvironmentModel env = EnvironmentModel::mass_spring(0.05, 1e5, 1.0);
    const ClosedLoopPoles plain = closed_loop_poles(kDevice, {3000.0, 0.5}, kRateHz, h, env);
    const ClosedLoopPoles zero = closed_loop_poles(kDevice, {3000.0, 0.5, 0.0}, kRateHz, h, env);
    EXPECT_EQ(plain.spectral_radius, zero.spectral_radius);
    EXPECT_EQ(plain.eigenvalues.size(), zero.eigenvalues.size());
    const ClosedLoopPoles filtered =
        closed_loop_poles(kDevice, {3000.0, 0.5, 100.0}, kRateHz, h, env);
    EXPECT_EQ(filtered.eigenvalues.size(), plain.eigenvalues.size() + 1);  // u[n-1]
    for (double bad : {-1.0, 0.5, 500.0, 800.0}) {
        EXPECT_NE(invalid_argument_message([&] {
                      closed_loop_poles(kDevice, {3000.0, 0.5, bad}, kRateHz, h, env);
                  }).find("velocity filter"),
                  std::string::npos)
            << bad;
    }
}

TEST(exactInput, RejectsNonPhysicalValuesNamingThem) {
    const OperatorModel h = OperatorModel::hands_off();
    const EnvironmentModel wall = EnvironmentModel::rigid_wall();
    EXPECT_NE(invalid_argument_message([&] {
                  check_exact({-0.25, 2.0}, {1000.0, 0.0}, kRateHz);
              }).find("-0.25"),
              std::string::npos);
    EXPECT_NE(invalid_argument_message([&] {
                  closed_loop_poles({-0.25, 2.0}, {1000.0, 0.0}, kRateHz, h, wall);
              }).find("-0.25"),
              std::string::npos);
    EXPECT_NE(invalid_argument_message([&] {
                  closed_loop_poles(kDevice, {-7.5, 0.0}, kRateHz, h, wall);
              }).find("-7.5"),
              std::string::npos);
    EXPECT_NE(invalid_argument_message([&] {
                  closed_loop_poles(kDevice, {1000.0, 0.0}, 0.0, h, wall);
              }).find("servo rate"),
              std::string::npos);
    EXPECT_NE(invalid_argument_message([&] {
                  closed_loop_poles(kDevice, {1000.0, 0.0}, kRateHz,
                                    OperatorModel::heavy_hand(-3.5, 0.0), wall);
              }).find("-3.5"),
              std::string::npos);
    EXPECT_NE(invalid_argument_message([&] {
                  closed_loop_poles(kDevice, {1000.0, 0.0}, kRateHz,
                                    OperatorModel::two_mass_grasp(100.0, 0.0, 0.0, 0.0, 0.0), wall);
              }).find("hand mass"),
              std::string::npos);
    EXPECT_NE(invalid_argument_message([&] {
                  closed_loop_poles(kDevice, {1000.0, 0.0}, kRateHz, h,
                                    EnvironmentModel::mass_spring(0.1, -1.0));
              }).find("environment stiffness"),
              std::string::npos);
    // A field the family does not use is an error, not silently ignored.
    OperatorModel typo = OperatorModel::heavy_hand(1.0, 0.0);
    typo.hand_stiffness_n_per_m = 500.0;
    EXPECT_NE(invalid_argument_message([&] {
                  closed_loop_poles(kDevice, {1000.0, 0.0}, kRateHz, typo, wall);
              }).find("hand_stiffness_n_per_m = 500"),
              std::string::npos);
    EXPECT_THROW(check_exact(kDevice, {1000.0, 0.0}, kRateHz, {}, {wall}), std::invalid_argument);
}

TEST(exactInput, DescriptionsNameTheFamilyAndValues) {
    EXPECT_EQ(OperatorModel::hands_off().describe(), "hands-off");
    EXPECT_EQ(OperatorModel::stiff_grasp(1.0, 1000.0, 0.0).describe(),
              "stiff grasp (m_h = 1 kg, k_h = 1000 N/m, b_h = 0 N s/m)");
    EXPECT_EQ(EnvironmentModel::rigid_wall().describe(), "rigid wall");
    EXPECT_EQ(EnvironmentModel::mass_spring(0.1, 1000.0).describe(),
              "mass-spring (m_e = 0.1 kg, k_e = 1000 N/m, b_e = 0 N s/m)");
}

}  // namespace
}  // namespace hapticd::tune
