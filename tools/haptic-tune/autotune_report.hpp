// What haptic-tune autotune reports: the outcome of one run, as text or as JSON
// (docs/autotune.md "Output").
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "config_editor.hpp"
#include "hapticd/daemon/startup_check.hpp"
#include "hapticd/tune/autotune.hpp"
#include "loop_delay.hpp"

namespace hapticd::tools {

struct Outcome {
    std::string config_path;
    std::string log_path;
    bool log_kept = true;
    tune::AutotuneResult result;
    std::vector<daemon::ConfigChange> changes;
    std::optional<daemon::StartupCheck> startup;
    std::string backup_path;   ///< empty: nothing written
    std::string written_path;  ///< the file written: the config resolved through symlinks
    bool dry_run = false;
    LoopDelay delay;
};

/// The outcome as one JSON object (--json).
nlohmann::ordered_json outcome_json(const Outcome& o);
/// The outcome as text on standard output.
void print_text(const Outcome& o);

}  // namespace hapticd::tools
