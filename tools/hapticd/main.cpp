// hapticd: the real-time servo daemon (docs/architecture.md §2.10, docs/daemon.md). With no
// arguments it runs the embedded default, the simulated device touching the demo wall, in real
// time, with a status line each second until SIGINT, SIGTERM or any other signal that would end
// it (stop_signals()), then prints the summary.
#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <ctime>
#include <iostream>
#include <optional>
#include <string>
#include <thread>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/exit_code.hpp"
#include "hapticd/daemon/journal.hpp"
#include "hapticd/daemon/run.hpp"
#include "hapticd/device/plugin_loader.hpp"
#include "hapticd/install/version.hpp"
#include "parse_command_line.hpp"

namespace {

/// Every signal whose default action ends the process without it being a crash (Linux,
/// signal(7)): each stops the run as SIGTERM does. SIGKILL and SIGSTOP cannot be caught;
/// SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP and SIGSYS are crashes (left to their
/// default action: a core dump); SIGCHLD, SIGCONT, SIGURG, SIGWINCH are ignored by default.
sigset_t stop_signals() {
    sigset_t set;
    sigemptyset(&set);
    for (const int signal : {SIGHUP, SIGINT, SIGQUIT, SIGPIPE, SIGALRM, SIGTERM, SIGUSR1, SIGUSR2,
                             SIGSTKFLT, SIGIO, SIGPROF, SIGVTALRM, SIGXCPU, SIGXFSZ, SIGPWR}) {
        sigaddset(&set, signal);
    }
    for (int signal = SIGRTMIN; signal <= SIGRTMAX; ++signal) sigaddset(&set, signal);
    return set;
}

// The stop signals are blocked in every thread (they inherit the mask: this runs before any
// thread is made) and taken here synchronously, so no signal ever interrupts the servo thread
// or runs a handler in it. A SIGPIPE or SIGXFSZ raised by a write stays pending in its thread
// and the write fails with EPIPE or EFBIG instead (the writer reports it). Dispositions
// inherited as "ignore" are reset to the default, so that the signal is delivered to the
// mask, except SIGHUP ignored by nohup(1), which stays ignored as nohup asks.
class SignalWatcher {
  public:
    SignalWatcher() : signals_(stop_signals()) {
        struct sigaction current {};
        for (int signal = 1; signal <= SIGRTMAX; ++signal) {
            if (sigismember(&signals_, signal) != 1 || signal == SIGHUP) continue;
            if (::sigaction(signal, nullptr, &current) == 0 && current.sa_handler == SIG_IGN) {
                std::signal(signal, SIG_DFL);
            }
        }
        pthread_sigmask(SIG_BLOCK, &signals_, nullptr);
        thread_ = std::thread([this] { watch(); });
    }
    ~SignalWatcher() {
        done_.store(true);
        thread_.join();
        if (lifeline_.joinable()) lifeline_.join();
    }
    SignalWatcher(const SignalWatcher&) = delete;
    SignalWatcher& operator=(const SignalWatcher&) = delete;

    std::atomic<bool>& stop() { return stop_; }
    const std::atomic<int>& cause() const { return cause_; }

    /// --parent-lifeline FD: the read end of a pipe whose write end only the parent holds.
    /// When the parent dies, by any means, the kernel closes it; this thread sees end of file
    /// (poll() wakes at once) and stops the run as SIGTERM does: the servo thread reads the
    /// flag at its next tick, so the force is zero within one period.
    void watch_lifeline(int fd) {
        lifeline_ = std::thread([this, fd] { watch_fd(fd); });
    }

  private:
    void watch() {
        const timespec poll{0, 100'000'000};
        while (!done_.load()) {
            if (const int signal = sigtimedwait(&signals_, nullptr, &poll); signal > 0) {
                int none = 0;
                cause_.compare_exchange_strong(none, signal);
                stop_.store(true, std::memory_order_release);
            }
        }
    }

