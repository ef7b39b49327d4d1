// hapticctl's readable forms of a status reply (docs/control.md, "status"): the block that
// `status` prints and the one line per sample that `watch` prints.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace hapticd::ctl {

/// Several lines: state and rate, positions and forces, faults, device and config.
std::string status_text(const nlohmann::json& status);
/// "t 12.34 s  running  1000.0 Hz  x [1.00] mm  f [-2.17] N  faults none".
std::string watch_line(const nlohmann::json& status);

}  // namespace hapticd::ctl
