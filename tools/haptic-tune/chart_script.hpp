// Drawing a chart: matplotlib draws it, through tools/plot/hapticd_chart.py. The script
// runs with Debian's /usr/bin/python3 (env HAPTICD_PYTHON overrides) and gets the chart as
// one JSON document on its standard input. The script is found through env
// HAPTICD_CHART_SCRIPT, else the build-tree path, else the installed path.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "chart_options.hpp"
#include "cli_common.hpp"

namespace hapticd::tools {

/// The chart could not be drawn (no python, no matplotlib, the script failed). Reported
/// like a usage error: exit 2, with what to install or what went wrong.
class ChartError : public UsageError {
  public:
    using UsageError::UsageError;
};

/// Draws `chart` (its "kind" selects the chart: "design-procedure", "zwidth", "run" or
/// "identify-fit"; its "caption" names the model and the device) into look.out, in the
/// format its extension names, at look's size and font size. Throws ChartError when the
/// chart cannot be drawn.
void render_chart(nlohmann::ordered_json chart, const ChartLook& look);

}  // namespace hapticd::tools
