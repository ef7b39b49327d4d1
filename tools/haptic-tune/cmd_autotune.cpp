// haptic-tune autotune: from the device to verified coupling gains in its config, in one
// command (docs/autotune.md). The computing half (identify, size, verify) is
// tune::autotune (hapticd/tune/autotune.hpp); this file is the glue to the daemon: its
// config (read, edited keeping comments, checked at start-up, written with a backup) and
// its executable (`hapticd --identify` when no --log is given).
//
// The loop delay the gains are sized for: --delay; else, when it runs the device, the delay
// measured over the link at zero force before the identification run (daemon/link_diag.hpp,
// as `haptic-tune diag`), when the device reports when its commands take effect; else
// [device.model] delay. A device that cannot report it with no delay stated anywhere is
// refused (a guess of none would size gains past the limit of every real device). From
// --log there is no device: [device.model] delay, else none, with a warning.
//
// Exit 0 written (or would be, --dry-run); 1 the exact model rejects the gains (nothing
// written); 2 bad usage or input, a log that cannot identify the device, a failed
// identification run, an unknown loop delay, or a config that cannot be edited or written
// (nothing changed).
#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <toml++/toml.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands.hpp"
#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/config_editor.hpp"
#include "hapticd/daemon/link_diag.hpp"
#include "hapticd/daemon/output_files.hpp"
#include "hapticd/daemon/startup_check.hpp"
#include "hapticd/input/text_input.hpp"
#include "hapticd/tune/autotune.hpp"
#include "hapticd/tune/input_checks.hpp"

extern char** environ;

