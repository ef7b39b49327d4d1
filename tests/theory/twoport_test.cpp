// Immittance forms (1)-(4), passivity (7) and Llewellyn's criteria (8).
#include "hapticd/theory/twoport.hpp"

#include <gtest/gtest.h>

#include <array>
#include <random>

#include "hapticd/theory/benchmark.hpp"
#include "hapticd/theory/llewellyn.hpp"
#include "stepped.hpp"

namespace hapticd::theory {
namespace {

using hapticd::testing::stepped;

constexpr std::array<ImmittanceForm, 4> kForms = {
    ImmittanceForm::impedance, ImmittanceForm::admittance, ImmittanceForm::hybrid,
    ImmittanceForm::alternate_hybrid};

Complex random_complex(std::mt19937& rng) {
    std::normal_distribution<double> n(0.0, 1.0);
    return {n(rng), n(rng)};
}

TwoPort random_network(std::mt19937& rng, ImmittanceForm form) {
    return {form, random_complex(rng), random_complex(rng), random_complex(rng),
            random_complex(rng)};
}

void expect_near(Complex a, Complex b, double tol = 1e-9) {
    EXPECT_NEAR(a.real(), b.real(), tol * (1.0 + std::abs(b)));
    EXPECT_NEAR(a.imag(), b.imag(), tol * (1.0 + std::abs(b)));
}

TEST(TwoPort, HybridFromImpedanceMatchesHandDerivedFormulas) {
    // From (1): -v2 = (F2 - z21 v1)/z22, so h11 = det Z / z22, h12 = z12/z22,
    // h21 = -z21/z22, h22 = 1/z22.
    const TwoPort z{ImmittanceForm::impedance, {2, 1}, {0.5, -1}, {3, 0.2}, {1, 1}};
    const TwoPort h = *convert(z, ImmittanceForm::hybrid);
    EXPECT_EQ(h.form, ImmittanceForm::hybrid);
    expect_near(h.p11, (z.p11 * z.p22 - z.p12 * z.p21) / z.p22);
    expect_near(h.p12, z.p12 / z.p22);
    expect_near(h.p21, -z.p21 / z.p22);
    expect_near(h.p22, 1.0 / z.p22);
}

TEST(TwoPort, ConversionsRoundTripThroughEveryForm) {
    std::mt19937 rng(7);
    for (int trial = 0; trial < 200; ++trial) {
        const TwoPort original = random_network(rng, kForms[trial % 4]);
        for (ImmittanceForm via : kForms) {
            const auto there = convert(original, via);
            ASSERT_TRUE(there);
            EXPECT_EQ(there->form, via);
            const auto back = convert(*there, original.form);
            ASSERT_TRUE(back);
            expect_near(back->p11, original.p11, 1e-8);
            expect_near(back->p12, original.p12, 1e-8);
            expect_near(back->p21, original.p21, 1e-8);
            expect_near(back->p22, original.p22, 1e-8);
        }
    }
}

TEST(TwoPort, ImpedanceFormOfTheBareDisplayDoesNotExist) {
    // (14) has h22 = 0: with F_d* = 0 the display imposes no relation on v_d*.
    const TwoPort display = impedance_display({0.1, 2.0}, HoldModel::paper, 0.5, 1e-3);
    EXPECT_FALSE(convert(display, ImmittanceForm::impedance));
    EXPECT_TRUE(convert(display, ImmittanceForm::alternate_hybrid));
}

TEST(Llewellyn, VerdictAndStabilityFactorAreTheSameInAllFourForms) {
    std::mt19937 rng(11);
    int stable_seen = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        TwoPort network = random_network(rng, ImmittanceForm::hybrid);
        // Bias half the samples toward stable networks so both verdicts are exercised.
        if (trial % 2 == 0) {
            network.p11 += 3.0;
            network.p22 += 3.0;
        }
        const LlewellynResult reference = llewellyn(network);
        stable_seen += reference.unconditionally_stable;
        for (ImmittanceForm form : kForms) {
            const auto other = convert(network, form);
            ASSERT_TRUE(other);
            const LlewellynResult r = llewellyn(*other);
            EXPECT_EQ(r.unconditionally_stable, reference.unconditionally_stable)
                << "form " << to_string(form) << " trial " << trial;
            EXPECT_NEAR(r.stability_factor, reference.stability_factor,
                        1e-7 * (1.0 + std::abs(reference.stability_factor)));
        }
    }
    EXPECT_GT(stable_seen, 200);
    EXPECT_LT(stable_seen, 1800);
}

TEST(Llewellyn, TheHapticInterfaceGivesTheSameVerdictInAllFourForms) {
    const DeviceModel device{0.1, 2.0};
    for (double k : {1000.0, 4000.0, 20000.0}) {
        for (const double theta : stepped(0.01, 3.11, 0.05)) {
            const TwoPort h =
                impedance_interface(device, {k, 0.5}, HoldModel::encoder, theta, 1e-3);
            const bool verdict = llewellyn(h).unconditionally_stable;
            for (ImmittanceForm form : kForms) {
                EXPECT_EQ(llewellyn(*convert(h, form)).unconditionally_stable, verdict);
            }
        }
    }
}

TEST(Llewellyn, SweepFindsTheWorstFrequencyOfTheInterface) {
    // Against (21)'s own check: same worst margin and frequency for an interior binding.
    const DeviceModel device{0.1, 2.0};
    const SpringDamperCoupling coupling{4000.0, 3.0};
    const LlewellynSweep sweep = llewellyn_over_frequency(
        [&](double theta) {
            return impedance_interface(device, coupling, HoldModel::encoder, theta, 1e-3);
        },
        1000.0);
    EXPECT_FALSE(sweep.unconditionally_stable);
    EXPECT_GT(sweep.worst_re_p11, 0.0);  // Re Z_dI = b > 0: only the second inequality fails
    double worst = 1e300;
    double worst_theta = 0.0;
    for (const double theta : stepped(1e-3, 3.14159, 1e-5)) {
        const double m = coupling_margin(device, coupling, HoldModel::encoder, theta, 1e-3);
        if (m < worst) worst = m, worst_theta = theta;
    }
    EXPECT_NEAR(sweep.worst_margin, worst, 1e-6 * std::abs(worst));
    EXPECT_NEAR(sweep.worst_frequency_hz, worst_theta / (2 * 3.14159265358979 * 1e-3), 0.01);
}

TEST(Passivity, CoincidesWithLlewellynForReciprocalNetworks) {
    // Section II-C: for z21 = z12 the tests (7) and (8) are identical.
    std::mt19937 rng(3);
    int passive_seen = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        TwoPort z = random_network(rng, ImmittanceForm::impedance);
        z.p21 = z.p12;
        z.p11 += 1.5;
        z.p22 += 1.5;
        const bool passive = passivity(z).passive;
        passive_seen += passive;
        EXPECT_EQ(passive, llewellyn(z).unconditionally_stable) << "trial " << trial;
        // Passivity is a property of the network, not of the form.
        EXPECT_EQ(passivity(*convert(z, ImmittanceForm::hybrid)).passive, passive);
    }
    EXPECT_GT(passive_seen, 100);
    EXPECT_LT(passive_seen, 1900);
}

