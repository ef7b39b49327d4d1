#include "chart_script.hpp"

#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "child_process.hpp"
#include "hapticd/install/layout.hpp"

namespace hapticd::tools {
namespace {

constexpr const char* kDefaultPython = "/usr/bin/python3";
/// hapticd_chart.py exits with this code when it cannot import matplotlib.
constexpr int kScriptNoMatplotlib = 3;
constexpr const char* kInstallHint =
    "install python3-matplotlib (Debian/Ubuntu: apt install python3-matplotlib), or set "
    "HAPTICD_PYTHON to a python interpreter that has matplotlib";

std::string env_or_empty(const char* name) {
    const char* value = std::getenv(name);
    return value == nullptr ? std::string() : std::string(value);
}

bool is_regular_file(const std::string& path) {
    std::error_code error;
    return std::filesystem::is_regular_file(path, error);
}

std::string find_chart_script() {
    if (std::string from_env = env_or_empty("HAPTICD_CHART_SCRIPT"); !from_env.empty()) {
        if (!is_regular_file(from_env)) {
            throw ChartError("HAPTICD_CHART_SCRIPT=" + from_env + " is not a file");
        }
        return from_env;
    }
    const std::string& script = install::layout().chart_script;
    if (is_regular_file(script)) return script;
    throw ChartError("chart script hapticd_chart.py not found at " + script +
                     " (this haptic-tune's own copy); set HAPTICD_CHART_SCRIPT to its path");
}

}  // namespace

void render_chart(nlohmann::ordered_json chart, const ChartLook& look) {
    const std::string& out_path = look.out;
    std::string python = env_or_empty("HAPTICD_PYTHON");
    if (python.empty()) python = kDefaultPython;
    const std::string script = find_chart_script();
    chart["output"] = chart_output_json(look);
    ChildOptions options;
    options.capture = true;  // its stdout too: haptic-tune's own stdout may carry --json
    options.input = chart.dump();
    const ChildRun run = run_child({python, script}, options);
    if (!run.started()) {
        throw ChartError("cannot run the python interpreter '" + python +
                         "': " + std::strerror(run.spawn_error) + "; " + kInstallHint);
    }
    const std::string said = trimmed(run.output);
    if (run.exit_code == kScriptNoMatplotlib) {
        throw ChartError("cannot draw the chart: " + python + " has no matplotlib; " +
                         kInstallHint + (said.empty() ? "" : " (" + said + ")"));
    }
    if (!run.succeeded()) {
        throw ChartError("chart script " + script + " (run with " + python + ") " +
                         run.describe_exit() + (said.empty() ? std::string() : ":\n" + said));
    }
    std::error_code error;
    if (!std::filesystem::is_regular_file(out_path, error) ||
        std::filesystem::file_size(out_path, error) == 0) {
        throw ChartError("chart script " + script + " reported success but wrote no " + out_path);
    }
}

}  // namespace hapticd::tools