namespace hapticd::tools {
namespace {

namespace fs = std::filesystem;

struct AutotuneCliOptions {
    std::string config_path;
    std::string log_path;     ///< --log: identify from this log; empty: run hapticd --identify
    std::string record_path;  ///< --record: where the run's log goes (kept)
    std::string hapticd_path;
    double margin = tune::kDefaultAutotuneMargin;
    bool optimize_damping = false;
    std::optional<double> delay_s;  ///< --delay; default [device.model] delay
    bool dry_run = false;
    bool json = false;
};

/// A failure that stops autotune before anything was written: exit 2 with this message.
class AutotuneError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

std::string read_file(const std::string& path) {
    try {
        return input::read_text_file(path, "the config file");
    } catch (const input::ConfigError& e) {
        throw AutotuneError(e.what());
    }
}

std::string number_text(double value, int digits = 6) {
    std::ostringstream out;
    out << std::setprecision(digits) << value;
    return out.str();
}

// ---------------------------------------------------------------------------------------
// The identification run: hapticd --identify as a child process.

/// The hapticd next to this haptic-tune (the build tree's bin/, or the install's bindir),
/// else "hapticd" to be found on PATH.
std::string default_hapticd() {
    std::error_code error;
    const fs::path self = fs::read_symlink("/proc/self/exe", error);
    if (!error) {
        const fs::path beside = self.parent_path() / "hapticd";
        if (::access(beside.c_str(), X_OK) == 0) return beside.string();
    }
    return "hapticd";
}

/// The sim plugin on its lockstep clock: the run can go as fast as the CPU (--lockstep).
bool sim_lockstep(const daemon::Config& config) {
    if (config.device.plugin != "sim" || config.device.plugin_table_toml.empty()) return false;
    try {
        const toml::table document = toml::parse(config.device.plugin_table_toml);
        return toml::at_path(document, config.device.plugin_table_path)["clock"].value_or(
                   std::string()) == "lockstep";
    } catch (const toml::parse_error&) {
        return false;  // hapticd itself will say what is wrong with the table
    }
}

volatile std::sig_atomic_t g_child_pid = 0;
volatile std::sig_atomic_t g_interrupted = 0;

/// The signals autotune passes on to the identification run: each stops hapticd as SIGTERM
/// does (zero force, log flushed), and autotune then reports the run as interrupted.
constexpr std::array<int, 4> kForwardedSignals = {SIGINT, SIGTERM, SIGHUP, SIGQUIT};

extern "C" void on_stop_signal(int signal) {
    g_interrupted = signal;
    // Passed on whoever sent it: a terminal's Ctrl-C reaches the whole process group,
    // hapticd included (a second SIGINT is harmless), but a signal sent to haptic-tune
    // alone must reach hapticd too.
    if (g_child_pid > 0) ::kill(static_cast<pid_t>(g_child_pid), signal);
}

std::string describe_hapticd_exit(int status) {
    if (WIFSIGNALED(status)) {
        return std::string("was killed by signal ") + std::to_string(WTERMSIG(status)) + " (" +
               strsignal(WTERMSIG(status)) + ")";
    }
    const int code = WEXITSTATUS(status);
    switch (code) {
        case 1:
            return "exited with status 1: a fault stopped the run, or the handle left the "
                   "[identify] workspace (its message above says which)";
        case 2:
            return "exited with status 2: it refused the config or the command line (its "
                   "message above says why)";
        case 3:
            return "exited with status 3: its telemetry log is incomplete (disk full or a write "
                   "error; its message above says which)";
        default:
            return "exited with status " + std::to_string(code);
    }
}

/// Runs `hapticd --identify --config CONFIG --log LOG [--lockstep] --parent-lifeline FD`.
/// Its standard output goes to our standard error (so that --json output stays clean); its
/// messages show. SIGINT, SIGTERM, SIGHUP and SIGQUIT are passed on to it (it stops at zero
/// force), and autotune reports "interrupted". The lifeline is the read end of a pipe whose
/// write end only this process holds: if autotune dies, even by SIGKILL, the kernel closes
/// it and hapticd stops on its own within one period.
void run_identification(const std::string& hapticd, const std::string& config_path,
                        const std::string& log_path, bool lockstep, bool quiet, bool& started) {
    std::array<int, 2> lifeline{-1, -1};
    if (::pipe2(lifeline.data(), O_CLOEXEC) != 0) {
        throw AutotuneError(std::string("cannot create the lifeline pipe for hapticd: ") +
                            std::strerror(errno));
    }
    // The read end stays open across the exec (hapticd watches it); the write end does not.
    ::fcntl(lifeline[0], F_SETFD, 0);
    std::vector<std::string> args = {hapticd,     "--identify", "--config",
                                     config_path, "--log",      log_path};
    if (lockstep) args.emplace_back("--lockstep");
    if (quiet) args.emplace_back("--no-status");
    std::string command;
    for (const std::string& arg : args) command += (command.empty() ? "" : " ") + arg;
    args.emplace_back("--parent-lifeline");
    args.emplace_back(std::to_string(lifeline[0]));
    std::vector<char*> argv;
    for (std::string& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);

    std::cerr << "haptic-tune: autotune: running " << command << '\n';

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, STDERR_FILENO, STDOUT_FILENO);
    // The signals are blocked from before the spawn until the child's pid is known to the
    // handler, so that none is lost in between; the child starts with our old mask and the
    // default actions (hapticd takes them itself).
    sigset_t forwarded;
    sigemptyset(&forwarded);
    for (const int signal : kForwardedSignals) sigaddset(&forwarded, signal);
    sigset_t old_mask;
    ::pthread_sigmask(SIG_BLOCK, &forwarded, &old_mask);
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    posix_spawnattr_setsigmask(&attributes, &old_mask);
    posix_spawnattr_setsigdefault(&attributes, &forwarded);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
    struct sigaction stop {};
    stop.sa_handler = on_stop_signal;
    sigemptyset(&stop.sa_mask);
    std::array<struct sigaction, kForwardedSignals.size()> old_actions{};
    g_interrupted = 0;
    for (std::size_t i = 0; i < kForwardedSignals.size(); ++i) {
        ::sigaction(kForwardedSignals[i], &stop, &old_actions[i]);
    }
    pid_t pid = 0;
    // posix_spawnp searches PATH when the name has no '/'; glibc reports a failed exec here.
    const int spawn_error =
        ::posix_spawnp(&pid, argv[0], &actions, &attributes, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attributes);
    ::close(lifeline[0]);
    int status = 0;
    if (spawn_error == 0) {
        g_child_pid = pid;
        started = true;
    }
    ::pthread_sigmask(SIG_SETMASK, &old_mask, nullptr);  // a signal that came meanwhile: now
    if (spawn_error == 0) {
        while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
        }
        g_child_pid = 0;
    }
    for (std::size_t i = 0; i < kForwardedSignals.size(); ++i) {
        ::sigaction(kForwardedSignals[i], &old_actions[i], nullptr);
    }
    ::close(lifeline[1]);

