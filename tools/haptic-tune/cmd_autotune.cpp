// haptic-tune autotune: from the device to verified coupling gains in its config, in one
// command (docs/autotune.md). The computing half (identify, size, verify) is
// tune::autotune (hapticd/tune/autotune.hpp). This file orders the steps and holds the
// command line: the config is read and checked, the run's log placed (autotune_run_log.hpp),
// the loop delay found (loop_delay.hpp), `hapticd --identify` run when no --log is given
// (excitation_child.hpp), the gains identified, sized and verified, the config edited
// keeping its comments, checked as the daemon checks it at start-up and written with a
// backup, and the outcome reported (autotune_report.hpp).
//
// Exit 0 written (or would be, --dry-run); 1 the exact model rejects the gains (nothing
// written); 2 bad usage or input, a log that cannot identify the device, a failed
// identification run, an unknown loop delay, or a config that cannot be edited or written
// (nothing changed).
#include <iostream>
#include <memory>

#include "autotune_error.hpp"
#include "autotune_report.hpp"
#include "autotune_run_log.hpp"
#include "cli_common.hpp"
#include "commands.hpp"
#include "config_editor.hpp"
#include "excitation_child.hpp"
#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/output_files.hpp"
#include "hapticd/daemon/startup_check.hpp"
#include "hapticd/input/text_input.hpp"
#include "hapticd/tune/autotune.hpp"
#include "hapticd/tune/input_checks.hpp"
#include "loop_delay.hpp"

