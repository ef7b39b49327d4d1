// --operator-class FILE and --scene FILE: what a verdict or a design assumes about the
// operator and the environment (tune/class_check.hpp). Without them: every passive
// operator and every passive environment.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "hapticd/tune/class_check.hpp"

namespace hapticd::tools {

struct AssumptionOptions {
    std::string operator_class_path;  ///< a TOML file with an [operator] table
    std::string scene_path;           ///< a scene TOML
};

void add_assumption_options(CLI::App& command, AssumptionOptions& options);

/// Reads the files. Throws daemon::ConfigError naming the file, key and value; UsageError
/// when an operator class is given to a model other than exact.
tune::StabilityAssumption resolve_assumption(const AssumptionOptions& options,
                                             const std::string& model);

}  // namespace hapticd::tools
