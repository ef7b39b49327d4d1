// haptic-tune conform: docs/protocol.md's firmware checklist run against the configured device
// over its own transport (serial, usb or hid), at zero force; a pass/fail table or JSON
// (hapticd/device/conform/conformance.hpp, docs/conform.md). Exit 0 every check passed, 1 a
// check failed (or was skipped after one did), 2 bad input or a link that does not open.
#include <iomanip>
#include <iostream>
#include <memory>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/device_open.hpp"
#include "hapticd/device/conform/conformance.hpp"
#include "hapticd/device/hid/hid_link.hpp"
#include "hapticd/device/link/protocol_device.hpp"
#include "hapticd/device/serial/serial_link.hpp"
#include "hapticd/device/usb/make_usb_link.hpp"
#include "hapticd/input/printable.hpp"

namespace hapticd::tools {
namespace {

struct ConformCommandOptions {
    std::string config_path;
    double watchdog_ms = 20.0;
    int exchanges = 1000;
    bool lockstep = false;
    bool json = false;
};

/// The transport's link factory for [device] plugin; throws UsageError for any other plugin.
device::link::MakeLink link_factory(const std::string& plugin, const std::string& source) {
    if (plugin == "serial") return &device::serial::make_serial_link;
    if (plugin == "usb") return &device::usb::make_usb_link;
    if (plugin == "hid") return &device::hid::make_hid_link;
    throw UsageError(source + ": [device] plugin = \"" + input::printable(plugin) +
                     "\": conform tests a device on the open protocol (docs/protocol.md); "
                     "allowed \"serial\", \"usb\" or \"hid\"");
}

nlohmann::ordered_json report_json(const device::conform::ConformReport& report) {
    nlohmann::ordered_json checks = nlohmann::ordered_json::array();
    for (const device::conform::CheckResult& c : report.checks) {
        checks.push_back({{"name", c.name},
                          {"section", c.section},
                          {"outcome", c.outcome == device::conform::Outcome::fail
                                          ? "fail"
                                          : std::string(to_string(c.outcome))},
                          {"detail", c.detail}});
    }
    nlohmann::ordered_json identity = nullptr;
    if (report.identity) {
        const auto& id = *report.identity;
        identity = {{"version", id.version},
                    {"paced", id.paced()},
                    {"axes", id.axes},
                    {"period_us", id.period_us},
                    {"force_limit_n", 1e-6 * id.force_limit_un},
                    {"counts_per_meter", id.counts_per_meter},
                    {"watchdog_timeout_us", id.watchdog_timeout_us},
                    {"serial", std::string(id.serial_number())},
                    {"firmware_version", id.firmware_version}};
    }
    return {{"device", report.device},
            {"passed", report.passed()},
            {"identity", identity},
            {"checks", checks}};
}

void print_table(const device::conform::ConformReport& report) {
    std::cout << "conform: " << report.device << '\n';
    for (const device::conform::CheckResult& c : report.checks) {
        std::cout << std::left << std::setw(6) << to_string(c.outcome) << std::setw(16) << c.name
                  << std::setw(11) << c.section << input::printable(c.detail) << '\n';
    }
    int failed = 0, skipped = 0;
    for (const auto& c : report.checks) {
        failed += c.outcome == device::conform::Outcome::fail;
        skipped += c.outcome == device::conform::Outcome::skipped;
    }
    std::cout << (report.passed() ? "PASS" : "FAIL") << ": "
              << report.checks.size() - failed - skipped << " of " << report.checks.size()
              << " checks passed";
    if (failed > 0) std::cout << ", " << failed << " failed";
    if (skipped > 0) std::cout << ", " << skipped << " skipped";
    std::cout << " (docs/protocol.md section 9)\n";
}

int run_conform(const ConformCommandOptions& o) {
    daemon::Config config;
    try {
        config = load_config_as_hapticd(o.config_path);
    } catch (const daemon::ConfigError& e) {
        throw UsageError(e.what());
    }
    const device::link::MakeLink make_link = link_factory(config.device.plugin, config.source);
    device::link::ProtocolDevice::Configured configured;
    try {
        configured = device::link::ProtocolDevice::configure(
            daemon::device_config(config, o.lockstep), config.device.plugin, make_link);
    } catch (const input::ConfigError& e) {
        throw UsageError(e.what());
    }
    device::conform::ConformOptions options;
    options.rate_hz = config.servo.rate_hz;
    options.watchdog_timeout_us = static_cast<std::uint32_t>(std::llround(o.watchdog_ms * 1000.0));
    options.timing_exchanges = o.exchanges;
    options.lockstep = o.lockstep;
    options.expected_serial = configured.settings.serial_number;
    device::conform::ConformReport report;
    try {
        report = device::conform::run_conformance(*configured.link, options);
    } catch (const std::invalid_argument& e) {
        throw UsageError(e.what());
    } catch (const std::exception& e) {
        std::cerr << "haptic-tune: device error: " << e.what() << '\n';
        return kExitBadInput;
    }
    if (o.json) {
        std::cout << report_json(report).dump(2) << '\n';
    } else {
        print_table(report);
    }
    return report.passed() ? kExitOk : kExitVerdictNo;
}

}  // namespace

void add_conform_command(CLI::App& app, Invocation& invocation) {
    auto options = std::make_shared<ConformCommandOptions>();
    CLI::App* command = app.add_subcommand(
        "conform",
        "Run docs/protocol.md's firmware checklist against the configured device (serial, usb "
        "or hid) at zero force: handshake, versions, sessions, configure, commands, timing, "
        "frame and message errors, the watchdog, bye. Prints a pass/fail table (--json: an "
        "object). Exit 0 all passed, 1 a check failed, 2 bad input or no link (docs/conform.md)");
    command->add_option("--config", options->config_path, "hapticd config file (TOML)")
        ->required()
        ->check(CLI::ExistingFile);
    command
        ->add_option("--watchdog", options->watchdog_ms,
                     "the watchdog timeout the watchdog check configures, ms (default 20; two "
                     "periods to 1000)")
        ->check(CLI::Range(0.001, 1000.0));
    command
        ->add_option("--exchanges", options->exchanges,
                     "commands in the timing check (default 1000: 1 s at 1 kHz)")
        ->check(CLI::Range(10, 1'000'000));
    command->add_flag("--lockstep", options->lockstep,
                      "the device runs a period per request (an emulated board: hapticd-avr-sim "
                      "--clock lockstep): no pacing, round trips not judged");
    command->add_flag("--json", options->json, "print the report as JSON");
    command->callback(
        [options, &invocation] { invocation.run = [options] { return run_conform(*options); }; });
}

}  // namespace hapticd::tools
