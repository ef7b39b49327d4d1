// The trajectory judge (tune/oscillation.hpp) on traces whose growth is known: a sine whose
// envelope is e^{σt}, riding on a ramp (the operating point creeping), sampled at 1 kHz.
#include "hapticd/tune/oscillation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace hapticd::tune {
namespace {

constexpr double kPeriodS = 1e-3;

std::vector<double> trace(double growth_per_s, double amplitude_m, double seconds) {
    std::vector<double> x(static_cast<std::size_t>(seconds / kPeriodS));
    for (std::size_t i = 0; i < x.size(); ++i) {
        const double t = static_cast<double>(i) * kPeriodS;
        x[i] = 2e-3 * t + amplitude_m * std::exp(growth_per_s * t) *
                              std::sin(2.0 * std::numbers::pi * 63.0 * t);
    }
    return x;
}

TEST(Oscillation, FitsTheEnvelopesGrowthThroughTheRamp) {
    for (const double sigma : {-8.0, 5.0, 23.5}) {
        const OscillationTrend trend = oscillation_trend(trace(sigma, 1e-4, 2.0), kPeriodS, 0, 50,
                                                         1e-12);  // below every window
        EXPECT_NEAR(trend.growth_per_s, sigma, 0.03 * std::abs(sigma)) << sigma;
        EXPECT_EQ(trend.amplitude_m.size(), 40u);
        EXPECT_NEAR(trend.window_s, 0.05, 1e-12);
    }
}

TEST(Oscillation, AStillTraceStaysAtTheFloorAndDoesNotGrow) {
    const OscillationTrend trend = oscillation_trend(trace(0.0, 0.0, 1.0), kPeriodS, 0, 100, 3e-6);
    EXPECT_NEAR(trend.growth_per_s, 0.0, 1e-12);
    EXPECT_EQ(trend.rise_growth_per_s, 0.0);
    EXPECT_EQ(trend.peak_amplitude_m, 3e-6);
}

TEST(Oscillation, TheRiseIsFittedFromTheFloorToHalfThePeak) {
    // Still at the floor for 1 s, then growing at 20/s until it saturates at 1 mm.
    std::vector<double> x(3000, 0.0);
    for (std::size_t i = 1000; i < x.size(); ++i) {
        const double t = static_cast<double>(i - 1000) * kPeriodS;
        x[i] =
            std::min(1e-3, 1e-6 * std::exp(20.0 * t)) * std::sin(2.0 * std::numbers::pi * 63.0 * t);
    }
    const OscillationTrend trend = oscillation_trend(x, kPeriodS, 0, 50, 1e-6);
    EXPECT_NEAR(trend.rise_growth_per_s, 20.0, 3.0);
    EXPECT_GT(trend.rise_factor(), 500.0);
    std::size_t windows = 0;
    const OscillationTrend grown = oscillation_trend(x, kPeriodS, 1000, 50, 1e-6);
    EXPECT_NEAR(linear_phase_growth_per_s(grown, 0.0, 0.5e-3, windows), 20.0, 1.0);
    // Peak to peak 2 e^{20 t} um reaches 0.5 mm at ln(250)/20 = 0.276 s: in the 6th window.
    EXPECT_EQ(windows, 5u);
}

}  // namespace
}  // namespace hapticd::tune