    if (spawn_error != 0) {
        throw AutotuneError(
            "cannot run " + hapticd + " for the identification run: " + std::strerror(spawn_error) +
            (hapticd.find('/') == std::string::npos
                 ? " (it is neither next to haptic-tune nor on PATH; give --hapticd PATH, or "
                   "record a run yourself and give --log)"
                 : " (give --hapticd PATH, or record a run yourself and give --log)"));
    }
    if (g_interrupted != 0) {
        throw AutotuneError(
            "interrupted by SIG" + std::string(sigabbrev_np(static_cast<int>(g_interrupted))) +
            ": passed on to the identification run (" + command + "), which " +
            describe_hapticd_exit(status) + (WIFEXITED(status) ? " (it stops at zero force)" : "") +
            "; nothing was written");
    }
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        throw AutotuneError("the identification run failed: " + command + " " +
                            describe_hapticd_exit(status) + "; nothing was written");
    }
}

/// The directory for the run's temporary log: $TMPDIR when set and not empty, else /tmp.
/// A TMPDIR that is not a directory is an error (exit 2, before anything runs), not a
/// reason to pick another directory: whoever set it expects temporary files there, as
/// mktemp(1) does.
std::string temporary_directory() {
    const char* tmpdir = std::getenv("TMPDIR");
    if (tmpdir == nullptr || *tmpdir == '\0') return "/tmp";
    const std::string named = "TMPDIR=" + std::string(tmpdir);
    const std::string why =
        ": the identification run's temporary log goes there; set TMPDIR to a directory, or "
        "give --record FILE to keep the log in FILE; nothing was run or written";
    struct stat st {};
    if (::stat(tmpdir, &st) != 0) throw AutotuneError(named + ": " + std::strerror(errno) + why);
    if (!S_ISDIR(st.st_mode)) throw AutotuneError(named + " is not a directory" + why);
    return tmpdir;
}

/// The identification run's log, when autotune runs hapticd: --record FILE (the user's,
/// always kept), or a temporary file created exclusively in temporary_directory(). The
/// temporary is removed only when autotune succeeds; once hapticd has started, every
/// failure keeps it (hapticd's last message may name it) and autotune's error names it. A
/// temporary that hapticd never got (nothing ran) is removed.
class RunLog {
  public:
    RunLog() = default;
    RunLog(const RunLog&) = delete;
    RunLog& operator=(const RunLog&) = delete;
    ~RunLog() {
        if (temporary_ && !started) ::unlink(path_.c_str());
    }

    void record_to(const std::string& path) { path_ = path; }
    void create_temporary() {
        const std::string directory = temporary_directory();
        std::string name = directory + "/haptic-tune-autotune-XXXXXX.csv";
        const int fd = ::mkstemps(name.data(), 4);  // O_CREAT | O_EXCL, a fresh name
        if (fd < 0) {
            throw AutotuneError(
                "cannot create a temporary file for the identification run's "
                "log in " +
                directory + ": " + std::strerror(errno) +
                " (set TMPDIR to another directory, or give --record FILE); "
                "nothing was run or written");
        }
        ::close(fd);
        path_ = name;
        temporary_ = true;
    }
    const std::string& path() const { return path_; }
    bool temporary() const { return temporary_; }

    /// For an error message: where the log is, once hapticd has started.
    std::string note() const {
        if (!started) return "";
        return temporary_ ? " (the run's log is kept: " + path_ + ")"
                          : " (the run's log: " + path_ + ", --record)";
    }
    /// Success: the temporary is not needed any more.
    void discard() {
        if (!temporary_) return;
        ::unlink(path_.c_str());
        temporary_ = false;
    }

    bool started = false;  ///< hapticd was started: the file is its log

  private:
    std::string path_;
    bool temporary_ = false;
};

// ---------------------------------------------------------------------------------------
// The report.

nlohmann::ordered_json exact_json(const tune::ExactCheck& exact) {
    return {{"stable", exact.stable},
            {"worst_margin", exact.worst_margin},
            {"worst_spectral_radius", exact.worst_spectral_radius},
            {"worst_frequency_hz", exact.worst_frequency_hz},
            {"worst_operator", exact.worst_operator.describe()},
            {"worst_environment", exact.worst_environment.describe()},
            {"cases_checked", exact.cases_checked}};
}

