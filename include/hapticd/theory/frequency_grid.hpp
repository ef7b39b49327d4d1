// Frequency grids over (0, π] and the search for the worst point of a margin on them.
#pragma once

#include <functional>
#include <vector>

namespace hapticd::theory {

/// `points` normalised frequencies θ in (0, π]: geometric from `lowest_theta` to 0.1 so
/// the low band is resolved, then uniform to π so the band near Nyquist is too. Sorted,
/// strictly increasing, last element exactly π. Throws std::invalid_argument for fewer than
/// 16 points, a lowest_theta outside (0, 0.1), or one so close to 0.1 that the grid would
/// not be strictly increasing.
std::vector<double> frequency_grid(int points, double lowest_theta = 1e-5);

/// The smallest value of f on a grid, refined by golden-section search between the grid
/// neighbours of the best grid point.
struct GridMinimum {
    double value = 0.0;
    double theta = 0.0;
};
GridMinimum minimize_on_grid(const std::function<double(double)>& f,
                             const std::vector<double>& grid);
/// The same with f already evaluated on the grid (values[i] = f(grid[i])). Both throw
/// std::invalid_argument for an empty grid, or a table of another size than the grid.
GridMinimum minimize_tabulated(const std::function<double(double)>& f,
                               const std::vector<double>& grid, const std::vector<double>& values);

}  // namespace hapticd::theory
