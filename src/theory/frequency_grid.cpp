#include "hapticd/theory/frequency_grid.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <functional>
#include <numbers>
#include <stdexcept>
#include <string>

namespace hapticd::theory {
namespace {

/// The shortest text that reads back as `value`.
std::string shortest(double value) {
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
    return {buffer, result.ptr};
}

}  // namespace

std::vector<double> frequency_grid(int points, double lowest_theta) {
    constexpr double kKnee = 0.1;
    if (points < 16) throw std::invalid_argument("frequency_grid: need at least 16 points");
    if (!(lowest_theta > 0.0 && lowest_theta < kKnee)) {
        throw std::invalid_argument("frequency_grid: lowest_theta must be in (0, 0.1)");
    }
    const int geometric = points / 4;
    const int uniform = points - geometric;
    std::vector<double> grid;
    grid.reserve(static_cast<std::size_t>(points));
    const double ratio = std::pow(kKnee / lowest_theta, 1.0 / geometric);
    double theta = lowest_theta;
    for (int i = 0; i < geometric; ++i, theta *= ratio) grid.push_back(theta);
    const double step = (std::numbers::pi - kKnee) / uniform;
    for (int i = 0; i < uniform; ++i) grid.push_back(kKnee + step * i);
    grid.back() = std::numbers::pi;
    // So close to the knee the ratio rounds to 1 and the low band would repeat one θ.
    if (std::adjacent_find(grid.begin(), grid.end(), std::greater_equal<>()) != grid.end()) {
        throw std::invalid_argument("frequency_grid: lowest_theta = " + shortest(lowest_theta) +
                                    " is too close to 0.1 for " + std::to_string(points) +
                                    " points: the grid would not be strictly increasing");
    }
    return grid;
}

GridMinimum minimize_on_grid(const std::function<double(double)>& f,
                             const std::vector<double>& grid) {
    std::vector<double> values;
    values.reserve(grid.size());
    for (double theta : grid) values.push_back(f(theta));
    return minimize_tabulated(f, grid, values);
}

GridMinimum minimize_tabulated(const std::function<double(double)>& f,
                               const std::vector<double>& grid, const std::vector<double>& values) {
    if (grid.empty()) throw std::invalid_argument("minimize_tabulated: the grid is empty");
    if (values.size() != grid.size()) {
        throw std::invalid_argument("minimize_tabulated: " + std::to_string(values.size()) +
                                    " values for a grid of " + std::to_string(grid.size()) +
                                    " points");
    }
    std::size_t best = 0;
    double best_value = values[0];
    for (std::size_t i = 1; i < grid.size(); ++i) {
        const double v = values[i];
        if (v < best_value) {
            best_value = v;
            best = i;
        }
    }
    // Golden-section between the neighbours; the grid is fine enough that the bracket
    // holds a single minimum.
    double lo = grid[best == 0 ? 0 : best - 1];
    double hi = grid[best + 1 == grid.size() ? best : best + 1];
    const double inv_phi = (std::sqrt(5.0) - 1.0) / 2.0;
    double x1 = hi - inv_phi * (hi - lo);
    double x2 = lo + inv_phi * (hi - lo);
    double f1 = f(x1);
    double f2 = f(x2);
    for (int i = 0; i < 80 && hi - lo > 1e-13 * hi; ++i) {
        if (f1 < f2) {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - inv_phi * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + inv_phi * (hi - lo);
            f2 = f(x2);
        }
    }
    GridMinimum result{best_value, grid[best]};
    if (f1 < result.value) result = {f1, x1};
    if (f2 < result.value) result = {f2, x2};
    return result;
}

}  // namespace hapticd::theory