nlohmann::ordered_json axis_json(const tune::AutotuneAxis& a) {
    const tune::IdentifiedAxis& id = a.identified;
    return {{"axis", id.axis},
            {"mass", id.estimate.mass_kg},
            {"mass_std_error", id.std_error.mass_kg},
            {"damping", id.estimate.damping_n_s_per_m},
            {"damping_std_error", id.std_error.damping_n_s_per_m},
            {"coulomb", id.estimate.coulomb_n},
            {"coulomb_std_error", id.std_error.coulomb_n},
            {"offset", id.estimate.offset_n},
            {"offset_std_error", id.std_error.offset_n},
            {"residual_rms_m", id.residual_rms_m},
            {"log_rate_hz", id.rate_hz},
            {"duration_s", id.duration_s},
            {"converged", id.report.converged},
            {"bound",
             {{"stiffness", a.bound.coupling.stiffness_n_per_m},
              {"stiffness_std_error", a.bound_stiffness_std_error_n_per_m},
              {"damping", a.bound.coupling.damping_n_s_per_m},
              {"binding_frequency_hz", a.bound.binding_frequency_hz}}},
            {"exact_check", exact_json(a.exact)}};
}

/// Where the loop delay came from.
enum class DelaySource { option, measured, config, none };

const char* to_string(DelaySource source) {
    switch (source) {
        case DelaySource::option:
            return "--delay";
        case DelaySource::measured:
            return "measured";
        case DelaySource::config:
            return "config";
        case DelaySource::none:
            break;
    }
    return "none";
}

/// How long the link is run at zero force to measure the delay: 2000 commands at 1 kHz, so
/// that the p99 rests on 20 of them.
constexpr double kDelayMeasurementS = 2.0;

struct LoopDelay {
    double delay_s = 0.0;
    DelaySource source = DelaySource::none;
    std::optional<daemon::DiagReport> measurement;  ///< when it ran the link
    std::string note;  ///< one line for the report: how the delay was found
};

/// [device.model] delay is written in the config (its parsed value defaults to 0 when not).
bool config_states_delay(const std::string& text) {
    try {
        const toml::table table = toml::parse(text);
        return table["device"]["model"]["delay"].is_value();
    } catch (const toml::parse_error&) {
        return false;  // load_config() has read it already; not reached
    }
}

std::string periods_text(double delay_s, double rate_hz) {
    const double periods = delay_s * rate_hz;
    return number_text(periods, 4) + (periods == 1.0 ? " period" : " periods");
}

