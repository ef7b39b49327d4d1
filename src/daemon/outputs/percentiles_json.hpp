// The percentiles of wake-up latency and tick compute as JSON, one shape for the --summary
// (summary_json.cpp) and the control socket's status (socket/requests.cpp): the same keys
// in the same order, in microseconds. Json: nlohmann::json or nlohmann::ordered_json.
#pragma once

#include <nlohmann/json.hpp>

#include "hapticd/servo/summary.hpp"

namespace hapticd::daemon {

template <typename Json>
Json percentiles_json(const servo::WakeLatencySummaryUs& p) {
    return Json{{"p50", p.p50}, {"p99", p.p99}, {"p999", p.p999}, {"max", p.max}};
}

template <typename Json>
Json percentiles_json(const servo::TickComputeSummaryUs& p) {
    return Json{{"p50", p.p50}, {"p99", p.p99}, {"max", p.max}};
}

}  // namespace hapticd::daemon
