// The exact admittance loop (exact_admittance.hpp) against closed forms and an independent
// computation of its poles.
#include "hapticd/tune/exact_admittance.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <string>
#include <utility>
#include <vector>

namespace hapticd::tune {
namespace {

using theory::Complex;

/// The eigenvalues with |λ| > 1e-9, largest first (ties by imaginary part).
std::vector<Complex> nonzero_sorted(const ClosedLoopPoles& poles) {
    std::vector<Complex> out;
    for (const Complex& l : poles.eigenvalues) {
        if (std::abs(l) > 1e-9) out.push_back(l);
    }
    std::sort(out.begin(), out.end(), [](Complex a, Complex b) {
        if (std::abs(std::abs(a) - std::abs(b)) > 1e-12) return std::abs(a) > std::abs(b);
        return a.imag() < b.imag();
    });
    return out;
}

void expect_poles(const ClosedLoopPoles& poles, const std::vector<Complex>& expected,
                  double tolerance) {
    const std::vector<Complex> got = nonzero_sorted(poles);
    ASSERT_EQ(got.size(), expected.size());
    for (std::size_t i = 0; i < got.size(); ++i) {
        EXPECT_NEAR(std::abs(got[i] - expected[i]), 0.0, tolerance)
            << i << ": " << got[i] << " vs " << expected[i];
    }
}

// Poles printed by `/usr/bin/python3 tools/scripts/admittance_closed_loop.py`, which closes
// the loop on transfer-function polynomials from scipy's ZOH sampling (no state matrix).
TEST(ExactAdmittanceLoop, AgreesWithAnIndependentTransferFunctionComputation) {
    AdmittanceDesign pi_alone{{2.0, 5.0}, {40.0, 2000.0}, {1.0, 1.0}, 1000.0};
    expect_poles(admittance_closed_loop_poles(pi_alone, OperatorModel::hands_off(),
                                              AdmittanceEnvironment::rigid_wall()),
                 {{0.988400985428347, -0.029572220605877},
                  {0.988400985428347, 0.029572220605877},
                  {0.010209896084387, 0.0}},
                 1e-9);
    // A stiff grasp in free space: the force sensor, the coupling's mass and damper, PI.
    AdmittanceDesign grasp{{2.0, 5.0}, {4.0, 100.0}, {0.5, 30.0}, 1000.0};
    expect_poles(admittance_closed_loop_poles(grasp, OperatorModel::stiff_grasp(1.0, 1000.0, 2.0),
                                              AdmittanceEnvironment::free_space()),
                 {{1.002745038414701, -0.019005141541919},
                  {1.002745038414701, 0.019005141541919},
                  {0.993432865765928, -0.011395088847824},
                  {0.993432865765928, 0.011395088847824},
                  {-0.043991035872697, 0.0}},
                 1e-9);
    // A heavy hand (rigid: the sensor reads m_h/(m + m_h) of the held force) on a pure-mass
    // coupling; the handle is not grounded, so the translation mode is deflated.
    AdmittanceDesign heavy{{0.5, 3.0}, {2.0, 0.0}, {2.0, INFINITY}, 2000.0};
    expect_poles(admittance_closed_loop_poles(heavy, OperatorModel::heavy_hand(3.0, 1.0),
                                              AdmittanceEnvironment::free_space()),
                 {{0.999941807960270, 0.0}, {0.998772712229953, 0.0}, {0.000142986529279, 0.0}},
                 1e-9);
}

// Hands-off, the PI loop alone on the device: with a = e^{-bT/m}, the ZOH-sampled device
// from F to x is -(1/b)[T/(z-1) - (m/b)(1-a)/(z-a)], the backward difference multiplies by
// (z-1)/(Tz), and a delay of q periods by z^-q, so the poles are the roots of
//   b T z^{1+q} (z-a)(z-1) + (k_p (z-1) + k_i T z)[T (z-a) - (m/b)(1-a)(z-1)] = 0.
TEST(ExactAdmittanceLoop, HandsOffIsThePiLoopOnTheSampledDevice) {
    const double m = 2.0, b = 5.0, t = 1e-3, kp = 40.0, ki = 2000.0;
    const double a = std::exp(-b * t / m);
    for (int q : {0, 1, 2}) {
        AdmittanceDesign d{{m, b}, {kp, ki}, {0.7, 12.0}, 1.0 / t, double(q)};
        // Hands-off the virtual side is not driven: the environment does not matter.
        for (const AdmittanceEnvironment& env :
             {AdmittanceEnvironment::rigid_wall(), AdmittanceEnvironment::free_space(),
              AdmittanceEnvironment::mass_spring(1.0, 100.0, 2.0)}) {
            const ClosedLoopPoles poles =
                admittance_closed_loop_poles(d, OperatorModel::hands_off(), env);
            int roots_found = 0;
            for (const Complex& z : poles.eigenvalues) {
                const Complex value =
                    b * t * std::pow(z, 1 + q) * (z - a) * (z - 1.0) +
                    (kp * (z - 1.0) + ki * t * z) * (t * (z - a) - (m / b) * (1.0 - a) * (z - 1.0));
                // Scale: the polynomial's coefficients are O(kp m/b (1-a)) ~ 1e-2.
                if (std::abs(value) < 1e-12) ++roots_found;
            }
            EXPECT_GE(roots_found, 3 + q) << "q = " << q << ", " << env.describe();
        }
    }
}

// The deflated translation mode is exactly the z = 1 that a vanishing ground spring moves
// off the unit circle: every other pole is continuous in k_h.
TEST(ExactAdmittanceLoop, DeflatingTheTranslationModeRemovesOnlyZEqualsOne) {
    AdmittanceDesign d{{2.0, 5.0}, {3.0, 50.0}, {1.5, 40.0}, 1000.0};
    const ClosedLoopPoles free =
        admittance_closed_loop_poles(d, OperatorModel::heavy_hand(1.0, 0.5),
                                     AdmittanceEnvironment::mass_spring(0.2, 300.0, 1.0));
    OperatorModel grounded = OperatorModel::stiff_grasp(1.0, 1e-9, 0.5);
    const ClosedLoopPoles near = admittance_closed_loop_poles(
        d, grounded, AdmittanceEnvironment::mass_spring(0.2, 300.0, 1.0));
    ASSERT_EQ(near.eigenvalues.size(), free.eigenvalues.size() + 1);
    std::vector<Complex> remaining = near.eigenvalues;
    // Remove the pole nearest 1 and match the rest.
    const auto one = std::min_element(remaining.begin(), remaining.end(), [](Complex x, Complex y) {
        return std::abs(x - 1.0) < std::abs(y - 1.0);
    });
    EXPECT_LT(std::abs(*one - 1.0), 1e-6);
    remaining.erase(one);
    for (const Complex& l : free.eigenvalues) {
        double nearest = INFINITY;
        for (const Complex& r : remaining) nearest = std::min(nearest, std::abs(r - l));
        EXPECT_LT(nearest, 1e-6) << l;
    }
}

// At the rigid wall v_com = 0: the coupling drops out, whatever its mass and damper.
TEST(ExactAdmittanceLoop, AtTheRigidWallTheCouplingDropsOut) {
    const OperatorModel grasp = OperatorModel::two_mass_grasp(1e4, 3.0, 0.5, 1e3, 1.0);
    AdmittanceDesign d{{2.0, 5.0}, {3.0, 80.0}, {0.1, 1.0}, 1000.0};
    const ClosedLoopPoles light =
        admittance_closed_loop_poles(d, grasp, AdmittanceEnvironment::rigid_wall());
    d.coupling = {50.0, INFINITY};
    const ClosedLoopPoles heavy =
        admittance_closed_loop_poles(d, grasp, AdmittanceEnvironment::rigid_wall());
    EXPECT_EQ(light.spectral_radius, heavy.spectral_radius);
}

// A fraction of a period of delay tends to the whole period continuously.
TEST(ExactAdmittanceLoop, AFractionalDelayTendsToTheWholePeriod) {
    AdmittanceDesign d{{2.0, 5.0}, {2.0, 0.0}, {3.0, 60.0}, 1000.0, 1.0};
    const OperatorModel grasp = OperatorModel::stiff_grasp(0.5, 2e3, 1.0);
    const double whole =
        admittance_closed_loop_poles(d, grasp, AdmittanceEnvironment::free_space()).spectral_radius;
    d.delay_periods = 1.0 - 1e-7;
    const double almost =
        admittance_closed_loop_poles(d, grasp, AdmittanceEnvironment::free_space()).spectral_radius;
    EXPECT_NEAR(almost, whole, 1e-6);
}

// The force-sensor filter's states (force_sensor_filter.hpp), against the same independent
// computation: scipy samples the device with the filter appended and closes the loop on
// polynomials (`/usr/bin/python3 tools/scripts/admittance_closed_loop.py`, last two cases).
TEST(ExactAdmittanceLoop, TheFilteredSensorAgreesWithAnIndependentComputation) {
    AdmittanceDesign grasp{{2.0, 5.0}, {4.0, 100.0}, {0.5, 30.0}, 1000.0};
    grasp.force_filter = theory::ForceSensorFilter{100.0, 0.5, 2};
    expect_poles(admittance_closed_loop_poles(grasp, OperatorModel::stiff_grasp(1.0, 1000.0, 2.0),
                                              AdmittanceEnvironment::free_space()),
                 {{1.0028151177025175, -0.018890127381267476},
                  {1.0028151177025175, 0.018890127381267476},
                  {0.993409236778213, -0.011492693797327673},
                  {0.993409236778213, 0.011492693797327673},
                  {0.6228995320723173, -0.39116918677158913},
                  {0.6228995320723173, 0.39116918677158913},
                  {0.0006610351137605316, 0.0}},
                 1e-9);
    AdmittanceDesign heavy{{0.5, 3.0}, {2.0, 0.0}, {2.0, INFINITY}, 2000.0};
    heavy.force_filter = theory::ForceSensorFilter{50.0, 0.7071067811865476, 2};
    expect_poles(admittance_closed_loop_poles(heavy, OperatorModel::heavy_hand(3.0, 1.0),
                                              AdmittanceEnvironment::free_space()),
                 {{0.9999417928883843, 0.0},
                  {0.9987685245746644, 0.0},
                  {0.889573766418543, -0.09902172631233865},
                  {0.889573766418543, 0.09902172631233865},
                  {0.00014292522302856428, 0.0}},
                 1e-9);
}

// A filter far above the servo rate is a wire: today's poles come back, with the filter's own
// (at e^{-ω_a T ...} ~ 0) added. The rigid hand reads the held force at nT⁻ either way.
TEST(ExactAdmittanceLoop, AVeryFastFilterRecoversTheUnfilteredLoop) {
    const std::vector<std::pair<OperatorModel, AdmittanceEnvironment>> cases{
        {OperatorModel::stiff_grasp(1.0, 1000.0, 2.0), AdmittanceEnvironment::free_space()},
        {OperatorModel::heavy_hand(3.0, 1.0), AdmittanceEnvironment::mass_spring(1.0, 100.0, 2.0)},
        {OperatorModel::two_mass_grasp(1e4, 3.0, 0.5, 1e3, 1.0),
         AdmittanceEnvironment::free_space()}};
    for (const auto& [human, env] : cases) {
        AdmittanceDesign d{{2.0, 5.0}, {4.0, 100.0}, {0.5, 30.0}, 1000.0};
        const std::vector<Complex> plain =
            nonzero_sorted(admittance_closed_loop_poles(d, human, env));
        d.force_filter = theory::ForceSensorFilter{100.0 * d.rate_hz, 0.7071067811865476, 2};
        const ClosedLoopPoles filtered = admittance_closed_loop_poles(d, human, env);
        EXPECT_EQ(
            filtered.eigenvalues.size(),
            admittance_closed_loop_poles({d.device, d.loop, d.coupling, d.rate_hz}, human, env)
                    .eigenvalues.size() +
                2);
        for (const Complex& p : plain) {
            double nearest = INFINITY;
            for (const Complex& q : filtered.eigenvalues)
                nearest = std::min(nearest, std::abs(p - q));
            EXPECT_LT(nearest, 1e-6) << human.describe() << ": " << p;
        }
    }
}

TEST(ExactAdmittanceLoop, NonPhysicalInputNamesTheValue) {
    const auto message = [](AdmittanceDesign d, AdmittanceEnvironment e) {
        try {
            admittance_closed_loop_poles(d, OperatorModel::hands_off(), e);
        } catch (const std::invalid_argument& error) {
            return std::string(error.what());
        }
        return std::string("no error");
    };
    const AdmittanceDesign good{{2.0, 5.0}, {2.0, 0.0}, {1.0, 10.0}, 1000.0};
    AdmittanceDesign d = good;
    d.loop.proportional_gain_n_s_per_m = -1.0;
    EXPECT_NE(message(d, {}).find("k_p = -1"), std::string::npos);
    d = good;
    d.coupling = {INFINITY, INFINITY};
    EXPECT_NE(message(d, {}).find("no coupling"), std::string::npos);
    d = good;
    d.coupling.mass_kg = 0.0;
    EXPECT_NE(message(d, {}).find("m_c = 0"), std::string::npos);
    d = good;
    d.delay_periods = 12.0;
    EXPECT_NE(message(d, {}).find("12"), std::string::npos);
    EXPECT_NE(message(good, AdmittanceEnvironment::mass_spring(-1.0, 0.0)).find("m_e = -1"),
              std::string::npos);
    EXPECT_EQ(message(good, AdmittanceEnvironment::free_space()), "no error");
    d = good;
    d.force_filter = theory::ForceSensorFilter{2e5, 0.7, 2};
    EXPECT_NE(message(d, {}).find("f_aa = 200000 Hz is outside (0, 100000]"), std::string::npos)
        << message(d, {});
    d.force_filter = theory::ForceSensorFilter{100.0, 11.0, 2};
    EXPECT_NE(message(d, {}).find("ζ = 11 is outside (0, 10]"), std::string::npos);
}

TEST(ExactAdmittanceLoop, EnvironmentsDescribeThemselves) {
    EXPECT_EQ(AdmittanceEnvironment::free_space().describe(), "free space");
    EXPECT_EQ(AdmittanceEnvironment::mass_spring(2.0, 0.0, 1.0).describe(),
              "virtual mass (m_e = 2 kg, b_e = 1 N s/m)");
    EXPECT_EQ(AdmittanceEnvironment::from(EnvironmentModel::lossless_mass_spring(1.0, 10.0)).kind,
              AdmittanceEnvironment::Kind::lossless_mass_spring);
}

}  // namespace
}  // namespace hapticd::tune