/// --delay, else the link's measurement (when autotune runs the device), else the config.
LoopDelay find_loop_delay(const AutotuneCliOptions& o, const daemon::Config& config,
                          const std::string& original) {
    LoopDelay out;
    const double rate_hz = config.servo.rate_hz;
    const bool stated = config_states_delay(original);
    if (o.delay_s) {
        out.delay_s = *o.delay_s;
        out.source = DelaySource::option;
        out.note = "loop delay " + number_text(out.delay_s) + " s (" +
                   periods_text(out.delay_s, rate_hz) + "): --delay";
        return out;
    }
    if (!o.log_path.empty()) {
        out.delay_s = config.device.model_delay_s;
        out.source = stated ? DelaySource::config : DelaySource::none;
        out.note = stated ? "loop delay " + number_text(out.delay_s) + " s (" +
                                periods_text(out.delay_s, rate_hz) +
                                "): [device.model] delay (not measured: from --log there is no "
                                "device to run)"
                          : "loop delay 0: not measured (from --log there is no device to run) "
                            "and neither --delay nor [device.model] delay states one";
        return out;
    }
    // Measure it, as haptic-tune diag does: zero force, the daemon's schedule.
    daemon::DiagOptions diag;
    diag.duration_s = kDelayMeasurementS;
    diag.lockstep = sim_lockstep(config);
    std::cerr << "haptic-tune: autotune: measuring the loop delay over the link ("
              << kDelayMeasurementS << " s at zero force)\n";
    try {
        out.measurement = daemon::run_link_diag(config, diag, std::cerr);
    } catch (const std::exception& e) {
        throw AutotuneError(std::string("cannot measure the loop delay: device error: ") +
                            e.what() + " (give --delay SECONDS to skip the measurement)");
    }
    const daemon::DiagReport& m = *out.measurement;
    std::string why_not;
    if (!m.delay_measured) {
        why_not = m.delay_missing;
    } else if (m.bad_ack_command + m.bad_ack_time + m.acausal + m.clock_backwards > 0) {
        why_not =
            "the device's acknowledgements or timestamps contradicted themselves (" +
            std::to_string(m.bad_ack_command + m.bad_ack_time + m.acausal + m.clock_backwards) +
            " times; haptic-tune diag shows which)";
    } else if (!(m.recommended_delay_s * rate_hz < tune::kMaxDelayPeriods)) {
        why_not = "the measured p99 " + number_text(m.delay_s.p99) +
                  " s is beyond the stability models' range (under 10 periods)";
    }
    if (why_not.empty()) {
        out.delay_s = m.recommended_delay_s;
        out.source = DelaySource::measured;
        out.note = "loop delay measured over the link (" + std::to_string(m.delay_commands) +
                   " commands at zero force): p50 " + periods_text(m.delay_s.p50, rate_hz) +
                   ", p99 " + periods_text(m.delay_s.p99, rate_hz) + "; sized for " +
                   number_text(out.delay_s) + " s (" + periods_text(out.delay_s, rate_hz) +
                   ": the p99 rounded up to the next 0.05 period)";
        if (stated && config.device.model_delay_s != out.delay_s) {
            out.note +=
                ", replacing [device.model] delay = " + number_text(config.device.model_delay_s);
        }
        std::cerr << "haptic-tune: autotune: " << out.note << '\n';  // before the long run
        return out;
    }
    if (stated) {
        out.delay_s = config.device.model_delay_s;
        out.source = DelaySource::config;
        out.note = "loop delay " + number_text(out.delay_s) + " s (" +
                   periods_text(out.delay_s, rate_hz) +
                   "): [device.model] delay; not measured: " + why_not;
        std::cerr << "haptic-tune: autotune: " << out.note << '\n';
        return out;
    }
    throw AutotuneError("the loop delay is unknown: it could not be measured over the link (" +
                        why_not +
                        "), and neither --delay nor [device.model] delay states it. Gains sized "
                        "for no delay would be past the limit of a real loop; give --delay "
                        "SECONDS (docs/autotune.md, docs/stability-models.md); nothing was "
                        "written");
}

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

nlohmann::ordered_json outcome_json(const Outcome& o) {
    const tune::AutotuneResult& r = o.result;
    nlohmann::ordered_json axes = nlohmann::ordered_json::array();
    for (const tune::AutotuneAxis& a : r.axes) axes.push_back(axis_json(a));
    nlohmann::ordered_json changes = nlohmann::ordered_json::array();
    for (const daemon::ConfigChange& c : o.changes) {
        changes.push_back({{"table", c.table},
                           {"key", c.key},
                           {"old", c.old_text.empty() ? nlohmann::ordered_json(nullptr)
                                                      : nlohmann::ordered_json(c.old_text)},
                           {"new", c.new_text},
                           {"changed", c.old_text != c.new_text}});
    }
    nlohmann::ordered_json out = {
        {"config", o.config_path},
        {"log", o.log_kept ? nlohmann::ordered_json(o.log_path) : nlohmann::ordered_json(nullptr)},
        {"written", !o.backup_path.empty()},
        {"written_file", o.written_path.empty() ? nlohmann::ordered_json(nullptr)
                                                : nlohmann::ordered_json(o.written_path)},
        {"dry_run", o.dry_run},
        {"backup", o.backup_path.empty() ? nlohmann::ordered_json(nullptr)
                                         : nlohmann::ordered_json(o.backup_path)},
        {"verified", r.verified},
        {"model", "passive"},
        {"rate_hz", r.rate_hz},
        {"delay_s", r.delay_periods / r.rate_hz},
        {"delay_source", to_string(o.delay.source)},
        {"delay_measurement",
         [&]() -> nlohmann::ordered_json {
             if (!o.delay.measurement) return nullptr;
             const daemon::DiagReport& m = *o.delay.measurement;
             if (!m.delay_measured) return {{"measured", false}, {"missing", m.delay_missing}};
             return {{"measured", true},       {"commands", m.delay_commands},
                     {"p50_s", m.delay_s.p50}, {"p99_s", m.delay_s.p99},
                     {"max_s", m.delay_s.max}, {"recommended_s", m.recommended_delay_s}};
         }()},
        {"margin", r.margin},
        {"optimize_damping", r.optimize_damping},
        {"binding_axis", r.binding().identified.axis},
        {"device", {{"mass", r.device.mass_kg}, {"damping", r.device.damping_n_s_per_m}}},
        {"bound",
         {{"stiffness", r.bound.stiffness_n_per_m},
          {"stiffness_std_error", r.binding().bound_stiffness_std_error_n_per_m},
          {"damping", r.bound.damping_n_s_per_m},
          {"binding_frequency_hz", r.binding().bound.binding_frequency_hz}}},
        {"stiffness", r.coupling.stiffness_n_per_m},
        {"damping", r.coupling.damping_n_s_per_m},
        {"exact_check",
         [&] {
             nlohmann::ordered_json e =
                 exact_json(r.axes[static_cast<std::size_t>(r.worst_axis)].exact);
             e["stable"] = r.verified;
             e["worst_axis"] = r.axes[static_cast<std::size_t>(r.worst_axis)].identified.axis;
             return e;
         }()},
        {"verdict", r.verdict},
        {"axes", axes},
        {"changes", changes},
        {"startup_check", o.startup ? nlohmann::ordered_json(o.startup->describe())
                                    : nlohmann::ordered_json(nullptr)},
        {"warnings", r.warnings},
        {"solve_time_s", r.solve_time_s},
    };
    return out;
}