namespace hapticd::tools {
namespace {

struct AutotuneCliOptions {
    std::string config_path;
    std::string log_path;     ///< --log: identify from this log; empty: run hapticd --identify
    std::string record_path;  ///< --record: where the run's log goes (kept)
    std::string hapticd_path;
    double margin = tune::kDefaultAutotuneMargin;
    bool optimize_damping = false;
    std::optional<double> delay_s;  ///< --delay; default [device.model] delay
    bool lockstep = false;          ///< --lockstep; also a sim device on its lockstep clock
    bool dry_run = false;
    bool json = false;
};

/// From the run's log (or --log) to the written config; every failure throws (the caller
/// adds where the run's log is). Exit 0 written, 1 the exact model rejects the gains.
int identify_size_and_write(const AutotuneCliOptions& o, const daemon::Config& config,
                            const std::string& original, const tune::AutotuneOptions& options,
                            Outcome& outcome, RunLog& run_log) {
    tune::TelemetryLog log;
    try {
        log =
            tune::read_telemetry_log(outcome.log_path, tune::TelemetryLogOptions::identification());
    } catch (const tune::LogFormatError& e) {
        throw input::with_context("bad log: ", e);
    }
    if (log.axes != config.device.axes) {
        throw AutotuneError(outcome.log_path + " has " + std::to_string(log.axes) +
                            " axes (x{i}_m and "
                            "f{i}_n), but " +
                            o.config_path + " says [device] axes = " +
                            std::to_string(config.device.axes) + ": is it a run of this device?");
    }
    try {
        outcome.result = tune::autotune(log, options);
    } catch (const tune::IdentificationRefused& e) {
        throw AutotuneError(outcome.log_path + ": cannot identify the device: " + e.what() + " [" +
                            std::string(tune::to_string(e.reason())) + "]");
    }
    if (outcome.delay.source == DelaySource::none) {
        outcome.result.warnings.push_back(
            "sized for no loop delay: none was measured (from --log there is no device to run) "
            "or stated; a device on the open protocol has at least one period "
            "(docs/stability-models.md): measure it with haptic-tune diag and give --delay");
    }
    const tune::AutotuneResult& result = outcome.result;

    if (!result.verified) {
        if (o.json) {
            print_result(outcome_json(outcome), true);
        } else {
            print_text(outcome);
        }
        std::cerr << "haptic-tune: autotune: " << o.config_path
                  << " not written: " << result.verdict << run_log.note() << '\n';
        return kExitVerdictNo;
    }

    // Edit the text, then hold the edited config to what the daemon will check at start-up.
    daemon::EditedConfig edited;
    try {
        std::vector<daemon::ConfigEdit> edits{
            {"device.model", "mass", result.device.mass_kg},
            {"device.model", "damping", result.device.damping_n_s_per_m},
            {"coupling", "stiffness", result.coupling.stiffness_n_per_m},
            {"coupling", "damping", result.coupling.damping_n_s_per_m}};
        // The delay the gains were sized for goes with them (a zero delay that nothing
        // stated or measured is not added).
        if (outcome.delay.source != DelaySource::none || options.delay_periods > 0.0) {
            edits.push_back({"device.model", "delay", options.delay_periods / options.rate_hz});
        }
        edited = daemon::edit_config_text(original, edits, o.config_path);
    } catch (const daemon::ConfigEditError& e) {
        throw input::with_context("", e, "; nothing was written");
    }
    outcome.changes = edited.changes;
    try {
        const daemon::Config tuned =
            daemon::parse_config(edited.text, o.config_path, config.base_dir);
        outcome.startup = daemon::check_coupling_at_startup(tuned);
    } catch (const daemon::ConfigError& e) {
        throw input::with_context("the edited config would not load: ", e, "; nothing was written");
    }
    if (!outcome.startup->passed && !outcome.startup->skipped) {
        throw AutotuneError("the daemon's start-up check would refuse the edited config: " +
                            outcome.startup->describe() + "; nothing was written");
    }

    if (!o.dry_run) {
        // The file the config resolves to is replaced (a symlink stays one) by a temporary
        // made exclusively beside it, with its mode and owner, after an exclusive backup; a
        // config without its owner's write bit is refused (tools/haptic-tune/config_editor.hpp).
        const daemon::WrittenConfig written =
            daemon::write_config_with_backup(o.config_path, original, edited.text);
        outcome.backup_path = written.backup;
        outcome.written_path = written.target;
    }
    // Done: the run's temporary log is not needed any more.
    outcome.log_kept = !run_log.temporary();
    run_log.discard();
    if (o.json) {
        print_result(outcome_json(outcome), true);
    } else {
        print_text(outcome);
    }
    return kExitOk;
}

int run_autotune(const AutotuneCliOptions& o) {
    tune::AutotuneOptions options;
    options.margin = o.margin;
    options.optimize_damping = o.optimize_damping;

    // The config first: a config the daemon would refuse is refused before any run.
    daemon::Config config;
    try {
        config = load_config_as_hapticd(o.config_path);
    } catch (const daemon::ConfigError& e) {
        throw input::with_context("the config does not load: ", e);
    }
    const std::string original = input::read_text_file(o.config_path, "the config file");
    if (!o.dry_run) {
        // A config that may not be replaced is refused before the run, not after it.
        try {
            daemon::check_config_writable(o.config_path);
        } catch (const daemon::ConfigWriteError& e) {
            throw input::with_context("", e, " (--dry-run shows the changes)");
        }
    }
    if (!o.record_path.empty()) {
        // The run's log must not land on the config (which autotune then edits), the scene,
        // the plugin or the log it would identify from: refused before anything runs.
        std::vector<daemon::NamedPath> inputs = {{"--config", o.config_path}};
        if (!config.scene_file.empty()) {
            inputs.push_back(
                {"the scene ([scene] file in " + o.config_path + ")", config.scene_file});
        }
        if (const std::string plugin = daemon::plugin_file(config.device.plugin); !plugin.empty()) {
            inputs.push_back(
                {"the device plugin ([device] plugin in " + o.config_path + ")", plugin});
        }
        daemon::refuse_overlapping_paths(inputs, {{"--record", o.record_path}});
    }
    options.rate_hz = config.servo.rate_hz;
    options.velocity_filter_hz = config.coupling.velocity_filter_hz;  // checked by the config
    options.identification.force_limit_n = config.safety.max_force_n;
    if (o.delay_s) {
        // A --delay out of range is bad input before anything runs.
        try {
            tune::check_delay_periods(*o.delay_s * config.servo.rate_hz);
        } catch (const std::invalid_argument& e) {
            throw AutotuneError(std::string(e.what()) + " (--delay x [servo] rate_hz)");
        }
    }
    // Where the run's log goes, before the device is opened: a TMPDIR that is not a
    // directory is refused before anything runs.
    RunLog run_log;
    if (o.log_path.empty()) {
        if (o.record_path.empty()) {
            run_log.create_temporary();
        } else {
            run_log.record_to(o.record_path);
        }
    }

    Outcome outcome;
    outcome.config_path = o.config_path;
    outcome.dry_run = o.dry_run;
    const bool lockstep = o.lockstep || sim_lockstep(config);
    outcome.delay = find_loop_delay(o.delay_s, !o.log_path.empty(), config, lockstep);
    options.delay_periods = outcome.delay.delay_s * config.servo.rate_hz;
    options.identification.delay_s = outcome.delay.identification_delay_s;
    try {
        tune::check_delay_periods(options.delay_periods);
    } catch (const std::invalid_argument& e) {
        throw AutotuneError(std::string(e.what()) +
                            " ([device.model] delay, the measured one or --delay x [servo] "
                            "rate_hz)");
    }
    options.validate();
    outcome.log_path = o.log_path.empty() ? run_log.path() : o.log_path;
    try {
        if (o.log_path.empty()) {
            run_identification(o.hapticd_path.empty() ? default_hapticd() : o.hapticd_path,
                               o.config_path, run_log.path(), lockstep, o.json, run_log.started);
            // Named now, so that whatever ends autotune from here on, the log can be found.
            std::cerr << "haptic-tune: autotune: identifying from the run's log " << run_log.path()
                      << (run_log.temporary() ? " (removed once the config is written)" : "")
                      << '\n';
        }
        return identify_size_and_write(o, config, original, options, outcome, run_log);
    } catch (const std::exception& e) {
        // Every failure once hapticd ran keeps its log, and says where it is.
        if (!run_log.started) throw;
        throw AutotuneError(e.what() + run_log.note());
    }
}

}  // namespace

void add_autotune_command(CLI::App& app, Invocation& invocation) {
    auto options = std::make_shared<AutotuneCliOptions>();
    CLI::App* command = app.add_subcommand(
        "autotune",
        "Identify the device (from --log, or from a `hapticd --identify` run it starts), "
        "measure the loop delay over the link (unless --delay or --log), size "
        "the coupling with the passive model (with the loop delay) and a safety margin, verify "
        "it with the exact model, and write [device.model] mass, damping, delay and [coupling] "
        "stiffness, damping into "
        "the config, keeping its comments, with a backup (FILE.bak, or FILE.bak.N if that "
        "exists). Exit 0 written, 1 the exact model rejects the gains (nothing written), 2 bad "
        "input, a log that cannot identify the device or a failed run (nothing written). "
        "docs/autotune.md");
    command->add_option("--config", options->config_path, "the hapticd config to tune")
        ->required()
        ->check(CLI::ExistingFile);
    CLI::Option* log =
        command
            ->add_option("--log", options->log_path,
                         "identify from this telemetry CSV instead of starting a run")
            ->check(CLI::ExistingFile);
    command
        ->add_option("--record", options->record_path,
                     "keep the identification run's log in FILE (default: a temporary file in "
                     "$TMPDIR, else /tmp, removed on success and kept, and named, on any "
                     "failure); refused when it is the config, the scene or the plugin")
        ->check(CLI::Validator(
            [](std::string& text) -> std::string {
                return text.empty() ? "the path is empty; give a file name" : "";
            },
            "FILE"))
        ->excludes(log);
    command
        ->add_option("--hapticd", options->hapticd_path,
                     "the hapticd executable for the run (default: the one next to "
                     "haptic-tune, else hapticd on PATH)")
        ->excludes(log);
    command
        ->add_option("--margin", options->margin,
                     "fraction of the largest stable coupling stiffness to use, (0, 1] "
                     "(default 0.9)")
        ->check(CLI::Validator(
            [](std::string& text) -> std::string {
                try {
                    std::size_t used = 0;
                    const double value = std::stod(text, &used);
                    if (used == text.size() && value > 0.0 && value <= 1.0) return {};
                } catch (const std::exception&) {
                }
                return "value " + text + " is out of range: allowed (0, 1]";
            },
            "(0, 1]"));
    command->add_flag("--optimize-damping", options->optimize_damping,
                      "size the best (k_c, b_c) pair instead of k_c at b_c = 0 (with no delay "
                      "the best pair has b_c = 0; docs/autotune.md)");
    command
        ->add_option("--delay", options->delay_s,
                     "loop delay (s) from the encoder sample to the force taking effect, "
                     "beyond the hold (default: measured over the link before the "
                     "identification run when the device reports it, else [device.model] "
                     "delay; from --log, [device.model] delay, else 0); written to "
                     "[device.model] delay")
        ->check(non_negative_finite("s"));
    command->add_flag("--lockstep", options->lockstep,
                      "the device keeps virtual time with the host (an emulated board: "
                      "hapticd-avr-sim --clock lockstep): measure the delay and run hapticd "
                      "--identify with --lockstep (implied by a sim device on its lockstep "
                      "clock)");
    command->add_flag("--dry-run", options->dry_run,
                      "identify, size, verify and print the changes, but do not write");
    command->add_flag("--json", options->json, "print the result as JSON");
    command->callback([options, &invocation] {
        invocation.run = [options] {
            try {
                return run_autotune(*options);
            } catch (const input::InputError& e) {  // AutotuneError, and what it did not wrap
                std::cerr << "haptic-tune: autotune: " << e.what() << '\n';
                return static_cast<int>(kExitBadInput);
            }
        };
    });
}

}  // namespace hapticd::tools
