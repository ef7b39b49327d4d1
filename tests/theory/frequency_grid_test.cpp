// The frequency grid over (0, π] (frequency_grid.hpp) and the search for a margin's worst
// point on it: the grid's endpoints, its two bands and their spacing, how it densifies with
// more points, its edge cases and the input it refuses.
#include "hapticd/theory/frequency_grid.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace hapticd::theory {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kKnee = 0.1;  // where the geometric band ends and the uniform band begins

/// The message of the std::invalid_argument that `call` throws; fails the test if it throws
/// nothing.
template <typename Call>
std::string invalid_argument_message(Call call) {
    try {
        call();
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    ADD_FAILURE() << "no std::invalid_argument";
    return {};
}

TEST(FrequencyGrid, HasThePointsAskedForFromLowestThetaToExactlyPi) {
    for (const int points : {16, 17, 100, 1001, 4096}) {
        for (const double lowest : {1e-6, 1e-5, 0.05}) {
            const std::vector<double> grid = frequency_grid(points, lowest);
            ASSERT_EQ(grid.size(), static_cast<std::size_t>(points));
            EXPECT_EQ(grid.front(), lowest) << points << " points";
            EXPECT_EQ(grid.back(), kPi) << points << " points";
        }
    }
}

TEST(FrequencyGrid, DefaultLowestThetaIsTenToTheMinusFive) {
    EXPECT_EQ(frequency_grid(64).front(), 1e-5);
    EXPECT_EQ(frequency_grid(64), frequency_grid(64, 1e-5));
}

TEST(FrequencyGrid, SixteenPointsAreFourDecadesThenTwelveUniformToPi) {
    // A quarter of the points are geometric from 1e-5 to the knee: ratio (0.1/1e-5)^(1/4) =
    // 10, one point per decade. The other twelve start at the knee in steps of
    // (π - 0.1)/12.
    const std::vector<double> grid = frequency_grid(16, 1e-5);
    const double decades[] = {1e-5, 1e-4, 1e-3, 1e-2};
    for (std::size_t i = 0; i < 4; ++i) EXPECT_NEAR(grid[i], decades[i], 1e-15 * decades[i]);
    const double step = (kPi - kKnee) / 12.0;
    EXPECT_EQ(grid[4], kKnee);
    for (std::size_t i = 5; i < 15; ++i) {
        EXPECT_NEAR(grid[i], kKnee + step * static_cast<double>(i - 4), 1e-14) << i;
    }
    EXPECT_NEAR(grid[14], kPi - 2.0 * step, 1e-14);
    EXPECT_EQ(grid[15], kPi);
}

TEST(FrequencyGrid, LowBandHasOneRatioAndUniformBandOneStep) {
    // 1000 points: 250 geometric (ratio (0.1/1e-6)^(1/250)), 750 uniform (step (π-0.1)/750).
    // The uniform band's last point is moved from π - step onto π, so its last gap is two
    // steps.
    const int points = 1000;
    const double lowest = 1e-6;
    const std::vector<double> grid = frequency_grid(points, lowest);
    const std::size_t geometric = points / 4;
    const double ratio = std::pow(kKnee / lowest, 1.0 / static_cast<double>(geometric));
    for (std::size_t i = 1; i < geometric; ++i) {
        EXPECT_NEAR(grid[i] / grid[i - 1], ratio, 1e-12) << i;
    }
    EXPECT_NEAR(grid[geometric - 1] * ratio, kKnee, 1e-12);  // the band ends one ratio short
    EXPECT_EQ(grid[geometric], kKnee);
    const double step = (kPi - kKnee) / static_cast<double>(points - geometric);
    for (std::size_t i = geometric + 1; i + 1 < grid.size(); ++i) {
        EXPECT_NEAR(grid[i] - grid[i - 1], step, 1e-12) << i;
    }
    EXPECT_NEAR(grid[points - 1] - grid[points - 2], 2.0 * step, 1e-12);
}

TEST(FrequencyGrid, IsStrictlyIncreasing) {
    for (int points = 16; points <= 600; points += 7) {
        for (const double lowest : {1e-9, 1e-6, 1e-5, 1e-3, 0.09, 0.0999999}) {
            const std::vector<double> grid = frequency_grid(points, lowest);
            for (std::size_t i = 1; i < grid.size(); ++i) {
                ASSERT_LT(grid[i - 1], grid[i]) << points << " points from " << lowest << ", " << i;
            }
        }
    }
}

TEST(FrequencyGrid, MorePointsMakeBothBandsDenser) {
    // Doubling the points (a multiple of four: the bands split exactly) halves the uniform
    // step and takes the square root of the geometric ratio.
    const double lowest = 1e-5;
    double last_ratio = 0.0;
    double last_step = 0.0;
    for (const int points : {64, 128, 256, 512, 1024, 2048}) {
        const std::vector<double> grid = frequency_grid(points, lowest);
        const int geometric = points / 4;
        const int uniform = points - geometric;
        const double ratio = grid[1] / grid[0];
        const double step = grid[geometric + 1] - grid[geometric];
        EXPECT_NEAR(ratio, std::pow(kKnee / lowest, 1.0 / geometric), 1e-12) << points;
        EXPECT_NEAR(step, (kPi - kKnee) / uniform, 1e-12) << points;
        if (last_step > 0.0) {
            EXPECT_NEAR(ratio, std::sqrt(last_ratio), 1e-12) << points;
            EXPECT_NEAR(step, last_step / 2.0, 1e-12) << points;
        }
        last_ratio = ratio;
        last_step = step;
    }
}

TEST(FrequencyGrid, LowBandResolvesLowFrequenciesFinerThanTheUniformBand) {
    // The reason for the two bands: the relative spacing (θ[i+1] - θ[i]) / θ[i] stays
    // ratio - 1 all the way down the geometric band, where a uniform grid of as many points
    // would start at π/points, above half of its four decades. 1024 points from 1e-5: 256
    // over four decades (64 a decade, 3.7 % apart); at the knee the uniform band is 4 % apart.
    const std::vector<double> grid = frequency_grid(1024, 1e-5);
    const double relative_low = grid[1] / grid[0] - 1.0;
    EXPECT_NEAR(relative_low, std::pow(10.0, 4.0 / 256.0) - 1.0, 1e-12);
    EXPECT_LT(relative_low, 0.04);
    const double relative_at_knee = (grid[257] - grid[256]) / grid[256];
    EXPECT_GT(relative_at_knee, relative_low);
    std::size_t below_knee = 0;
    for (const double theta : grid) below_knee += theta < kKnee ? 1 : 0;
    EXPECT_EQ(below_knee, 256u);
    EXPECT_NEAR(grid[128], 1e-3, 1e-15);
    EXPECT_GT(kPi / 1024.0, grid[128]);  // a uniform grid's first point, 3e-3, is above 1e-3
}

TEST(FrequencyGrid, AnOddNumberOfPointsGivesTheRemainderToTheUniformBand) {
    // 19 points: 19/4 = 4 geometric, 15 uniform.
    const std::vector<double> grid = frequency_grid(19, 1e-4);
    ASSERT_EQ(grid.size(), 19u);
    EXPECT_LT(grid[3], kKnee);
    EXPECT_EQ(grid[4], kKnee);
    EXPECT_NEAR(grid[5] - grid[4], (kPi - kKnee) / 15.0, 1e-15);
}

TEST(FrequencyGrid, LowestThetaJustBelowTheKneeStillGivesAStrictlyIncreasingGrid) {
    const std::vector<double> grid = frequency_grid(16, 0.0999);
    for (std::size_t i = 1; i < grid.size(); ++i) EXPECT_LT(grid[i - 1], grid[i]) << i;
    EXPECT_EQ(grid.front(), 0.0999);
    EXPECT_EQ(grid[4], kKnee);
}

TEST(FrequencyGrid, RefusesFewerThanSixteenPoints) {
    for (const int points : {15, 1, 0, -16}) {
        EXPECT_EQ(invalid_argument_message([&] { (void)frequency_grid(points); }),
                  "frequency_grid: need at least 16 points")
            << points;
    }
    EXPECT_EQ(frequency_grid(16).size(), 16u);
}

TEST(FrequencyGrid, RefusesALowestThetaOutsideZeroToTheKnee) {
    for (const double lowest : {0.0, -1e-5, 0.1, 0.2, kPi, std::numeric_limits<double>::infinity(),
                                std::numeric_limits<double>::quiet_NaN()}) {
        EXPECT_EQ(invalid_argument_message([&] { (void)frequency_grid(64, lowest); }),
                  "frequency_grid: lowest_theta must be in (0, 0.1)")
            << lowest;
    }
}

TEST(FrequencyGrid, RefusesALowestThetaTooCloseToTheKneeForAnIncreasingLowBand) {
    // One ulp below 0.1 the geometric ratio rounds to exactly 1: every low-band point would
    // be the same θ, and the grid would not be strictly increasing as promised.
    const double lowest = std::nextafter(kKnee, 0.0);
    const std::string message = invalid_argument_message([&] { (void)frequency_grid(64, lowest); });
    EXPECT_NE(message.find("frequency_grid: lowest_theta = 0.09999999999999999"), std::string::npos)
        << message;
    EXPECT_NE(message.find("too close to 0.1 for 64 points"), std::string::npos) << message;
}

// ---- minimize_on_grid, minimize_tabulated ----

TEST(MinimizeOnGrid, RefinesAMinimumBetweenGridPointsByGoldenSection) {
    // A parabola whose vertex lies between two grid points: the grid alone is off by up to
    // half a step in θ; the golden-section search finds the vertex.
    const std::vector<double> grid = frequency_grid(64);
    for (const double vertex : {1e-4, 0.0123, 0.7, 2.0, 3.1}) {
        const auto f = [vertex](double theta) {
            return -1.5 + (theta - vertex) * (theta - vertex) / (vertex * vertex);
        };
        const GridMinimum minimum = minimize_on_grid(f, grid);
        EXPECT_NEAR(minimum.theta, vertex, 1e-7 * vertex) << vertex;
        EXPECT_NEAR(minimum.value, -1.5, 1e-12) << vertex;
    }
}

TEST(MinimizeOnGrid, FindsTheDeeperOfTwoMinima) {
    const std::vector<double> grid = frequency_grid(256);
    const auto f = [](double theta) {
        return std::min((theta - 0.5) * (theta - 0.5) - 1.0, (theta - 2.5) * (theta - 2.5) - 2.0);
    };
    const GridMinimum minimum = minimize_on_grid(f, grid);
    EXPECT_NEAR(minimum.theta, 2.5, 1e-7);
    EXPECT_NEAR(minimum.value, -2.0, 1e-12);
}

TEST(MinimizeOnGrid, AMinimumAtAnEndOfTheGridIsThatEnd) {
    const std::vector<double> grid = frequency_grid(64);
    const auto rising = [](double theta) { return 3.0 * theta + 1.0; };
    const GridMinimum low = minimize_on_grid(rising, grid);
    EXPECT_EQ(low.theta, grid.front());
    EXPECT_EQ(low.value, rising(grid.front()));
    const auto falling = [](double theta) { return std::cos(theta / 2.0); };
    const GridMinimum high = minimize_on_grid(falling, grid);
    EXPECT_EQ(high.theta, kPi);
    EXPECT_EQ(high.value, falling(kPi));
}

TEST(MinimizeTabulated, UsesTheTableAndEvaluatesOnlyTheRefinement) {
    // The same answer as minimize_on_grid, with f called only by the golden-section search
    // (two points to start, one per iteration, at most 80 iterations), never on the grid.
    const std::vector<double> grid = frequency_grid(512);
    const auto f = [](double theta) { return std::sin(3.0 * theta) + 0.1 * theta; };
    std::vector<double> values;
    values.reserve(grid.size());
    for (const double theta : grid) values.push_back(f(theta));
    int calls = 0;
    const auto counted = [&](double theta) {
        ++calls;
        return f(theta);
    };
    const GridMinimum tabulated = minimize_tabulated(counted, grid, values);
    const GridMinimum direct = minimize_on_grid(f, grid);
    EXPECT_EQ(tabulated.theta, direct.theta);
    EXPECT_EQ(tabulated.value, direct.value);
    EXPECT_GE(calls, 2);
    EXPECT_LE(calls, 82);
    // sin(3θ) + 0.1θ is smallest where 3 cos(3θ) = -0.1, near θ = π/2 (sin(3π/2) = -1).
    const double vertex = (kPi + std::acos(1.0 / 30.0)) / 3.0;
    EXPECT_NEAR(tabulated.theta, vertex, 1e-7);
    EXPECT_NEAR(tabulated.value, f(vertex), 1e-13);
}

TEST(MinimizeTabulated, ThePointOfTheSmallestTableValueChoosesTheBracket) {
    // The table, not f, says where to refine: a table whose smallest value is at grid[10]
    // makes the search refine in [grid[9], grid[11]] even if f is smaller elsewhere.
    const std::vector<double> grid = frequency_grid(64);
    std::vector<double> values(grid.size(), 1.0);
    values[10] = 0.0;
    const auto f = [](double theta) { return theta; };  // smallest at grid[0]
    const GridMinimum minimum = minimize_tabulated(f, grid, values);
    EXPECT_GE(minimum.theta, grid[9]);
    EXPECT_LE(minimum.theta, grid[11]);
    EXPECT_EQ(minimum.theta, grid[10]);  // f > 0 = values[10] everywhere in the bracket
    EXPECT_EQ(minimum.value, 0.0);
}

TEST(MinimizeTabulated, RefusesATableOfAnotherSizeOrAnEmptyGrid) {
    const std::vector<double> grid = frequency_grid(16);
    const std::vector<double> short_table(15, 0.0);
    const auto f = [](double theta) { return theta; };
    EXPECT_EQ(invalid_argument_message([&] { (void)minimize_tabulated(f, grid, short_table); }),
              "minimize_tabulated: 15 values for a grid of 16 points");
    EXPECT_EQ(invalid_argument_message([&] { (void)minimize_tabulated(f, {}, {}); }),
              "minimize_tabulated: the grid is empty");
    EXPECT_EQ(invalid_argument_message([&] { (void)minimize_on_grid(f, {}); }),
              "minimize_tabulated: the grid is empty");
}

}  // namespace
}  // namespace hapticd::theory