TEST(Passivity, TheTransparentInterfaceIsLosslessAndTheBareDisplayIsNot) {
    // (9): perfect transparency is lossless: P + P^H = 0.
    const TwoPort ideal{ImmittanceForm::hybrid, 0.0, 1.0, -1.0, 0.0};
    EXPECT_TRUE(passivity(ideal).passive);
    EXPECT_NEAR(passivity(ideal).min_eigenvalue, 0.0, 1e-15);
    // (14) is not reciprocal and not passive: ZOH != 1 away from DC.
    const TwoPort display = impedance_display({0.1, 2.0}, HoldModel::paper, 1.0, 1e-3);
    EXPECT_FALSE(passivity(display).passive);
    EXPECT_LT(passivity(display).min_eigenvalue, 0.0);
}

TEST(Dual, IsAnInvolutionAndPreservesTheStabilityFactor) {
    std::mt19937 rng(5);
    for (int trial = 0; trial < 100; ++trial) {
        const TwoPort p = random_network(rng, kForms[trial % 4]);
        const TwoPort d = dual(p);
        EXPECT_NE(d.form, p.form);
        const TwoPort dd = dual(d);
        EXPECT_EQ(dd.form, p.form);
        expect_near(dd.p12, p.p12);
        EXPECT_NEAR(llewellyn(d).stability_factor, llewellyn(p).stability_factor, 1e-12);
    }
    EXPECT_EQ(dual(TwoPort{ImmittanceForm::hybrid, 1, 1, 1, 1}).form,
              ImmittanceForm::alternate_hybrid);
    EXPECT_EQ(dual(TwoPort{ImmittanceForm::impedance, 1, 1, 1, 1}).form,
              ImmittanceForm::admittance);
}

}  // namespace
}  // namespace hapticd::theory
