// haptic-tune diag: the first command a lab runs on new hardware. Drives the configured
// device at zero force and reports round-trip times, lost and late frames, the device
// clock's drift, and the loop delay from the encoder sample to the force taking effect when
// the device says when its commands take effect (tools/haptic-tune/link_diag.hpp,
// docs/link-diagnostics.md).
#include <iostream>
#include <memory>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticd/daemon/config.hpp"
#include "link_diag.hpp"

namespace hapticd::tools {
namespace {

struct DiagCommandOptions {
    std::string config_path;
    double duration_s = 5.0;
    bool json = false;
    bool lockstep = false;
};

int run_diag(const DiagCommandOptions& o) {
    daemon::Config config;
    try {
        config = load_config_as_hapticd(o.config_path);
    } catch (const daemon::ConfigError& e) {
        throw UsageError(e.what());
    }
    daemon::DiagOptions options;
    options.duration_s = o.duration_s;
    options.lockstep = o.lockstep;
    daemon::DiagReport report;
    try {
        report = daemon::run_link_diag(config, options, std::cerr);
    } catch (const std::invalid_argument& e) {
        throw UsageError(e.what());
    } catch (const std::exception& e) {
        std::cerr << "haptic-tune: device error: " << e.what() << '\n';
        return kExitBadInput;
    }
    std::cout << (o.json ? daemon::diag_json(report) + "\n" : daemon::diag_text(report))
              << std::flush;
    return report.verdict().ok() ? kExitOk : kExitVerdictNo;
}

}  // namespace

void add_diag_command(CLI::App& app, Invocation& invocation) {
    auto options = std::make_shared<DiagCommandOptions>();
    CLI::App* command = app.add_subcommand(
        "diag",
        "Diagnose the device link: run the configured device at zero force and report the "
        "round-trip time histogram, lost and late frames, the device clock's drift, and the "
        "loop delay (sample to force, median and p99, host and link parts, and the value for "
        "[device.model] delay) when the device reports when commands take effect (protocol "
        "version 2). Exit 0 if the link keeps up with [servo] rate_hz and the config's delay "
        "covers the measured one, 1 if not, 2 on bad input");
    command->add_option("--config", options->config_path, "hapticd config file (TOML)")
        ->required()
        ->check(CLI::ExistingFile);
    command->add_option("--duration", options->duration_s, "seconds to run (default 5)")
        ->check(CLI::Range(0.001, 3600.0));
    command->add_flag("--json", options->json, "print the report as JSON");
    command->add_flag("--lockstep", options->lockstep,
                      "virtual time (tests; round trips and drift are then not physical)");
    command->callback(
        [options, &invocation] { invocation.run = [options] { return run_diag(*options); }; });
}

}  // namespace hapticd::tools
