// hapticd: the real-time servo daemon (DESIGN.md). With no arguments it runs the embedded
// default, the simulated device touching the demo wall, in real time, with a status line
// each second until SIGINT or SIGTERM, then prints the summary.
#include <CLI/CLI.hpp>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <ctime>
#include <iostream>
#include <thread>

#include "hapticd/daemon/run.hpp"
#include "hapticd/device/plugin_loader.hpp"

namespace {

// SIGINT and SIGTERM are blocked in every thread (they inherit the mask) and taken here
// synchronously, so no signal ever interrupts the servo thread or runs a handler in it.
class SignalWatcher {
  public:
    SignalWatcher() {
        sigemptyset(&signals_);
        sigaddset(&signals_, SIGINT);
        sigaddset(&signals_, SIGTERM);
        pthread_sigmask(SIG_BLOCK, &signals_, nullptr);
        thread_ = std::thread([this] { watch(); });
    }
    ~SignalWatcher() {
        done_.store(true);
        thread_.join();
    }
    SignalWatcher(const SignalWatcher&) = delete;
    SignalWatcher& operator=(const SignalWatcher&) = delete;

    const std::atomic<bool>& stop() const { return stop_; }

  private:
    void watch() {
        const timespec poll{0, 100'000'000};
        while (!done_.load()) {
            if (sigtimedwait(&signals_, nullptr, &poll) > 0) stop_.store(true);
        }
    }

    sigset_t signals_{};
    std::atomic<bool> stop_{false};
    std::atomic<bool> done_{false};
    std::thread thread_;
};

int list_plugins() {
    for (const hapticd::device::PluginListing& plugin : hapticd::device::list_plugins()) {
        std::cout << plugin.name << "\t" << plugin.path;
        if (plugin.shadowed) std::cout << "\t(shadowed)";
        if (!plugin.error.empty()) std::cout << "\tunusable: " << plugin.error;
        if (!plugin.description.empty()) std::cout << "\t" << plugin.description;
        std::cout << "\n";
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "hapticd: the haptic servo daemon. Reads the device's encoders at a fixed rate, renders "
        "the scene through the virtual coupling (16) of Adams & Hannaford and writes "
        "zero-order-hold force commands. Without --config it runs the embedded default: the "
        "simulated device and a demo wall. With --identify it drives the device open loop with "
        "the [identify] multisine instead and logs the run for haptic-tune identify.\n\nExit "
        "status: 0 stopped by a signal or at the end of --duration; 1 stopped on a fault (the "
        "force was zeroed in the same tick), the loop could not run, or (--identify) the "
        "handle left the workspace; 2 bad usage, config, scene, device table, or coupling "
        "gains that fail the start-up stability check.",
        "hapticd"};
    hapticd::daemon::RunOptions options;
    std::string config_path, summary_path, log_path;
    double duration_s = 0.0;
    bool no_status = false;
    bool show_plugins = false;
    app.add_option("--config", config_path, "the TOML config file (docs/daemon.md)");
    app.add_option("--duration", duration_s,
                   "stop after S seconds (device time: virtual time with --lockstep)")
        ->check(CLI::PositiveNumber & CLI::Range(0.0, 1e7));
    app.add_option("--summary", summary_path,
                   "write the JSON summary to FILE at the end, or to standard output with -");
    app.add_option("--log", log_path, "write telemetry, one CSV line per tick, to FILE");
    app.add_flag("--identify", options.identify,
                 "the excitation run: drive the device open loop with the [identify] multisine "
                 "(no scene, no coupling) and log it; needs --log; without --duration it runs "
                 "for the whole excitation (docs/daemon.md)");
    app.add_flag("--lockstep", options.lockstep,
                 "run the device on virtual time, as fast as the CPU goes (the sim plugin)");
    app.add_flag("--no-status", no_status, "do not print the status line each second");
    app.add_flag("--list-plugins", show_plugins, "list the device plugins found, then exit");
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& help) {
        return app.exit(help);
    } catch (const CLI::ParseError& error) {
        app.exit(error);
        return hapticd::daemon::kExitBadInput;
    }
    if (show_plugins) return list_plugins();
    if (!config_path.empty()) options.config_path = config_path;
    if (!summary_path.empty()) options.summary_path = summary_path;
    if (!log_path.empty()) options.log_path = log_path;
    if (app.count("--duration") != 0) options.duration_s = duration_s;
    if (no_status) options.status_interval_s = 0.0;

    const SignalWatcher signals;
    return hapticd::daemon::run_daemon(options, signals.stop(), std::cout, std::cerr);
}
