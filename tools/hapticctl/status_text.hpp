// hapticctl's readable forms of a status reply (docs/control.md, "status"): the block that
// `status` prints and the one line per sample that `watch` prints; and the CSV that `stream`
// makes of telemetry events.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace hapticd::ctl {

/// Several lines: state and rate, positions and forces, faults, device and config.
std::string status_text(const nlohmann::json& status);
/// "t 12.34 s  running  1000.0 Hz  x [1.00] mm  f [-2.17] N  faults none".
std::string watch_line(const nlohmann::json& status);

/// "tick,t_s,state,x0_m,...,xe0_m,...,f0_n,...,faults": the --log's names for the columns.
std::string stream_header(int axes);
/// One CSV row of a telemetry event, full precision; faults joined by '|' ("" for none).
/// Throws nlohmann::json::exception for an event without the fields or with fewer axes.
std::string stream_row(const nlohmann::json& event, int axes);

}  // namespace hapticd::ctl
