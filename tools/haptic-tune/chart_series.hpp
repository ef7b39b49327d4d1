// A time series for a chart: every sample of a short log, and for a long one the extremes
// of each stretch, so that a spike or a limit cycle shows in a chart of an hour's run as it
// does in a chart of a second's (min-max decimation, as an oscilloscope's peak detect).
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <vector>

namespace hapticd::tools {

/// Points a chart's series keeps at most.
inline constexpr std::size_t kMaxSeriesPoints = 20000;

/// {"t_s": [...], "value": [...]}: every (t, y) when there are at most `max_points`; else,
/// for each of max_points/2 equal stretches of samples, its smallest and largest y in time
/// order. t and y have the same size.
nlohmann::ordered_json chart_series(const std::vector<double>& t, const std::vector<double>& y,
                                    std::size_t max_points = kMaxSeriesPoints);

}  // namespace hapticd::tools