void print_text(const Outcome& o) {
    const tune::AutotuneResult& r = o.result;
    const tune::IdentifiedAxis& first = r.axes.front().identified;
    std::cout << "identified from " << (o.log_kept ? o.log_path : "the identification run") << " ("
              << number_text(first.duration_s, 4) << " s at " << number_text(first.rate_hz, 6)
              << " Hz, " << r.axes.size() << (r.axes.size() == 1 ? " axis" : " axes")
              << "), value +- standard error:\n";
    for (const tune::AutotuneAxis& a : r.axes) {
        const tune::IdentifiedAxis& id = a.identified;
        std::cout << "  axis " << id.axis << ": mass " << number_text(id.estimate.mass_kg) << " +- "
                  << number_text(id.std_error.mass_kg, 2) << " kg, damping "
                  << number_text(id.estimate.damping_n_s_per_m) << " +- "
                  << number_text(id.std_error.damping_n_s_per_m, 2) << " N s/m, coulomb "
                  << number_text(id.estimate.coulomb_n, 3) << " +- "
                  << number_text(id.std_error.coulomb_n, 2) << " N, offset "
                  << number_text(id.estimate.offset_n, 3) << " +- "
                  << number_text(id.std_error.offset_n, 2) << " N\n";
    }
    std::cout << o.delay.note << '\n';
    std::cout << "largest stable coupling (passive model, "
              << (r.optimize_damping ? "optimised damping" : "b_c = 0") << ", [servo] rate_hz "
              << number_text(r.rate_hz) << " Hz, loop delay "
              << number_text(r.delay_periods / r.rate_hz * 1e3) << " ms):\n";
    for (const tune::AutotuneAxis& a : r.axes) {
        std::cout << "  axis " << a.identified.axis << ": k_c "
                  << number_text(a.bound.coupling.stiffness_n_per_m) << " +- "
                  << number_text(a.bound_stiffness_std_error_n_per_m, 2) << " N/m";
        if (r.optimize_damping) {
            std::cout << " with b_c " << number_text(a.bound.coupling.damping_n_s_per_m)
                      << " N s/m";
        }
        std::cout << (a.bound.binding_frequency_hz > 0.0
                          ? ", binding at " + number_text(a.bound.binding_frequency_hz, 4) + " Hz"
                          : ", binding as f -> 0")
                  << (&a == &r.binding() && r.axes.size() > 1 ? "  <- binding axis" : "") << '\n';
    }
    std::cout << "coupling: margin " << number_text(r.margin) << " x "
              << number_text(r.bound.stiffness_n_per_m) << " N/m = k_c "
              << number_text(r.coupling.stiffness_n_per_m) << " N/m, b_c "
              << number_text(r.coupling.damping_n_s_per_m) << " N s/m\n";
    std::cout << (r.verified ? "verified: " : "REJECTED: ") << r.verdict << '\n';
    if (o.startup)
        std::cout << "start-up check of the edited config: " << o.startup->describe() << '\n';
    for (const std::string& warning : r.warnings) std::cout << "warning: " << warning << '\n';
    if (!o.changes.empty()) {
        std::cout << (o.backup_path.empty() ? "changes (not written):\n" : "changes:\n");
        std::size_t width = 0;
        for (const daemon::ConfigChange& c : o.changes) {
            width = std::max(width, c.table.size() + c.key.size() + 5);
        }
        for (const daemon::ConfigChange& c : o.changes) {
            std::cout << "  " << std::left << std::setw(static_cast<int>(width))
                      << "[" + c.table + "] " + c.key << (c.old_text.empty() ? "(new)" : c.old_text)
                      << " -> " << c.new_text << (c.old_text == c.new_text ? "  (unchanged)" : "")
                      << '\n';
        }
    }
    if (!o.backup_path.empty()) {
        std::cout << "written: " << o.config_path
                  << (o.written_path != o.config_path ? " (" + o.written_path + "; " : " (")
                  << "backup: " << o.backup_path << ")\n";
    } else if (o.dry_run) {
        std::cout << "dry run: " << o.config_path << " not written\n";
    }
}