    void watch_fd(int fd) {
        pollfd entry{fd, POLLIN, 0};
        while (!done_.load()) {
            const int ready = ::poll(&entry, 1, 100);
            if (ready < 0 && errno == EINTR) continue;
            if (ready < 0 || (entry.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0) break;
            if (ready > 0) {
                char byte = 0;
                const ssize_t n = ::read(fd, &byte, 1);
                if (n == 0 || (n < 0 && errno != EINTR && errno != EAGAIN)) break;
            }
        }
        if (done_.load()) return;
        int none = 0;
        cause_.compare_exchange_strong(none, hapticd::daemon::kStopByLifeline);
        stop_.store(true, std::memory_order_release);
    }

    sigset_t signals_{};
    std::atomic<bool> stop_{false};
    std::atomic<int> cause_{0};
    std::atomic<bool> done_{false};
    std::thread thread_;
    std::thread lifeline_;
};

int list_plugins() {
    for (const hapticd::device::PluginListing& plugin : hapticd::device::list_plugins()) {
        std::cout << plugin.name << "\t" << plugin.path;
        if (plugin.shadowed) std::cout << "\t(shadowed)";
        if (!plugin.error.empty()) std::cout << "\tunusable: " << plugin.error;
        if (!plugin.description.empty()) std::cout << "\t" << plugin.description;
        std::cout << "\n";
    }
    return hapticd::daemon::kExitOk;
}

int run_main(int argc, char** argv) {
    CLI::App app{
        "hapticd: the haptic servo daemon. Reads the device's encoders at a fixed rate, renders "
        "the scene through the virtual coupling (16) of Adams & Hannaford and writes "
        "zero-order-hold force commands. Without --config it runs the embedded default: the "
        "simulated device and a demo wall. With --identify it drives the device open loop with "
        "the [identify] multisine instead and logs the run for haptic-tune identify.\n\n"
        "Signals: SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE, SIGALRM, SIGUSR1, SIGUSR2, "
        "SIGVTALRM, SIGPROF, SIGXCPU, SIGXFSZ, SIGIO, SIGPWR, SIGSTKFLT and the real-time "
        "signals all stop the run the same way: force zeroed, telemetry flushed, summary "
        "written. The --log file is written every 100 ms: a SIGKILL loses at most the last "
        "100 ms of it, and every line in it is whole.\n\nExit "
        "status: 0 stopped by a signal or at the end of --duration; 1 stopped on a fault (the "
        "force was zeroed in the same tick), the loop could not run, or (--identify) the "
        "handle left the workspace; 2 bad usage, config, scene or device table, a plugin "
        "that cannot be loaded or a device that cannot be opened, coupling gains that fail "
        "the start-up stability check, real time refused with realtime = \"enforce\", or an "
        "output path that is empty, names an input or another output, is locked by another "
        "hapticd, or cannot be created (all found before the first tick: the device never "
        "pushed); 3 the run ended without a fault "
        "but the --log or --summary is incomplete (disk full, a write error, records "
        "dropped: the summary says telemetry_complete: false).",
        "hapticd"};
    hapticd::daemon::RunOptions options;
    std::string config_path, summary_path, log_path, socket_path;
    double duration_s = 0.0;
    bool no_status = false;
    bool show_plugins = false;
    app.add_option("--config", config_path, "the TOML config file (docs/daemon.md)");
    int lifeline_fd = -1;
    app.add_option("--duration", duration_s,
                   "stop after S seconds (device time: virtual time with --lockstep); from half a "
                   "period to 1e7 s");
    app.set_version_flag("--version", std::string("hapticd ") + hapticd::install::kVersion);
    app.add_option("--summary", summary_path,
                   "write the JSON summary to FILE at the end, or to standard output with -; "
                   "{start} in FILE becomes the start time (UTC, 20261203T124100.123Z), so "
                   "that each start writes a file of its own");
    app.add_option("--log", log_path,
                   "write telemetry, one CSV line per tick, to FILE ({start} as in --summary)");
    app.add_option("--socket", socket_path,
                   "serve the control socket (docs/control.md, hapticctl) on PATH, mode 0660, "
                   "group hapticd; with it a fault latches at zero force until hapticctl reset "
                   "instead of ending the run");
    app.add_flag("--identify", options.identify,
                 "the excitation run: drive the device open loop with the [identify] multisine "
                 "(no scene, no coupling) and log it; needs --log; without --duration it runs "
                 "for the whole excitation (docs/daemon.md)");
    app.add_flag("--lockstep", options.lockstep,
                 "run the device on virtual time, as fast as the CPU goes (the sim plugin)");
    app.add_flag("--no-status", no_status, "do not print the status line each second");
    app.add_flag("--list-plugins", show_plugins, "list the device plugins found, then exit");
    bool show_config_keys = false;
    app.add_flag("--config-keys", show_config_keys,
                 "print the reference of the config file's keys (allowed values, defaults, "
                 "meaning; a Markdown table, as in docs/daemon.md), then exit");
    app.add_option("--parent-lifeline", lifeline_fd,
                   "FD: the read end of a pipe whose write end the parent holds; when it closes "
                   "(the parent died) the run stops as on SIGTERM (haptic-tune autotune passes "
                   "it)");
    if (const std::optional<int> ended = hapticd::tools::parse_command_line(app, argc, argv)) {
        return *ended;
    }
    if (show_plugins) return list_plugins();
    if (show_config_keys) {
        std::cout << hapticd::daemon::config_keys_markdown();
        return hapticd::daemon::kExitOk;
    }
    // Given but empty is an error (run_daemon says so), not "not given".
    if (app.count("--config") != 0) options.config_path = config_path;
    if (app.count("--summary") != 0) options.summary_path = summary_path;
    if (app.count("--log") != 0) options.log_path = log_path;
    if (app.count("--socket") != 0) options.socket_path = socket_path;
    if (app.count("--parent-lifeline") != 0 && ::fcntl(lifeline_fd, F_GETFD) < 0) {
        std::cerr << "hapticd: --parent-lifeline " << lifeline_fd
                  << ": not an open file descriptor (give the read end of a pipe)\n";
        return hapticd::daemon::kExitBadInput;
    }
    if (app.count("--duration") != 0) options.duration_s = duration_s;
    if (no_status) options.status_interval_s = 0.0;

    SignalWatcher signals;
    if (lifeline_fd >= 0) {
        ::fcntl(lifeline_fd, F_SETFD, FD_CLOEXEC);
        signals.watch_lifeline(lifeline_fd);
    }
    options.stop_cause = &signals.cause();
    // Each message line carries its priority for the journal, stripped anywhere else.
    hapticd::daemon::PriorityLineFilter priorities(
        std::cerr.rdbuf(), hapticd::daemon::is_journal_stream(STDERR_FILENO));
    std::ostream log(&priorities);
    return hapticd::daemon::run_daemon(options, signals.stop(), std::cout, log);
}

}  // namespace

/// Nothing escapes: an exception the run did not turn into an exit code (it never opened the
/// device, or has already left it at zero force) is a message and exit 1.
int main(int argc, char** argv) {
    try {
        return run_main(argc, argv);
    } catch (const std::exception& e) {
        std::cerr << "hapticd: " << e.what() << "\n";
    } catch (...) {
        std::cerr << "hapticd: an unknown exception ended the run\n";
    }
    return hapticd::daemon::kExitFault;
}
