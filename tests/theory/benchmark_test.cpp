// The benchmark impedance display (10)-(21), the coupling check, and Z-width (23)-(26).
#include "hapticd/theory/benchmark.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "hapticd/theory/coupling_check.hpp"
#include "hapticd/theory/llewellyn.hpp"
#include "hapticd/theory/zwidth.hpp"

namespace hapticd::theory {
namespace {

constexpr double kT = 1e-3;
const DeviceModel kDevice{0.1, 2.0};
constexpr double kPi = std::numbers::pi;

class EveryFrequency : public ::testing::TestWithParam<double> {};
INSTANTIATE_TEST_SUITE_P(Theta, EveryFrequency,
                         ::testing::Values(1e-4, 0.01, 0.3, 1.0, 2.0, 3.0, kPi - 1e-3));

TEST_P(EveryFrequency, TustinDeviceHasRealPartExactlyB) {
    // (12): Tustin maps the imaginary axis onto the unit circle, so Re Z_dI = b.
    const Complex z = device_impedance(kDevice, GetParam(), kT);
    EXPECT_NEAR(z.real(), 2.0, 1e-12 * std::abs(z));
}

TEST_P(EveryFrequency, PaperHoldIsHalfASampleOfDelayWithCosineGain) {
    const double theta = GetParam();
    const Complex zoh = hold_term(HoldModel::paper, theta);
    EXPECT_NEAR(std::abs(zoh), std::cos(theta / 2), 1e-12);
    EXPECT_NEAR(std::arg(zoh), -theta / 2, 1e-9);
}

TEST_P(EveryFrequency, EncoderHoldIsTheSquareOfTheExactZeroOrderHold) {
    // The exact ZOH response (1 - e^{-jθ})/(jθ), computed directly, squared: once for the
    // hold, once for the backward difference that averages velocity over the period.
    const double theta = GetParam();
    const Complex j(0.0, 1.0);
    const Complex zoh = (1.0 - std::exp(-j * theta)) / (j * theta);
    const Complex expected = zoh * zoh;
    const Complex h = hold_term(HoldModel::encoder, theta);
    EXPECT_NEAR(std::abs(h - expected), 0.0, 1e-7 * std::abs(expected));
}

TEST_P(EveryFrequency, ConventionalDesignIsNeverUnconditionallyStable) {
    // (15): applying (8) to (14) gives cos∠ZOH >= 1, which never holds for 0 < θ < 2π.
    for (HoldModel model : {HoldModel::paper, HoldModel::encoder}) {
        const LlewellynResult r = llewellyn(impedance_display(kDevice, model, GetParam(), kT));
        EXPECT_FALSE(r.unconditionally_stable);
        EXPECT_NEAR(r.stability_factor, std::cos(std::arg(hold_term(model, GetParam()))), 1e-12);
        EXPECT_LT(r.stability_factor, 1.0);
    }
}

TEST_P(EveryFrequency, LlewellynOnTheInterfaceIsCondition20) {
    const double theta = GetParam();
    const SpringDamperCoupling coupling{3000.0, 0.7};
    for (HoldModel model : {HoldModel::paper, HoldModel::encoder}) {
        const Complex h = hold_term(model, theta);
        const double conductance = (1.0 / coupling_impedance(coupling, theta, kT)).real();
        // (20): cos∠ZOH + 2 Re(Z_dI) Re(1/Z_cI)/|ZOH| is Llewellyn's stability factor of (18).
        const double eta20 = std::cos(std::arg(h)) + 2.0 * 2.0 * conductance / std::abs(h);
        const LlewellynResult r =
            llewellyn(impedance_interface(kDevice, coupling, model, theta, kT));
        EXPECT_NEAR(r.stability_factor, eta20, 1e-6 * eta20);
        EXPECT_EQ(r.unconditionally_stable, eta20 >= 1.0);
        // The margin of (8) is the ratio of the sides of (21), minus one.
        EXPECT_NEAR(r.margin, coupling_margin(kDevice, coupling, model, theta, kT),
                    1e-7 * (1.0 + std::abs(r.margin)));
    }
}

TEST_P(EveryFrequency, RealConductanceFormulaMatchesComplexArithmetic) {
    const double theta = GetParam();
    for (const SpringDamperCoupling c : {SpringDamperCoupling{5000, 0}, {100, 3}, {0, 2}}) {
        const double expected = (1.0 / coupling_impedance(c, theta, kT)).real();
        EXPECT_NEAR(coupling_conductance(c.stiffness_n_per_m, c.damping_n_s_per_m, theta, kT),
                    expected, 1e-6 * expected);  // z - 1 costs complex arithmetic digits
    }
}

TEST_P(EveryFrequency, ZWidthIsTheCouplingImpedanceThroughTheHold) {
    const double theta = GetParam();
    const SpringDamperCoupling coupling{3000.0, 0.7};
    const HoldModel model = HoldModel::encoder;
    const Complex zmin = impedance_display_zmin(kDevice, model, theta, kT);
    const Complex zmax = impedance_display_zmax(kDevice, coupling, model, theta, kT);
    // (26): Z_max = Z_min + Z_cI ZOH.
    const Complex expected = coupling_impedance(coupling, theta, kT) * hold_term(model, theta);
    EXPECT_NEAR(std::abs(zmax - zmin - expected), 0.0, 1e-9 * std::abs(zmax));
    // (23) tends to (24) as Z_e -> 0 and to (25) as Z_e -> ∞.
    const Complex free = perceived_impedance(kDevice, coupling, model, 1e-9, theta, kT);
    const Complex rigid = perceived_impedance(kDevice, coupling, model, 1e12, theta, kT);
    EXPECT_NEAR(std::abs(free - zmin), 0.0, 1e-6 * std::abs(zmin));
    EXPECT_NEAR(std::abs(rigid - zmax), 0.0, 1e-6 * std::abs(zmax));
}

TEST_P(EveryFrequency, DelayTurnsTheZWidthsCouplingTermByDelayTimesTheta) {
    // With d periods of delay, H carries e^{-jdθ}: the coupling's share of Z_max keeps its
    // magnitude and turns by -dθ; Z_min (free space) does not see the delay.
    const double theta = GetParam();
    const SpringDamperCoupling coupling{3000.0, 0.7};
    const double delay_periods = 1.5;
    const LoopModel delayed{HoldModel::encoder, delay_periods};
    const LoopModel prompt{HoldModel::encoder};
    const Complex zmin = impedance_display_zmin(kDevice, delayed, theta, kT);
    EXPECT_EQ(zmin, impedance_display_zmin(kDevice, prompt, theta, kT));
    const Complex delayed_term =
        impedance_display_zmax(kDevice, coupling, delayed, theta, kT) - zmin;
    const Complex prompt_term = impedance_display_zmax(kDevice, coupling, prompt, theta, kT) - zmin;
    EXPECT_NEAR(std::abs(delayed_term - prompt_term * std::polar(1.0, -delay_periods * theta)), 0.0,
                1e-9 * std::abs(prompt_term));
    const Complex rigid = perceived_impedance(kDevice, coupling, delayed, 1e12, theta, kT);
    EXPECT_NEAR(std::abs(rigid - zmin - delayed_term), 0.0, 1e-6 * std::abs(rigid));
}

TEST(CouplingCheck, EncoderModelReproducesColgateAndSchenkelsWallBound) {
    // b_c = 0: (21) with e^{-jθ} sinc²(θ/2) reads 2b/(k_c T) >= sinc²(θ/2), tightest as
    // θ -> 0, so k_c <= 2b/T: Colgate and Schenkel's bound for a wall without damping.
    const double bound = 2.0 * kDevice.damping_n_s_per_m / kT;
    const CouplingCheck below =
        check_coupling(kDevice, {bound * (1 - 1e-6), 0}, HoldModel::encoder, 1000);
    const CouplingCheck above =
        check_coupling(kDevice, {bound * (1 + 1e-6), 0}, HoldModel::encoder, 1000);
    EXPECT_TRUE(below.unconditionally_stable);
    EXPECT_FALSE(above.unconditionally_stable);
    EXPECT_NEAR(below.worst_margin, 1e-6, 1e-8);
    EXPECT_EQ(below.worst_frequency_hz, 0.0);
}

TEST(CouplingCheck, PaperModelAllowsFourTimesColgatesBound) {
    // b_c = 0 with (13): 8 cos²(θ/4)/(k_c T) >= cos(θ/2)/b, tightest as θ -> 0: k_c <= 8b/T.
    const double bound = 8.0 * kDevice.damping_n_s_per_m / kT;
    EXPECT_TRUE(check_coupling(kDevice, {bound * (1 - 1e-6), 0}, HoldModel::paper, 1000)
                    .unconditionally_stable);
    EXPECT_FALSE(check_coupling(kDevice, {bound * (1 + 1e-6), 0}, HoldModel::paper, 1000)
                     .unconditionally_stable);
}

TEST(CouplingCheck, DcLimitMatchesTheLowFrequencyMargin) {
    // Derived closed form: at low frequency (21) with the encoder hold and b_c > 0 reads
    // (k_c T)² <= 2 b k_c T + 4 b b_c, so the DC-binding stiffness is
    // k_c T = b + sqrt(b² + 4 b b_c).
    const double b = kDevice.damping_n_s_per_m;
    const double b_c = 0.2;
    const double k = (b + std::sqrt(b * b + 4 * b * b_c)) / kT;
    EXPECT_NEAR(coupling_margin_at_dc(kDevice, {k, b_c}, HoldModel::encoder, kT), 0.0, 1e-12);
    EXPECT_NEAR(coupling_margin(kDevice, {k, b_c}, HoldModel::encoder, 1e-5, kT), 0.0, 1e-8);
}

TEST(CouplingCheck, ReportsTheBindingFrequencyOfAnInteriorViolation) {
    // With heavy coupling damping the violation sits at mid frequency, not at DC.
    const CouplingCheck check = check_coupling(kDevice, {4000.0, 3.0}, HoldModel::encoder, 1000);
    EXPECT_FALSE(check.unconditionally_stable);
    EXPECT_GT(check.worst_frequency_hz, 100.0);
    EXPECT_LT(check.worst_frequency_hz, 500.0);
    // The reported margin is the minimum: nearby frequencies are no worse.
    const double theta = normalized_frequency(check.worst_frequency_hz, kT);
    for (double d : {-1e-3, 1e-3}) {
        EXPECT_GE(coupling_margin(kDevice, {4000.0, 3.0}, HoldModel::encoder, theta + d, kT),
                  check.worst_margin - 1e-12);
    }
}

}  // namespace
}  // namespace hapticd::theory
