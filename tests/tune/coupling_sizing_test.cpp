// Coupling sizing from (21) and (37), held against an independent dense-grid bisection.
#include "hapticd/tune/coupling_sizing.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <ostream>
#include <sstream>
#include <vector>

#include "hapticd/theory/coupling_check.hpp"
#include "stepped.hpp"

namespace hapticd::tune {
namespace {

using hapticd::testing::stepped;

using theory::DeviceModel;
using theory::HoldModel;
using Complex = std::complex<double>;

// ---- An independent implementation of (21), written with complex arithmetic only. ----
Complex hold(HoldModel model, double theta) {
    const Complex j(0, 1);
    const Complex z = std::exp(j * theta);
    if (model == HoldModel::paper) return 0.5 * (z + 1.0) / z;
    // (1 - e^{-jθ})/(jθ), with 1 - e^{-jθ} = 2j sin(θ/2) e^{-jθ/2} so small θ keeps its digits.
    const Complex zoh = 2.0 * j * std::sin(theta / 2) * std::exp(-j * theta / 2.0) / (j * theta);
    return zoh * zoh;
}

bool satisfies_21_on_grid(const DeviceModel& d, double k, double b_c, HoldModel model,
                          double period, const std::vector<double>& grid) {
    for (double theta : grid) {
        const Complex z = std::exp(Complex(0, theta));
        const Complex z_minus_1 =
            2.0 * Complex(0, std::sin(theta / 2)) * std::exp(Complex(0, theta / 2));
        const Complex zc = b_c + k * period * z / z_minus_1;
        const Complex h = hold(model, theta);
        // |H|(1 - cos∠H), with 1 - cos x = 2 sin²(x/2) so that small θ keeps its digits.
        const double half = std::sin(std::arg(h) / 2.0);
        const double bound = std::abs(h) * 2.0 * half * half / (2.0 * d.damping_n_s_per_m);
        if ((1.0 / zc).real() < bound) return false;
    }
    return true;
}

std::vector<double> dense_grid(int n) {
    std::vector<double> g;
    // Quadratically spaced from 1e-5 (the f -> 0 limit to 1e-10) up to π.
    for (int i = 0; i <= n; ++i) {
        g.push_back(1e-5 + (std::numbers::pi - 1e-5) * std::pow(double(i) / n, 2.0));
    }
    return g;
}

double bisect_stiffness(const DeviceModel& d, double b_c, HoldModel model, double period) {
    static const std::vector<double> grid = dense_grid(200000);
    double lo = 0.0;
    double hi = 100.0 * d.damping_n_s_per_m / period;
    while (hi - lo > 1e-10 * hi) {
        const double mid = 0.5 * (lo + hi);
        (satisfies_21_on_grid(d, mid, b_c, model, period, grid) ? lo : hi) = mid;
    }
    return lo;
}

struct Case {
    DeviceModel device;
    double rate_hz;
    double b_c;
    HoldModel model;
};

void PrintTo(const Case& c, std::ostream* os) {
    *os << theory::to_string(c.model) << ", m = " << c.device.mass_kg
        << " kg, b = " << c.device.damping_n_s_per_m << " N s/m, " << c.rate_hz
        << " Hz, b_c = " << c.b_c;
}

class AgainstBisection : public ::testing::TestWithParam<Case> {};

std::string case_name(const ::testing::TestParamInfo<Case>& info) {
    const Case& c = info.param;
    std::string name = std::string(theory::to_string(c.model)) + "_m" +
                       std::to_string(int(c.device.mass_kg * 1000)) + "g_b" +
                       std::to_string(int(c.device.damping_n_s_per_m * 100)) + "cNspm_" +
                       std::to_string(int(c.rate_hz)) + "Hz_bc" + std::to_string(int(c.b_c * 100));
    return name;
}

TEST_P(AgainstBisection, StiffnessAgreesToOnePartPerMillion) {
    const Case c = GetParam();
    const ImpedanceSizing s = size_impedance_coupling({c.device, c.rate_hz, c.model, c.b_c});
    const double reference = bisect_stiffness(c.device, c.b_c, c.model, 1.0 / c.rate_hz);
    EXPECT_NEAR(s.coupling.stiffness_n_per_m, reference, 1e-6 * reference)
        << "method " << s.report.method;
    EXPECT_EQ(s.coupling.damping_n_s_per_m, c.b_c);
    EXPECT_GE(s.verified_worst_margin, 0.0);   // strictly feasible, rounding included
    EXPECT_LT(s.verified_worst_margin, 1e-4);  // tight: the design touches the bound
    // And the check that `haptic-tune check` runs agrees.
    const theory::CouplingCheck check =
        theory::check_coupling(c.device, s.coupling, c.model, c.rate_hz);
    EXPECT_TRUE(check.unconditionally_stable) << check.worst_margin;
    EXPECT_LT(check.worst_margin, 1e-4);
}

INSTANTIATE_TEST_SUITE_P(Devices, AgainstBisection,
                         ::testing::Values(Case{{0.1, 2.0}, 1000, 0.0, HoldModel::encoder},
                                           Case{{0.1, 2.0}, 1000, 0.3, HoldModel::encoder},
                                           Case{{0.1, 2.0}, 1000, 1.0, HoldModel::encoder},
                                           Case{{0.1, 2.0}, 1000, 0.0, HoldModel::paper},
                                           Case{{0.1, 2.0}, 1000, 2.0, HoldModel::paper},
                                           Case{{0.5, 0.4}, 2000, 0.05, HoldModel::encoder},
                                           Case{{0.02, 8.0}, 500, 3.0, HoldModel::paper},
                                           Case{{1.0, 1.0}, 4000, 0.1, HoldModel::encoder}),
                         case_name);

TEST(ImpedanceSizing, EncoderModelAtZeroDampingIsColgatesBound) {
    const DeviceModel device{0.1, 2.0};
    const ImpedanceSizing s = size_impedance_coupling({device, 1000, HoldModel::encoder, 0.0});
    EXPECT_NEAR(s.coupling.stiffness_n_per_m, 2.0 * 2.0 / 1e-3, 1e-9 * 4000.0);
    EXPECT_LE(s.coupling.stiffness_n_per_m, 4000.0);
    EXPECT_EQ(s.binding_frequency_hz, 0.0);
    EXPECT_EQ(s.report.method, "dc-limit");
}

TEST(ImpedanceSizing, PaperModelAtZeroDampingIsEightBOverT) {
    const ImpedanceSizing s = size_impedance_coupling({{0.1, 2.0}, 1000, HoldModel::paper, 0.0});
    EXPECT_NEAR(s.coupling.stiffness_n_per_m, 16000.0, 16000.0 * 1e-9);
}

TEST(ImpedanceSizing, InteriorBindingIsFoundByTheTangencySolve) {
    const ImpedanceSizing s = size_impedance_coupling({{0.1, 2.0}, 1000, HoldModel::encoder, 1.0});
    EXPECT_EQ(s.report.method, "tangency");
    EXPECT_GT(s.report.ceres_iterations, 0);
    EXPECT_GT(s.binding_frequency_hz, 100.0);
}

class OptimizeDamping : public ::testing::TestWithParam<HoldModel> {};
INSTANTIATE_TEST_SUITE_P(Models, OptimizeDamping,
                         ::testing::Values(HoldModel::paper, HoldModel::encoder));

TEST_P(OptimizeDamping, BestPairBeatsEveryDampingOnABruteForceScan) {
    const DeviceModel device{0.1, 2.0};
    const ImpedanceSizing best = size_impedance_coupling({device, 1000, GetParam(), std::nullopt});
    double brute = 0.0;
    double brute_b_c = 0.0;
    for (const double b_c : stepped(0.0, 3.99, 0.01)) {
        try {
            const double k =
                size_impedance_coupling({device, 1000, GetParam(), b_c}).coupling.stiffness_n_per_m;
            if (k > brute) brute = k, brute_b_c = b_c;
        } catch (const InfeasibleCoupling&) {
        }
    }
    EXPECT_GE(best.coupling.stiffness_n_per_m, brute * (1 - 1e-9));
    EXPECT_LT(best.coupling.stiffness_n_per_m, brute * 1.001);  // a 0.01 grid is close
    EXPECT_NEAR(best.coupling.damping_n_s_per_m, brute_b_c, 0.02);
    // At the optimum the coupling impedance has a 45° phase at the binding frequency.
    const double theta = theory::normalized_frequency(best.binding_frequency_hz, 1e-3);
    const double x = best.coupling.stiffness_n_per_m * 0.5e-3 / std::tan(theta / 2);
    const double r = best.coupling.damping_n_s_per_m + best.coupling.stiffness_n_per_m * 0.5e-3;
    EXPECT_NEAR(x, r, 1e-6 * r);
    // And it agrees with the bisection at its own damping.
    EXPECT_NEAR(best.coupling.stiffness_n_per_m,
                bisect_stiffness(device, best.coupling.damping_n_s_per_m, GetParam(), 1e-3),
                1e-6 * best.coupling.stiffness_n_per_m);
}

TEST(ImpedanceSizing, InfeasibleDampingIsRejectedWithTheLargestFeasibleValue) {
    try {
        size_impedance_coupling({{0.1, 2.0}, 1000, HoldModel::encoder, 50.0});
        FAIL() << "b_c = 50 cannot meet (21)";
    } catch (const InfeasibleCoupling& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("b_c = 50"), std::string::npos) << what;
        EXPECT_NE(what.find("must be below"), std::string::npos) << what;
    }
}

TEST(ImpedanceSizing, NonPhysicalInputNamesTheValue) {
    const auto message = [](const ImpedanceSizingRequest& r) {
        try {
            size_impedance_coupling(r);
        } catch (const std::invalid_argument& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_NE(message({{-0.1, 2.0}, 1000}).find("mass m = -0.1"), std::string::npos);
    EXPECT_NE(message({{0.1, 0.0}, 1000}).find("damping b = 0"), std::string::npos);
    EXPECT_NE(message({{0.1, 2.0}, NAN}).find("rate = nan"), std::string::npos);
    EXPECT_NE(message({{0.1, 2.0}, 1000, HoldModel::encoder, -1.0}).find("b_c = -1"),
              std::string::npos);
}

// ---- The damper on a filtered velocity (theory/velocity_filter.hpp) ----

/// (21) with Z_c = b_c (1 - a)/(1 - a z⁻¹) + k_c T z/(z - 1), complex arithmetic only; the
/// passive model without delay is the hold term e^{-jθ}.
bool filtered_satisfies_21(const DeviceModel& d, double k, double b_c, double cutoff_hz,
                           HoldModel model, double period, const std::vector<double>& grid) {
    const double a = std::exp(-2.0 * std::numbers::pi * cutoff_hz * period);
    for (double theta : grid) {
        const Complex z = std::exp(Complex(0, theta));
        const Complex z_minus_1 =
            2.0 * Complex(0, std::sin(theta / 2)) * std::exp(Complex(0, theta / 2));
        const Complex zc = b_c * (1.0 - a) / (1.0 - a / z) + k * period * z / z_minus_1;
        const Complex h =
            model == HoldModel::passive ? std::exp(Complex(0, -theta)) : hold(model, theta);
        const double half = std::sin(std::arg(h) / 2.0);
        const double bound = std::abs(h) * 2.0 * half * half / (2.0 * d.damping_n_s_per_m);
        if ((1.0 / zc).real() < bound) return false;
    }
    return true;
}

double bisect_filtered_stiffness(const DeviceModel& d, double b_c, double cutoff_hz,
                                 HoldModel model, double period) {
    static const std::vector<double> grid = dense_grid(200000);
    double lo = 0.0;
    double hi = 100.0 * d.damping_n_s_per_m / period;
    while (hi - lo > 1e-10 * hi) {
        const double mid = 0.5 * (lo + hi);
        (filtered_satisfies_21(d, mid, b_c, cutoff_hz, model, period, grid) ? lo : hi) = mid;
    }
    return lo;
}

struct FilteredCase {
    DeviceModel device;
    double rate_hz;
    double b_c;
    double cutoff_hz;
    HoldModel model;
};

class FilteredAgainstBisection : public ::testing::TestWithParam<FilteredCase> {};
INSTANTIATE_TEST_SUITE_P(
    Devices, FilteredAgainstBisection,
    ::testing::Values(FilteredCase{{0.1, 2.0}, 1000, 0.5, 100.0, HoldModel::passive},
                      FilteredCase{{0.1, 2.0}, 1000, 2.0, 300.0, HoldModel::passive},
                      FilteredCase{{0.1, 2.0}, 1000, 0.5, 100.0, HoldModel::encoder},
                      FilteredCase{{0.1, 2.0}, 1000, 3.0, 30.0, HoldModel::encoder},
                      FilteredCase{{0.1, 2.0}, 1000, 1.0, 100.0, HoldModel::paper},
                      FilteredCase{{0.5, 0.4}, 2000, 0.2, 50.0, HoldModel::encoder}));

TEST_P(FilteredAgainstBisection, StiffnessAgreesToOnePartPerMillion) {
    const FilteredCase c = GetParam();
    ImpedanceSizingRequest request{c.device, c.rate_hz, c.model, c.b_c};
    request.velocity_filter_hz = c.cutoff_hz;
    const ImpedanceSizing s = size_impedance_coupling(request);
    const double reference =
        bisect_filtered_stiffness(c.device, c.b_c, c.cutoff_hz, c.model, 1.0 / c.rate_hz);
    EXPECT_NEAR(s.coupling.stiffness_n_per_m, reference, 1e-6 * reference)
        << "method " << s.report.method;
    EXPECT_EQ(s.coupling.damping_n_s_per_m, c.b_c);
    EXPECT_EQ(s.coupling.velocity_filter_hz, c.cutoff_hz);
    EXPECT_GE(s.verified_worst_margin, 0.0);
    EXPECT_LT(s.verified_worst_margin, 1e-4);
    const theory::CouplingCheck check =
        theory::check_coupling(c.device, s.coupling, c.model, c.rate_hz);
    EXPECT_TRUE(check.unconditionally_stable) << check.worst_margin;
    EXPECT_LT(check.worst_margin, 1e-4);
    if (c.model == HoldModel::passive) {
        // The closed form without delay: k_c T/2 + b_c (1 - a)/(1 + a) = b, at Nyquist.
        const double a = std::exp(-2.0 * std::numbers::pi * c.cutoff_hz / c.rate_hz);
        EXPECT_NEAR(s.coupling.stiffness_n_per_m,
                    2.0 * (c.device.damping_n_s_per_m - c.b_c * (1.0 - a) / (1.0 + a)) * c.rate_hz,
                    1e-8 * reference);
        EXPECT_NEAR(s.binding_frequency_hz, c.rate_hz / 2.0, 1e-6);
    }
}

TEST(FilteredSizing, WithADelayItIsThePassiveBisection) {
    // One period of delay: the bound binds in the band (tests/theory/velocity_filter_test.cpp
    // holds these against numpy): 1240.23684 N/m at 100 Hz, 1534.0702 N/m unfiltered.
    ImpedanceSizingRequest request{{0.1, 2.0}, 1000, {HoldModel::passive, 1.0}, 0.5};
    request.velocity_filter_hz = 100.0;
    const ImpedanceSizing filtered = size_impedance_coupling(request);
    EXPECT_NEAR(filtered.coupling.stiffness_n_per_m, 1240.23684, 1e-6 * 1240.0);
    EXPECT_NEAR(filtered.binding_frequency_hz, 135.362, 0.01);
    request.velocity_filter_hz = 0.0;
    EXPECT_NEAR(size_impedance_coupling(request).coupling.stiffness_n_per_m, 1534.0702,
                1e-6 * 1534.0);
}

class FilteredOptimizeDamping : public ::testing::TestWithParam<theory::LoopModel> {};
INSTANTIATE_TEST_SUITE_P(Models, FilteredOptimizeDamping,
                         ::testing::Values(theory::LoopModel{HoldModel::encoder},
                                           theory::LoopModel{HoldModel::passive, 1.0}));

TEST_P(FilteredOptimizeDamping, BestPairBeatsEveryDampingOnABruteForceScan) {
    const DeviceModel device{0.1, 2.0};
    const double cutoff_hz = 100.0;
    ImpedanceSizingRequest request{device, 1000, GetParam(), std::nullopt};
    request.velocity_filter_hz = cutoff_hz;
    const ImpedanceSizing best = size_impedance_coupling(request);
    EXPECT_EQ(best.report.method, "golden-section");
    double brute = 0.0;
    double brute_b_c = 0.0;
    for (const double b_c : stepped(0.0, 5.98, 0.02)) {
        request.coupling_damping_n_s_per_m = b_c;
        try {
            const double k = size_impedance_coupling(request).coupling.stiffness_n_per_m;
            if (k > brute) brute = k, brute_b_c = b_c;
        } catch (const InfeasibleCoupling&) {
        }
    }
    EXPECT_GE(best.coupling.stiffness_n_per_m, brute * (1 - 1e-9));
    EXPECT_LT(best.coupling.stiffness_n_per_m, brute * 1.001);
    EXPECT_NEAR(best.coupling.damping_n_s_per_m, brute_b_c, 0.04);
    EXPECT_GE(best.verified_worst_margin, 0.0);
    EXPECT_EQ(best.coupling.velocity_filter_hz, cutoff_hz);
}

TEST(FilteredSizing, InfeasibleDampingNamesTheFilter) {
    // Without delay the filtered damper alone meets (21) up to b_c = b (1 + a)/(1 - a) (Nyquist):
    // 6.574 N s/m at 100 Hz, against b = 2 N s/m unfiltered.
    ImpedanceSizingRequest request{{0.1, 2.0}, 1000, HoldModel::passive, 7.0};
    request.velocity_filter_hz = 100.0;
    const double a = std::exp(-2.0 * std::numbers::pi * 0.1);
    try {
        size_impedance_coupling(request);
        FAIL() << "b_c = 7 cannot meet (21)";
    } catch (const InfeasibleCoupling& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("b_c = 7"), std::string::npos) << what;
        EXPECT_NE(what.find("velocity filter at 100 Hz"), std::string::npos) << what;
        std::ostringstream limit;
        limit << "must be below " << 2.0 * (1.0 + a) / (1.0 - a);
        EXPECT_NE(what.find(limit.str().substr(0, 18)), std::string::npos) << what;
    }
    request.coupling_damping_n_s_per_m = 6.5;
    EXPECT_GT(size_impedance_coupling(request).coupling.stiffness_n_per_m, 0.0);
    request.velocity_filter_hz = 600.0;  // above Nyquist
    EXPECT_THROW(size_impedance_coupling(request), std::invalid_argument);
}

// ---- Admittance display (37) ----

TEST(AdmittanceSizing, MeetsThirtySevenWithEqualityAndIsMinimal) {
    AdmittanceSizingRequest request;
    request.device = {2.0, 5.0};
    request.loop = {10.0, 0.0};  // passive under the encoder model: b >= (4/π²)(k_p + k_i T/2)
    request.rate_hz = 1000;
    request.model = HoldModel::encoder;
    request.coupling_damping_n_s_per_m = std::nullopt;  // the best (m_c, b_c) pair
    const AdmittanceSizing s = size_admittance_coupling(request);
    EXPECT_GT(s.coupling.mass_kg, 0.0);
    EXPECT_GT(s.coupling.damping_n_s_per_m, 0.0);
    EXPECT_GT(s.verified_worst_margin, -1e-9);
    EXPECT_LT(s.verified_worst_margin, 1e-4);
    // A lighter coupling mass at the same damping breaks (37) somewhere.
    const double period = 1e-3;
    bool violated = false;
    const theory::MassDamperCoupling lighter{s.coupling.mass_kg * 0.99,
                                             s.coupling.damping_n_s_per_m};
    for (const double theta : stepped(1e-4, 3.1415, 1e-4)) {
        const double re_zca = (1.0 / theory::coupling_admittance(lighter, theta, period)).real();
        if (re_zca < theory::admittance_coupling_bound(request.device, request.loop, request.model,
                                                       theta, period)) {
            violated = true;
            break;
        }
    }
    EXPECT_TRUE(violated);
    // Given a damping, the sized mass is feasible and tight as well.
    request.coupling_damping_n_s_per_m = 2.0 * s.coupling.damping_n_s_per_m;
    const AdmittanceSizing given = size_admittance_coupling(request);
    EXPECT_GT(given.verified_worst_margin, -1e-9);
    EXPECT_LT(given.verified_worst_margin, 1e-4);
}

TEST(AdmittanceSizing, ExplainsWhyIntegralActionCannotBeCoupled) {
    // With k_i > 0, T(z) -> 1 and Re(1/Z_dA) -> 0 together as f -> 0 and the bound of (37)
    // tends to a constant, while Re(Z_cA) of a series mass-damper vanishes like f².
    AdmittanceSizingRequest request;
    request.device = {2.0, 5.0};
    request.loop = {10.0, 1000.0};
    request.model = HoldModel::encoder;
    request.coupling_damping_n_s_per_m = std::nullopt;
    try {
        size_admittance_coupling(request);
        FAIL() << "integral action cannot meet (37) at DC";
    } catch (const InfeasibleCoupling& e) {
        EXPECT_NE(std::string(e.what()).find("k_i = 1000"), std::string::npos) << e.what();
    }
}

TEST(AdmittanceSizing, ExplainsWhyALoopThatIsTooStiffCannotBeCoupled) {
    AdmittanceSizingRequest request;
    request.device = {2.0, 5.0};
    request.loop = {2000.0, 0.0};
    request.model = HoldModel::encoder;
    try {
        size_admittance_coupling(request);
        FAIL() << "k_p = 2000 makes the display active";
    } catch (const InfeasibleCoupling& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("(35)"), std::string::npos) << what;
        EXPECT_NE(what.find("k_p = 2000"), std::string::npos) << what;
    }
}

}  // namespace
}  // namespace hapticd::tune
