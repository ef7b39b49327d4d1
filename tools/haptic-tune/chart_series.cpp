#include "chart_series.hpp"

#include <algorithm>

namespace hapticd::tools {

nlohmann::ordered_json chart_series(const std::vector<double>& t, const std::vector<double>& y,
                                    std::size_t max_points) {
    const std::size_t rows = std::min(t.size(), y.size());
    if (rows <= max_points || max_points < 2) {
        return {
            {"t_s", std::vector<double>(t.begin(), t.begin() + static_cast<std::ptrdiff_t>(rows))},
            {"value",
             std::vector<double>(y.begin(), y.begin() + static_cast<std::ptrdiff_t>(rows))}};
    }
    const std::size_t stretches = max_points / 2;
    std::vector<double> kept_t;
    std::vector<double> kept_y;
    kept_t.reserve(2 * stretches);
    kept_y.reserve(2 * stretches);
    for (std::size_t k = 0; k < stretches; ++k) {
        const auto begin = static_cast<std::ptrdiff_t>(k * rows / stretches);
        const auto end = static_cast<std::ptrdiff_t>((k + 1) * rows / stretches);
        const auto [low, high] = std::minmax_element(y.begin() + begin, y.begin() + end);
        for (const auto at : {std::min(low, high), std::max(low, high)}) {
            const auto row = static_cast<std::size_t>(at - y.begin());
            kept_t.push_back(t[row]);
            kept_y.push_back(y[row]);
        }
    }
    return {{"t_s", kept_t}, {"value", kept_y}};
}

}  // namespace hapticd::tools
