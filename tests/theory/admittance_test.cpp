// The admittance display (27)-(43) and its duality with the impedance display (Table I).
#include "hapticd/theory/admittance.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "hapticd/theory/llewellyn.hpp"
#include "hapticd/theory/zwidth.hpp"
#include "stepped.hpp"

namespace hapticd::theory {
namespace {

using hapticd::testing::stepped;

constexpr double kT = 1e-3;
const DeviceModel kDevice{2.0, 5.0};       // a heavy, admittance-type manipulator
const PiVelocityLoop kLoop{40.0, 2000.0};  // K_PI = 40 + 2000 T z/(z - 1)
const MassDamperCoupling kCoupling{0.5, 30.0};

void expect_same(Complex a, Complex b) {
    EXPECT_NEAR(std::abs(a - b), 0.0, 1e-9 * (1.0 + std::abs(b)));
}

class AdmittanceFrequency : public ::testing::TestWithParam<double> {};
INSTANTIATE_TEST_SUITE_P(Theta, AdmittanceFrequency,
                         ::testing::Values(1e-3, 0.05, 0.5, 1.5, 2.5, 3.1));

TEST_P(AdmittanceFrequency, ConventionalAdmittanceDesignIsNeverUnconditionallyStable) {
    // (31): (8) on (28) reads cos∠T >= 1, false for any lead or lag of the velocity loop.
    const double theta = GetParam();
    for (HoldModel model : {HoldModel::paper, HoldModel::encoder}) {
        const TwoPort display = admittance_display(kDevice, kLoop, model, theta, kT);
        const LlewellynResult r = llewellyn(display);
        EXPECT_FALSE(r.unconditionally_stable);
        const Complex t = velocity_tracking(kDevice, kLoop, model, theta, kT);
        EXPECT_NEAR(r.stability_factor, std::cos(std::arg(t)), 1e-9);
    }
}

TEST_P(AdmittanceFrequency, TableIMapsTheImpedanceInterfaceOntoTheAdmittanceInterface) {
    // Table I: Z_dI <-> 1/Z_dA, 1/Z_cI <-> Z_cA, ZOH <-> T. Substituting into (18) and
    // taking the dual network gives (34) term by term.
    const double theta = GetParam();
    const HoldModel model = HoldModel::paper;
    const Complex zda = admittance_display_impedance(kDevice, kLoop, model, theta, kT);
    const Complex t = velocity_tracking(kDevice, kLoop, model, theta, kT);
    const Complex zca = 1.0 / coupling_admittance(kCoupling, theta, kT);
    const TwoPort impedance_like{ImmittanceForm::hybrid, 1.0 / zda, t, -1.0, zca};
    const TwoPort mapped = dual(impedance_like);
    const TwoPort admittance = admittance_interface(kDevice, kLoop, kCoupling, model, theta, kT);
    EXPECT_EQ(mapped.form, admittance.form);
    expect_same(mapped.p11, admittance.p11);
    expect_same(mapped.p12, admittance.p12);
    expect_same(mapped.p21, admittance.p21);
    expect_same(mapped.p22, admittance.p22);
    // And (21) under the same substitution is (37).
    const double bound21 = (1.0 - std::cos(std::arg(t))) * std::abs(t) / (2.0 * (1.0 / zda).real());
    EXPECT_NEAR(admittance_coupling_bound(kDevice, kLoop, model, theta, kT), bound21,
                1e-9 * bound21 + 1e-15);
    // The verdicts agree: (36) is (20) for the dual network.
    EXPECT_EQ(llewellyn(admittance).unconditionally_stable,
              llewellyn(impedance_like).unconditionally_stable);
}

TEST_P(AdmittanceFrequency, ZWidthBoundsAreTheLimitsOfThePerceivedAdmittance) {
    const double theta = GetParam();
    const HoldModel model = HoldModel::encoder;
    // (40): Y_e -> 0 leaves 1/Z_dA; (43) Z_max = Z_dA.
    const Complex stiff = perceived_admittance(kDevice, kLoop, kCoupling, model, 1e-12, theta, kT);
    const Complex zmax = admittance_display_zmax(kDevice, kLoop, model, theta, kT);
    EXPECT_NEAR(std::abs(1.0 / stiff - zmax), 0.0, 1e-6 * std::abs(zmax));
    // (41)-(42): Y_e -> ∞ gives Y_max = 1/Z_dA + T/Z_cA and Z_min = 1/Y_max.
    const Complex free = perceived_admittance(kDevice, kLoop, kCoupling, model, 1e12, theta, kT);
    const Complex zmin = admittance_display_zmin(kDevice, kLoop, kCoupling, model, theta, kT);
    EXPECT_NEAR(std::abs(1.0 / free - zmin), 0.0, 1e-6 * std::abs(zmin));
}

TEST(Admittance, VelocityLoopTracksAtLowFrequency) {
    // With integral action T(z) -> 1 as ω -> 0.
    const Complex t = velocity_tracking(kDevice, kLoop, HoldModel::encoder, 1e-6, kT);
    EXPECT_NEAR(std::abs(t - 1.0), 0.0, 1e-4);
}

TEST(Admittance, CouplingAdmittanceIsSeriesMassAndDamper) {
    // (32): Y_cA = 1/b_c + 1/(m_c s), s -> (z - 1)/(T z).
    const double theta = 0.7;
    const Complex z = unit_circle_point(theta);
    const Complex expected = 1.0 / 30.0 + kT * z / ((z - 1.0) * 0.5);
    expect_same(coupling_admittance(kCoupling, theta, kT), expected);
}

TEST(Admittance, TooHighLoopGainMakesTheBoundInfinite) {
    // A stiff velocity loop drives Re(1/Z_dA) negative near Nyquist: (35) fails.
    // Under (13) the hold lags at most 90°, so only the encoder model's lag can do this:
    // Re Z_dA = b + sinc²(θ/2)(k_p cos θ - k_i T/2) < 0 near Nyquist.
    const PiVelocityLoop hot{2000.0, 0.0};
    bool found_negative = false;
    for (const double theta : stepped(0.01, 3.13, 0.01)) {
        if (admittance_display_conductance(kDevice, hot, HoldModel::encoder, theta, kT) < 0.0) {
            found_negative = true;
            EXPECT_TRUE(
                std::isinf(admittance_coupling_bound(kDevice, hot, HoldModel::encoder, theta, kT)));
        }
    }
    EXPECT_TRUE(found_negative);
}

}  // namespace
}  // namespace hapticd::theory