// ---------------------------------------------------------------------------------------

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
        throw AutotuneError(std::string("bad log: ") + e.what());
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
        throw AutotuneError(std::string(e.what()) + "; nothing was written");
    }
    outcome.changes = edited.changes;
    try {
        const daemon::Config tuned =
            daemon::parse_config(edited.text, o.config_path, config.base_dir);
        outcome.startup = daemon::check_coupling_at_startup(tuned);
    } catch (const daemon::ConfigError& e) {
        throw AutotuneError(std::string("the edited config would not load: ") + e.what() +
                            "; nothing was written");
    }
    if (!outcome.startup->passed && !outcome.startup->skipped) {
        throw AutotuneError("the daemon's start-up check would refuse the edited config: " +
                            outcome.startup->describe() + "; nothing was written");
    }

    if (!o.dry_run) {
        // The file the config resolves to is replaced (a symlink stays one) by a temporary
        // made exclusively beside it, with its mode and owner, after an exclusive backup; a
        // config without its owner's write bit is refused (daemon/config_editor.hpp).
        try {
            const daemon::WrittenConfig written =
                daemon::write_config_with_backup(o.config_path, original, edited.text);
            outcome.backup_path = written.backup;
            outcome.written_path = written.target;
        } catch (const daemon::ConfigWriteError& e) {
            throw AutotuneError(e.what());
        }
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
        config = daemon::load_config(o.config_path);
    } catch (const daemon::ConfigError& e) {
        throw AutotuneError(std::string("the config does not load: ") + e.what());
    }
    const std::string original = read_file(o.config_path);
    if (!o.dry_run) {
        // A config that may not be replaced is refused before the run, not after it.
        try {
            daemon::check_config_writable(o.config_path);
        } catch (const daemon::ConfigWriteError& e) {
            throw AutotuneError(std::string(e.what()) + " (--dry-run shows the changes)");
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
        try {
            daemon::refuse_overlapping_paths(inputs, {{"--record", o.record_path}});
        } catch (const daemon::OutputError& e) {
            throw AutotuneError(e.what());
        }
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
    outcome.delay = find_loop_delay(o, config, original);
    options.delay_periods = outcome.delay.delay_s * config.servo.rate_hz;
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
                               o.config_path, run_log.path(), sim_lockstep(config), o.json,
                               run_log.started);
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
    command->add_flag("--dry-run", options->dry_run,
                      "identify, size, verify and print the changes, but do not write");
    command->add_flag("--json", options->json, "print the result as JSON");
    command->callback([options, &invocation] {
        invocation.run = [options] {
            try {
                return run_autotune(*options);
            } catch (const AutotuneError& e) {
                std::cerr << "haptic-tune: autotune: " << e.what() << '\n';
                return static_cast<int>(kExitBadInput);
            }
        };
    });
}

}  // namespace hapticd::tools
