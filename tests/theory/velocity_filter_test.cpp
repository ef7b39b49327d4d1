// The coupling damper on a filtered velocity (velocity_filter.hpp) in every model's Z_c:
// its response against complex arithmetic, the conductance (21) uses, and the passive
// model's limits against their closed form and against an independent numpy computation
// (tools/scripts/velocity_filter_limits.py).
#include "hapticd/theory/velocity_filter.hpp"

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "hapticd/theory/benchmark.hpp"
#include "hapticd/theory/coupling_check.hpp"

namespace hapticd::theory {
namespace {

constexpr double kT = 1e-3;
constexpr double kRateHz = 1000.0;
constexpr double kPi = std::numbers::pi;
const DeviceModel kPen{0.1, 2.0};

double pole_of(double cutoff_hz) { return std::exp(-2.0 * kPi * cutoff_hz * kT); }

/// Z_c = k_c T/(1 - z⁻¹) + b_c (1 - a)/(1 - a z⁻¹), straight from its definition.
Complex direct_impedance(double k, double b, double cutoff_hz, double theta) {
    const Complex z_inverse = std::exp(Complex(0.0, -theta));
    const double a = cutoff_hz > 0.0 ? pole_of(cutoff_hz) : 0.0;
    return k * kT / (1.0 - z_inverse) + b * (1.0 - a) / (1.0 - a * z_inverse);
}

/// The largest k_c the passive model allows, to 1e-10 relative (bisection on check_coupling).
double passive_limit(double b_c, double cutoff_hz, double delay_periods) {
    double lo = 0.0, hi = 1e5;
    while (hi - lo > 1e-10 * hi) {
        const double mid = 0.5 * (lo + hi);
        const bool stable = check_coupling(kPen, {mid, b_c, cutoff_hz},
                                           {HoldModel::passive, delay_periods}, kRateHz)
                                .unconditionally_stable;
        (stable ? lo : hi) = mid;
    }
    return lo;
}

class FilteredAtEveryFrequency : public ::testing::TestWithParam<double> {};
INSTANTIATE_TEST_SUITE_P(Theta, FilteredAtEveryFrequency,
                         ::testing::Values(1e-4, 0.01, 0.3, 1.0, 2.0, 3.0, kPi));

TEST_P(FilteredAtEveryFrequency, ResponseIsTheFirstOrderLowPass) {
    const double theta = GetParam();
    for (double cutoff_hz : {1.0, 30.0, 100.0, 300.0, 499.0}) {
        const double a = velocity_filter_pole(cutoff_hz, kT);
        EXPECT_DOUBLE_EQ(a, pole_of(cutoff_hz));
        const Complex expected = (1.0 - a) / (1.0 - a * std::exp(Complex(0.0, -theta)));
        const FilterResponse<double> b = velocity_filter_response(a, theta);
        EXPECT_NEAR(b.re, expected.real(), 1e-13);
        EXPECT_NEAR(b.im, expected.imag(), 1e-13);
        EXPECT_GT(b.re, 0.0);  // positive real: the filtered coupling is a passive impedance
        EXPECT_NEAR(velocity_filter_conductance_gain(a, theta), (1.0 / expected).real(),
                    1e-12 * (1.0 / expected).real());
    }
    EXPECT_EQ(velocity_filter_pole(0.0, kT), 0.0);
}

TEST_P(FilteredAtEveryFrequency, ImpedanceAndConductanceAreTheDefinition) {
    const double theta = GetParam();
    for (auto [k, b, f] : {std::tuple{3000.0, 0.5, 100.0},
                           {1000.0, 2.0, 10.0},
                           {0.0, 1.5, 300.0},
                           {4000.0, 0.0, 50.0}}) {
        const SpringDamperCoupling c{k, b, f};
        const Complex expected = direct_impedance(k, b, f, theta);
        EXPECT_NEAR(std::abs(coupling_impedance(c, theta, kT) - expected), 0.0,
                    1e-9 * std::abs(expected));
        const double g = (1.0 / expected).real();
        EXPECT_NEAR(coupling_conductance(c, theta, kT), g, 1e-6 * g);  // z - 1 costs digits
        EXPECT_EQ(coupling_conductance(c, theta, kT), coupling_conductance(k, b, theta, kT, f));
    }
}

TEST_P(FilteredAtEveryFrequency, NoFilterIsTheUnfilteredConductanceToTheBit) {
    const double theta = GetParam();
    const double half_kt = 3000.0 * kT / 2.0;
    const double r = 0.7 + half_kt;
    const double x = half_kt / std::tan(theta / 2.0);
    EXPECT_EQ(coupling_conductance(SpringDamperCoupling{3000.0, 0.7, 0.0}, theta, kT),
              r / (r * r + x * x));
}

TEST(VelocityFilter, ConductanceJetsCarryTheSlopes) {
    // The sizing solver differentiates Re(1/Z_c) in k_c and θ with Ceres jets.
    using Jet = ceres::Jet<double, 2>;
    const double k = 2500.0, b = 0.8, f = 120.0, theta = 0.9;
    const Jet g = coupling_conductance(Jet(k, 0), Jet(b), Jet(theta, 1), kT, f);
    const auto at = [&](double kk, double tt) { return coupling_conductance(kk, b, tt, kT, f); };
    EXPECT_NEAR(g.a, at(k, theta), 1e-15);
    EXPECT_NEAR(g.v[0], (at(k + 1e-3, theta) - at(k - 1e-3, theta)) / 2e-3,
                1e-6 * std::abs(g.v[0]));
    EXPECT_NEAR(g.v[1], (at(k, theta + 1e-6) - at(k, theta - 1e-6)) / 2e-6,
                1e-6 * std::abs(g.v[1]));
}

TEST(VelocityFilter, LagTurnsTheDamperIntoLessDampingAndSomeSpring) {
    // Re B = 1 - a (1 + a) θ²/(2 (1 - a)²) + O(θ⁴), Im B = -a θ/(1 - a) + O(θ³): at low frequency
    // the filtered damper resists less than b_c and adds a compliant reactance, so its coupling
    // conducts less than the unfiltered one there; at Nyquist B = (1 - a)/(1 + a) and it
    // conducts more.
    const double f = 100.0, a = pole_of(f);
    for (double theta : {1e-3, 1e-2}) {
        const FilterResponse<double> b = velocity_filter_response(a, theta);
        const double drop = a * (1.0 + a) * theta * theta / (2.0 * (1.0 - a) * (1.0 - a));
        EXPECT_NEAR(b.re, 1.0 - drop, 1e-2 * drop);
        EXPECT_NEAR(b.im, -a * theta / (1.0 - a), 1e-2 * a * theta);
        EXPECT_LT(b.re, 1.0);
    }
    EXPECT_NEAR(velocity_filter_response(a, kPi).re, (1.0 - a) / (1.0 + a), 1e-15);
    EXPECT_NEAR(velocity_filter_response(a, kPi).im, 0.0, 1e-15);
    const SpringDamperCoupling filtered{3000.0, 0.5, f}, plain{3000.0, 0.5, 0.0};
    for (double theta : {0.05, 0.3, 0.6}) {
        EXPECT_LT(coupling_conductance(filtered, theta, kT), coupling_conductance(plain, theta, kT))
            << theta;
    }
    EXPECT_GT(coupling_conductance(filtered, kPi, kT), coupling_conductance(plain, kPi, kT));
    // The limit f -> 0 of (21) is the unfiltered one: the filter is transparent at DC.
    for (HoldModel hold : {HoldModel::passive, HoldModel::encoder, HoldModel::paper}) {
        const double dc = coupling_margin_at_dc(kPen, filtered, hold, kT);
        EXPECT_EQ(dc, coupling_margin_at_dc(kPen, plain, hold, kT));
        EXPECT_NEAR(coupling_margin(kPen, filtered, hold, 1e-5, kT), dc, 1e-6 * (1.0 + dc));
    }
}

TEST(VelocityFilter, PassiveLimitWithoutDelayIsTheNyquistClosedForm) {
    // With no delay, Re(1/Z_c) >= (1 - cos θ)/(2b) reduces to
    //   k_c T/2 + b_c (1 - a)/(1 + a) <= b   (docs/stability-models.md),
    // binding at Nyquist: the filtered damper counts with (1 - a)/(1 + a) of b_c there.
    for (auto [f, b_c] : {std::pair{100.0, 0.5},
                          {300.0, 0.5},
                          {100.0, 2.0},
                          {30.0, 5.0},
                          {10.0, 1.0},
                          {499.0, 1.5}}) {
        const double a = pole_of(f);
        const double closed = 2.0 * (kPen.damping_n_s_per_m - b_c * (1.0 - a) / (1.0 + a)) / kT;
        const CouplingCheck below =
            check_coupling(kPen, {closed * (1.0 - 1e-6), b_c, f}, HoldModel::passive, kRateHz);
        const CouplingCheck above =
            check_coupling(kPen, {closed * (1.0 + 1e-6), b_c, f}, HoldModel::passive, kRateHz);
        EXPECT_TRUE(below.unconditionally_stable) << f << " " << b_c;
        EXPECT_FALSE(above.unconditionally_stable) << f << " " << b_c;
        EXPECT_NEAR(above.worst_frequency_hz, kRateHz / 2.0, 1e-3) << f << " " << b_c;
    }
    // The same damping unfiltered is held to b_c + k_c T/2 <= b: 3000 N/m at 0.5 N s/m, where
    // a 100 Hz filter allows 3695.78 N/m and a 300 Hz one 3263.64 N/m.
    EXPECT_NEAR(passive_limit(0.5, 0.0, 0.0), 3000.0, 1e-6);
}

TEST(VelocityFilter, PassiveLimitsAgreeWithAnIndependentComputation) {
    // tools/scripts/velocity_filter_limits.py (numpy complex arithmetic, its own grid and
    // minimiser): FC:BC 100:0.5 300:0.5 [--delay-periods 1 0:0.5 100:0.5 300:0.5 100:0.1].
    struct Case {
        double cutoff_hz, b_c, delay_periods, numpy_limit, numpy_binding_hz;
    };
    for (const Case c :
         {Case{100.0, 0.5, 0.0, 3695.78381, 500.0}, Case{300.0, 0.5, 0.0, 3263.6414, 500.0},
          Case{0.0, 0.5, 1.0, 1534.0702, 151.821}, Case{100.0, 0.5, 1.0, 1240.23684, 135.362},
          Case{300.0, 0.5, 1.0, 1453.01801, 157.453}, Case{100.0, 0.1, 1.0, 1144.83691, 70.8495}}) {
        const double limit = passive_limit(c.b_c, c.cutoff_hz, c.delay_periods);
        EXPECT_NEAR(limit, c.numpy_limit, 2e-8 * c.numpy_limit)
            << c.cutoff_hz << " Hz, b_c " << c.b_c << ", delay " << c.delay_periods;
        const CouplingCheck at = check_coupling(kPen, {limit * (1.0 + 1e-7), c.b_c, c.cutoff_hz},
                                                {HoldModel::passive, c.delay_periods}, kRateHz);
        EXPECT_NEAR(at.worst_frequency_hz, c.numpy_binding_hz, 1e-3 * c.numpy_binding_hz);
    }
}

}  // namespace
}  // namespace hapticd::theory
