// HilExit: every way a hapticd run ends leaves the device at zero force and its outputs
// whole (docs/architecture.md §7.2). The real binary against the sim plugin: each stop
// signal ends a run as SIGTERM does; a SIGKILL loses at most the writer's flush interval of
// the log and never a half line; a full disk is an incomplete log in the summary and exit
// 3; outputs that are inputs, shared, locked, unwritable or empty are refused (exit 2)
// before the device is opened; a bad --duration is refused naming its range; and
// haptic-tune autotune passes its stop signals on to the identification run and, when it is
// SIGKILLed, the run stops on its own (the lifeline). HAPTICD_EXIT_TEST_HAPTICD and
// HAPTICD_EXIT_TEST_HAPTIC_TUNE run these against other builds (to see them fail before a
// fix). Run serially: the real-time runs are timed.
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "hapticd_run.hpp"
#include "operators.hpp"
#include "pen_display.hpp"
#include "text_file.hpp"
#include "tuned_gains.hpp"
#include "wall_contact.hpp"

namespace hapticd::testing {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

std::string binary(const char* variable, const char* built) {
    const char* other = std::getenv(variable);
    return other != nullptr && *other != '\0' ? other : built;
}
std::string hapticd_bin() { return binary("HAPTICD_EXIT_TEST_HAPTICD", HAPTICD_BIN); }
std::string haptic_tune_bin() { return binary("HAPTICD_EXIT_TEST_HAPTIC_TUNE", HAPTIC_TUNE_BIN); }

/// Waits until `predicate` holds, up to `timeout`.
template <typename Predicate>
bool eventually(Predicate predicate, std::chrono::milliseconds timeout) {
    const auto until = Clock::now() + timeout;
    while (!predicate()) {
        if (Clock::now() > until) return false;
        std::this_thread::sleep_for(2ms);
    }
    return true;
}

// The log is read here as bytes, not through the product's reader (telemetry_csv.hpp), on
// purpose: what these tests check for is a torn line, the last line of a run killed or out of
// disk cut mid-write, and the reader cannot see one. A line cut inside its last field still
// has every field, each a number ("0.12" cut to "0.1"), so the reader takes it as a row; only
// the missing newline at the end of the file shows the cut. last_row_t() and the row counts
// read the file while hapticd appends to it, where the last line may be cut at any byte.

/// The log's lines from its header row on (the preamble's "# " lines left out), and whether
/// the file ends on a newline (its last line is whole).
struct LogFile {
    std::vector<std::string> lines;
    bool ends_whole = true;
    std::size_t bytes = 0;
};
LogFile read_log(const std::string& path) {
    const std::string text = read_file(path);
    LogFile log;
    log.bytes = text.size();
    log.ends_whole = text.empty() || text.back() == '\n';
    log.lines = lines_of_text(text);
    const auto header =
        std::find_if(log.lines.begin(), log.lines.end(),
                     [](const std::string& line) { return !line.starts_with('#'); });
    log.lines.erase(log.lines.begin(), header);
    return log;
}

std::size_t commas(const std::string& line) {
    return static_cast<std::size_t>(std::count(line.begin(), line.end(), ','));
}

/// Every data line has the header's columns and a tick one more than the line before.
void expect_whole_rows(const LogFile& log) {
    ASSERT_FALSE(log.lines.empty());
    EXPECT_TRUE(log.ends_whole) << "the last line is cut";
    const std::size_t columns = commas(log.lines.front());
    for (std::size_t i = 1; i < log.lines.size(); ++i) {
        ASSERT_EQ(commas(log.lines[i]), columns) << "line " << i + 1 << ": " << log.lines[i];
        ASSERT_EQ(std::stoull(log.lines[i].substr(0, log.lines[i].find(','))), i - 1)
            << "line " << i + 1;
    }
}

/// A pen display resting in free space, on the sim's real-time clock (or lockstep).
std::string free_config(const std::string& clock = "realtime") {
    DaemonConfig config;
    config.coupling = coupling_table(size_coupling("encoder"), "encoder");
    config.sim_clock = clock;
    // SCHED_FIFO where granted (a warning where not): these runs are about how they end, and a
    // host stall of 20 periods would end them on overrun_budget first; so would a longer one
    // on a loaded machine without it, so the budget is patient here.
    config.realtime = clock == "realtime" ? "warn" : "off";
    config.safety_keys = "max_missed_periods = 1000\nmax_consecutive_overruns = 1000\n";
    config.initial_position = "-0.001";
    config.humans = human_table(stiff_grasp(push_toml(0.005, 0.3, 0.3, 100.0)));
    return config.toml();
}

struct Bench {
    ScratchDir dir;
    std::string config, log, summary;
    explicit Bench(const std::string& clock = "realtime") {
        config = dir.write("cfg.toml", free_config(clock));
        dir.write("scene.toml", wall_contact_scene(1e5));
        log = dir.file("run.csv");
        summary = dir.file("summary.json");
    }
    std::vector<std::string> args(std::vector<std::string> more = {}) const {
        std::vector<std::string> a = {hapticd_bin(), "--no-status", "--config",  config,
                                      "--log",       log,           "--summary", summary};
        a.insert(a.end(), more.begin(), more.end());
        return a;
    }
    std::unique_ptr<ChildProcess> start(std::vector<std::string> more = {}) const {
        return std::make_unique<ChildProcess>(args(std::move(more)), dir.file("out.txt"),
                                              dir.file("err.txt"));
    }
    /// Runs to the end (at most `timeout`).
    std::unique_ptr<ChildProcess> run(std::vector<std::string> more,
                                      std::chrono::milliseconds timeout = 60s) const {
        auto child = start(std::move(more));
        EXPECT_TRUE(child->wait(timeout)) << "hapticd did not end";
        return child;
    }
    nlohmann::json summary_json() const {
        const std::string text = read_file(summary);
        return text.empty() ? nlohmann::json() : nlohmann::json::parse(text);
    }
    /// Whether the log holds `rows` data rows now (the header not counted). It reads only
    /// the start of the log: a lockstep run writes tens of MB/s, faster than a test under
    /// ASan could read all of it, so a count of the whole would chase a file it never caught.
    bool has_rows(std::size_t rows) const { return has_lines(log, rows + 1); }
};

// --- signals ----------------------------------------------------------------------------

struct NamedSignal {
    int number;
    const char* name;
};

std::vector<NamedSignal> stop_signals() {
    return {{SIGHUP, "SIGHUP"},     {SIGINT, "SIGINT"},    {SIGQUIT, "SIGQUIT"},
            {SIGPIPE, "SIGPIPE"},   {SIGALRM, "SIGALRM"},  {SIGTERM, "SIGTERM"},
            {SIGUSR1, "SIGUSR1"},   {SIGUSR2, "SIGUSR2"},  {SIGSTKFLT, "SIGSTKFLT"},
            {SIGIO, "SIGPOLL"},     {SIGPROF, "SIGPROF"},  {SIGVTALRM, "SIGVTALRM"},
            {SIGXCPU, "SIGXCPU"},   {SIGXFSZ, "SIGXFSZ"},  {SIGPWR, "SIGPWR"},
            {SIGRTMIN, "SIGRTMIN"}, {SIGRTMAX, "SIGRTMAX"}};
}

/// Ends a run with `signal` once it has logged `after_rows` rows; the run must end as on
/// SIGTERM: exit 0, "stopped", the summary written, the log whole and complete.
void expect_stops_cleanly(const Bench& bench, const NamedSignal& signal, bool lockstep) {
    std::vector<std::string> more;
    if (lockstep) more = {"--lockstep"};
    auto child = bench.start(more);
    ASSERT_TRUE(eventually([&] { return bench.has_rows(100); }, 20s)) << child->err();
    child->signal(signal.number);
    ASSERT_TRUE(child->wait(10s)) << signal.name << ": hapticd did not stop";
    ASSERT_EQ(child->exit_code(), 0) << signal.name << "\n" << child->err();
    const nlohmann::json s = bench.summary_json();
    ASSERT_FALSE(s.is_null()) << signal.name << ": no summary";
    EXPECT_EQ(s.at("exit"), "stopped") << signal.name;
    const std::string expected_name =
        signal.number >= SIGRTMIN ? "signal " + std::to_string(signal.number) : signal.name;
    EXPECT_EQ(s.at("stopped_by"), expected_name);
    EXPECT_EQ(s.at("telemetry_complete"), true) << signal.name;
    EXPECT_EQ(s.at("final_command"), "zero") << signal.name;  // the device took it
    const LogFile log = read_log(bench.log);
    expect_whole_rows(log);
    EXPECT_EQ(log.lines.size() - 1, s.at("ticks").get<std::size_t>()) << signal.name;
    EXPECT_EQ(s.at("telemetry_records_written").get<std::size_t>(), log.lines.size() - 1);
    EXPECT_NE(child->err().find("stopped by " + expected_name + ": force zeroed"),
              std::string::npos)
        << child->err();
}

TEST(HilExit, EveryStopSignalEndsARealTimeRunAsSigtermDoes) {
    for (const NamedSignal& signal : stop_signals()) {
        const Bench bench;
        expect_stops_cleanly(bench, signal, /*lockstep=*/false);
    }
}

TEST(HilExit, EveryStopSignalEndsALockstepRunAsSigtermDoes) {
    for (const NamedSignal& signal : stop_signals()) {
        const Bench bench("lockstep");
        expect_stops_cleanly(bench, signal, /*lockstep=*/true);
    }
}

// --- the log on SIGKILL -----------------------------------------------------------------

/// t_s of the last whole row in the log now, if there is one: the file as hapticd is writing
/// it, its last line perhaps cut (see LogFile).
std::optional<double> last_row_t(const std::string& path) {
    const std::string text = read_file(path);
    const std::size_t end = text.rfind('\n');
    if (end == std::string::npos || end == 0) return std::nullopt;
    const std::size_t begin = text.rfind('\n', end - 1);
    if (begin == std::string::npos) return std::nullopt;  // only the header
    const std::string line = text.substr(begin + 1, end - begin - 1);
    const std::size_t comma = line.find(',');
    return std::stod(line.substr(comma + 1));
}

double seconds(Clock::time_point t) {
    return std::chrono::duration<double>(t.time_since_epoch()).count();
}

TEST(HilExit, SigkillLosesAtMostTheFlushIntervalAndNoHalfLine) {
    // While the run goes, the log's last row (its device time t_s, which the sim's real-time
    // clock keeps in step with the wall clock) is sampled every 2 ms: wall time - t_s is the
    // start of the run plus how far the file lags. Its smallest value is the start (just after
    // a write); what the SIGKILL loses is the kill's time past the start minus the last t_s
    // in the file afterwards.
    const Bench bench;
    auto child = bench.start();
    ASSERT_TRUE(eventually([&] { return last_row_t(bench.log).has_value(); }, 20s)) << child->err();
    double start_s = 1e300;
    double worst_lag_s = 0.0;
    const auto until = Clock::now() + 1200ms;
    while (Clock::now() < until) {
        if (const auto t = last_row_t(bench.log)) {
            const double offset = seconds(Clock::now()) - *t;
            start_s = std::min(start_s, offset);
            worst_lag_s = std::max(worst_lag_s, offset - start_s);
        }
        std::this_thread::sleep_for(2ms);
    }
    const double killed_s = seconds(Clock::now());
    child->signal(SIGKILL);
    ASSERT_TRUE(child->wait(5s));
    EXPECT_EQ(child->exit_code(), -SIGKILL);
    const LogFile log = read_log(bench.log);
    expect_whole_rows(log);
    const double last_t = last_row_t(bench.log).value_or(0.0);
    const double lost_s = killed_s - start_s - last_t;
    std::cout << "[hil] SIGKILL at t = " << killed_s - start_s
              << " s: the file ends at t_s = " << last_t << " s (" << log.lines.size() - 1
              << " rows, " << log.bytes << " bytes): lost " << lost_s
              << " s; the file lagged the run by at most " << worst_lag_s << " s while it ran\n";
    // The flush interval (0.1 s), and slack for this shared VM's scheduling of the writer.
    EXPECT_LE(lost_s, 0.1 + 0.05);
    EXPECT_LE(worst_lag_s, 0.1 + 0.05);
    EXPECT_GE(last_t, 1.0);
}

// --- a full disk ------------------------------------------------------------------------

TEST(HilExit, DevFullIsAnIncompleteLogInTheSummaryAndExitThree) {
    const Bench bench("lockstep");
    auto child = std::make_unique<ChildProcess>(
        std::vector<std::string>{hapticd_bin(), "--no-status", "--lockstep", "--duration", "10",
                                 "--config", bench.config, "--log", "/dev/full", "--summary",
                                 bench.summary},
        bench.dir.file("out.txt"), bench.dir.file("err.txt"));
    ASSERT_TRUE(child->wait(60s));
    EXPECT_EQ(child->exit_code(), 3) << child->err();
    const nlohmann::json s = bench.summary_json();
    ASSERT_FALSE(s.is_null()) << child->err();
    EXPECT_EQ(s.at("ticks"), 10000);
    EXPECT_EQ(s.at("telemetry_records"), 10000);
    EXPECT_EQ(s.at("telemetry_records_written"), 0);
    EXPECT_EQ(s.at("telemetry_complete"), false);
    EXPECT_NE(child->err().find("--log /dev/full: writing telemetry failed: No space left on "
                                "device; the file holds the first 0 of 10000 records"),
              std::string::npos)
        << child->err();
}

TEST(HilExit, AFullFilesystemKeepsWholeLinesAndSaysHowManyAreThere) {
    const Bench bench("lockstep");
    const fs::path mount = bench.dir.path() / "small";
    fs::create_directory(mount);
    if (::mount("tmpfs", mount.c_str(), "tmpfs", 0, "size=64k") != 0) {
        GTEST_SKIP() << "cannot mount a tmpfs here (" << std::strerror(errno) << ")";
    }
    struct Unmount {
        fs::path path;
        ~Unmount() { ::umount2(path.c_str(), MNT_DETACH); }
    } unmount{mount};
    const std::string log = (mount / "run.csv").string();
    auto child = std::make_unique<ChildProcess>(
        std::vector<std::string>{hapticd_bin(), "--no-status", "--lockstep", "--duration", "10",
                                 "--config", bench.config, "--log", log, "--summary",
                                 bench.summary},
        bench.dir.file("out.txt"), bench.dir.file("err.txt"));
    ASSERT_TRUE(child->wait(60s));
    EXPECT_EQ(child->exit_code(), 3) << child->err();
    const nlohmann::json s = bench.summary_json();
    ASSERT_FALSE(s.is_null()) << child->err();
    const LogFile file = read_log(log);
    expect_whole_rows(file);
    std::cout << "[hil] 64 KiB tmpfs: " << file.lines.size() - 1 << " of 10000 rows, " << file.bytes
              << " bytes\n";
    EXPECT_GT(file.lines.size(), 100u);
    EXPECT_LT(file.lines.size(), 10000u);
    EXPECT_EQ(s.at("telemetry_records"), 10000);
    EXPECT_EQ(s.at("telemetry_records_written").get<std::size_t>(), file.lines.size() - 1);
    EXPECT_EQ(s.at("telemetry_complete"), false);
}

// --- outputs that are inputs, shared, locked, unwritable, empty --------------------------

/// A run that must be refused before the device opens: exit 2, the message has `needle`,
/// no row logged and `untouched` (the config by default) unchanged.
void expect_refused(const Bench& bench, std::vector<std::string> args, const std::string& needle) {
    const std::string config_before = read_file(bench.config);
    const std::string scene_before = read_file(bench.dir.file("scene.toml"));
    ChildProcess child(std::move(args), bench.dir.file("out.txt"), bench.dir.file("err.txt"));
    ASSERT_TRUE(child.wait(30s));
    EXPECT_EQ(child.exit_code(), 2) << child.err();
    EXPECT_NE(child.err().find(needle), std::string::npos) << child.err();
    EXPECT_EQ(child.err().find("sim device, 1 axis"), std::string::npos)
        << "the device was opened:\n"
        << child.err();
    EXPECT_EQ(read_file(bench.config), config_before);
    EXPECT_EQ(read_file(bench.dir.file("scene.toml")), scene_before);
}

TEST(HilExit, AnOutputThatIsAnInputIsRefused) {
    const Bench bench("lockstep");
    const std::string h = hapticd_bin();
    const std::string scene = bench.dir.file("scene.toml");
    expect_refused(
        bench,
        {h, "--lockstep", "--duration", "1", "--config", bench.config, "--log", bench.config},
        "--log " + bench.config + " is the same file as --config " + bench.config);
    expect_refused(
        bench,
        {h, "--lockstep", "--duration", "1", "--config", bench.config, "--summary", bench.config},
        "--summary " + bench.config + " is the same file as --config");
    expect_refused(bench,
                   {h, "--lockstep", "--duration", "1", "--config", bench.config, "--log", scene},
                   "--log " + scene + " is the same file as the scene ([scene] file in " +
                       bench.config + ") " + scene);
    // Through a symlink and a "..": the same inode.
    fs::create_symlink(bench.config, bench.dir.path() / "link.toml");
    const std::string dotted = (bench.dir.path() / "x" / ".." / "link.toml").string();
    fs::create_directory(bench.dir.path() / "x");
    expect_refused(
        bench, {h, "--lockstep", "--duration", "1", "--config", bench.config, "--summary", dotted},
        "is the same file as --config " + bench.config);
    // The plugin (refused before it is loaded, so any file will do).
    const std::string plugin =
        bench.dir.write("hapticd-device-fake.so", "not really a shared object\n");
    const std::string with_plugin = bench.dir.write("plugin.toml", [&] {
        std::string text = read_file(bench.config);
        const std::string from = "plugin = \"sim\"";
        text.replace(text.find(from), from.size(), "plugin = \"" + plugin + "\"");
        return text.substr(0, text.find("[device.sim"));  // no table for that plugin
    }());
    const std::string plugin_before = read_file(plugin);
    expect_refused(bench,
                   {h, "--lockstep", "--duration", "1", "--config", with_plugin, "--log", plugin},
                   "--log " + plugin + " is the same file as the device plugin");
    EXPECT_EQ(read_file(plugin), plugin_before);
}

TEST(HilExit, TwoOutputsOnOneFileAreRefused) {
    const Bench bench("lockstep");
    expect_refused(bench,
                   {hapticd_bin(), "--lockstep", "--duration", "1", "--config", bench.config,
                    "--log", bench.log, "--summary", bench.log},
                   "--summary " + bench.log + " is the same file as --log " + bench.log);
}

TEST(HilExit, ASecondDaemonOnTheSameLogIsRefusedNamingTheHolder) {
    const Bench bench;
    auto first = bench.start();
    ASSERT_TRUE(eventually([&] { return bench.has_rows(50); }, 20s)) << first->err();
    ChildProcess second({hapticd_bin(), "--no-status", "--duration", "1", "--config", bench.config,
                         "--log", bench.log},
                        bench.dir.file("out2.txt"), bench.dir.file("err2.txt"));
    ASSERT_TRUE(second.wait(30s));
    EXPECT_EQ(second.exit_code(), 2) << second.err();
    EXPECT_NE(second.err().find("--log " + bench.log + ": the file is locked by process " +
                                std::to_string(first->pid())),
              std::string::npos)
        << second.err();
    EXPECT_EQ(second.err().find("sim device, 1 axis"), std::string::npos) << second.err();
    first->signal(SIGTERM);
    ASSERT_TRUE(first->wait(10s));
    EXPECT_EQ(first->exit_code(), 0) << first->err();
    // The first daemon's log is whole: the second neither emptied nor interleaved it.
    const LogFile log = read_log(bench.log);
    expect_whole_rows(log);
    EXPECT_EQ(log.lines.size() - 1, bench.summary_json().at("ticks").get<std::size_t>());
}

TEST(HilExit, AnUnwritableOutputIsRefusedBeforeTheRun) {
    const Bench bench("lockstep");
    const std::string h = hapticd_bin();
    const std::string nowhere = bench.dir.file("no/such/dir/summary.json");
    expect_refused(
        bench, {h, "--lockstep", "--duration", "1", "--config", bench.config, "--summary", nowhere},
        "--summary " + nowhere + ": cannot create the file: No such file or directory");
    expect_refused(
        bench,
        {h, "--lockstep", "--duration", "1", "--config", bench.config, "--log",
         bench.dir.path().string()},
        "--log " + bench.dir.path().string() + ": cannot create the file: Is a directory");
    EXPECT_FALSE(fs::exists(bench.log));
}

TEST(HilExit, ARunRefusedAfterTheOutputsWereCheckedLeavesNoneBehind) {
    // The device cannot be loaded: the outputs, already checked and created, are removed
    // again (the ones it created) or left as they were (the ones that existed).
    const Bench bench("lockstep");
    std::string text = read_file(bench.config);
    text.replace(text.find("plugin = \"sim\""), std::string("plugin = \"sim\"").size(),
                 "plugin = \"" + bench.dir.file("hapticd-device-none.so") + "\"");
    const std::string config =
        bench.dir.write("none.toml", text.substr(0, text.find("[device.sim")));
    const std::string old_summary = bench.dir.write("old-summary.json", "{\"old\": true}\n");
    ChildProcess child({hapticd_bin(), "--lockstep", "--duration", "1", "--config", config, "--log",
                        bench.log, "--summary", old_summary},
                       bench.dir.file("out.txt"), bench.dir.file("err.txt"));
    ASSERT_TRUE(child.wait(30s));
    EXPECT_EQ(child.exit_code(), 2) << child.err();
    EXPECT_NE(child.err().find("hapticd-device-none.so"), std::string::npos) << child.err();
    EXPECT_FALSE(fs::exists(bench.log));
    EXPECT_EQ(read_file(old_summary), "{\"old\": true}\n");
}

TEST(HilExit, EmptyPathsAreErrors) {
    const Bench bench("lockstep");
    const std::string h = hapticd_bin();
    for (const char* option : {"--config", "--log", "--summary"}) {
        std::vector<std::string> args = {h, "--lockstep", "--duration", "1"};
        if (std::string(option) != "--config") args.insert(args.end(), {"--config", bench.config});
        args.insert(args.end(), {option, ""});
        expect_refused(bench, args, std::string(option) + " \"\": the path is empty");
    }
}

TEST(HilExit, ADurationOutsideItsRangeIsRefusedNamingTheRange) {
    const Bench bench("lockstep");
    for (const char* duration : {"nan", "-1", "0", "0.0004", "inf", "2e7"}) {
        expect_refused(
            bench, {hapticd_bin(), "--lockstep", "--config", bench.config, "--duration", duration},
            "--duration " + std::string(duration == std::string("2e7") ? "2e+07" : duration) +
                ": must be a number of seconds from half a period (0.0005 s at "
                "[servo] rate_hz = 1000) to 1e+07");
    }
    // Half a period is one tick.
    const auto child = bench.run({"--lockstep", "--duration", "0.0005"}, 30s);
    EXPECT_EQ(child->exit_code(), 0) << child->err();
    EXPECT_EQ(bench.summary_json().at("ticks"), 1);
}

// --- haptic-tune autotune's identification run ------------------------------------------

/// autotune_cli_test's lab config, on the sim's real-time clock: the run takes seconds.
std::string lab_config() {
    return "[servo]\nrate_hz = 1000.0\nrealtime = \"warn\"\n"
           "[device]\nplugin = \"sim\"\naxes = 1\n"
           "[device.model]\nmass = 0.12\ndamping = 1.5\n"
           "[coupling]\nstiffness = 2000.0\ndamping = 0.0\ncheck = \"passive\"\n"
           "[scene]\nfile = \"" HAPTICD_SOURCE_DIR
           "/config/scenes/demo-wall.toml\"\n"
           "[safety]\nmax_force = 20.0\nmax_speed = 1.0\nmax_missed_periods = 1000\n"
           "max_consecutive_overruns = 1000\n"
           "[device.sim]\nmass = 0.1\ndamping = 2.0\ncounts_per_meter = 1e5\n"
           "force_limit = 20.0\ncoulomb = 0.2\nclock = \"realtime\"\n"
           "[identify]\nforce_amplitude = 0.7\n";
}

/// The pids of `pid`'s children.
std::vector<pid_t> children_of(pid_t pid) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/task/" + std::to_string(pid) + "/children");
    std::vector<pid_t> pids;
    for (pid_t child = 0; in >> child;) pids.push_back(child);
    return pids;
}

struct AutotuneBench {
    ScratchDir dir;
    std::string config, record, original;
    AutotuneBench() {
        original = lab_config();
        config = dir.write("lab.toml", original);
        record = dir.file("identify.csv");
    }
    /// Starts autotune and waits until its hapticd child has logged `rows` rows; the child's
    /// pid in `hapticd`.
    std::unique_ptr<ChildProcess> start_running(pid_t& hapticd, std::size_t rows = 300) const {
        auto autotune = std::make_unique<ChildProcess>(
            std::vector<std::string>{haptic_tune_bin(), "autotune", "--config", config, "--record",
                                     record},
            dir.file("out.txt"), dir.file("err.txt"));
        const auto logged = [&] {
            const std::string text = read_file(record);
            return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
        };
        EXPECT_TRUE(eventually(
            [&] {
                return autotune->err().find("autotune: running") != std::string::npos &&
                       logged() > rows;
            },
            30s))
            << autotune->err();
        const std::vector<pid_t> children = children_of(autotune->pid());
        EXPECT_EQ(children.size(), 1u);
        hapticd = children.empty() ? -1 : children.front();
        return autotune;
    }
};

TEST(HilExit, AutotunePassesItsStopSignalsOnToTheIdentificationRun) {
    for (const NamedSignal& signal :
         std::vector<NamedSignal>{{SIGINT, "SIGINT"}, {SIGTERM, "SIGTERM"}, {SIGHUP, "SIGHUP"}}) {
        const AutotuneBench bench;
        pid_t hapticd = -1;
        auto autotune = bench.start_running(hapticd);
        ASSERT_GT(hapticd, 0);
        const auto sent = Clock::now();
        autotune->signal(signal.number);  // autotune alone, not its process group
        ASSERT_TRUE(autotune->wait(5s)) << signal.name << ": autotune did not end";
        const double took_s = std::chrono::duration<double>(Clock::now() - sent).count();
        std::cout << "[hil] autotune " << signal.name << ": ended " << took_s << " s later\n";
        EXPECT_EQ(autotune->exit_code(), 2) << autotune->err();
        const std::string err = autotune->err();
        EXPECT_NE(err.find("hapticd: stopped by " + std::string(signal.name) + ": force zeroed"),
                  std::string::npos)
            << err;
        EXPECT_NE(err.find("autotune: interrupted by " + std::string(signal.name) +
                           ": passed on to the identification run"),
                  std::string::npos)
            << err;
        EXPECT_NE(err.find("exited with status 0 (it stops at zero force); nothing was written"),
                  std::string::npos)
            << err;
        EXPECT_LT(took_s, 2.0);
        EXPECT_EQ(read_file(bench.config), bench.original);
        expect_whole_rows(read_log(bench.record));
        EXPECT_EQ(::kill(hapticd, 0), -1);  // reaped by autotune
    }
}

TEST(HilExit, TheIdentificationRunStopsOnItsOwnWhenAutotuneIsKilled) {
    // This test adopts the orphaned hapticd (a subreaper), to wait for it and see its status.
    ASSERT_EQ(::prctl(PR_SET_CHILD_SUBREAPER, 1), 0);
    const AutotuneBench bench;
    pid_t hapticd = -1;
    auto autotune = bench.start_running(hapticd);
    ASSERT_GT(hapticd, 0);
    // The first row is the first tick of the run (after the still wait): time it from there.
    const std::size_t rows_at_kill_before = read_log(bench.record).lines.size();
    const auto killed = Clock::now();
    autotune->signal(SIGKILL);
    ASSERT_TRUE(autotune->wait(5s));
    int status = 0;
    pid_t reaped = 0;
    ASSERT_TRUE(eventually(
        [&] {
            reaped = ::waitpid(hapticd, &status, WNOHANG);
            return reaped == hapticd;
        },
        5s))
        << "hapticd is still running after its parent was killed";
    const double took_s = std::chrono::duration<double>(Clock::now() - killed).count();
    ::prctl(PR_SET_CHILD_SUBREAPER, 0);
    ASSERT_TRUE(WIFEXITED(status)) << "hapticd was killed by signal " << WTERMSIG(status);
    EXPECT_EQ(WEXITSTATUS(status), 0);
    const std::string err = autotune->err();  // hapticd's messages went to autotune's stderr
    EXPECT_NE(err.find("hapticd: stopped by parent lifeline: force zeroed"), std::string::npos)
        << err;
    const LogFile log = read_log(bench.record);
    expect_whole_rows(log);
    // The loop stopped right after the parent died (it reads the stop at its next tick):
    // only the rows still in the writer's buffer (up to its 0.1 s flush interval, more when
    // this shared VM is loaded) came after the ones on disk at the kill; without the
    // lifeline the run goes on for its whole 10 s excitation.
    const double extra_s = static_cast<double>(log.lines.size() - rows_at_kill_before) * kPeriodS;
    std::cout << "[hil] autotune SIGKILL: hapticd exited " << took_s << " s later; "
              << log.lines.size() - rows_at_kill_before << " rows after the kill\n";
    EXPECT_LT(took_s, 1.0);
    EXPECT_LT(extra_s, 0.5);
    EXPECT_EQ(read_file(bench.config), bench.original);
}

TEST(HilExit, AutotuneRefusesARecordThatIsItsConfig) {
    const AutotuneBench bench;
    ChildProcess autotune(
        {haptic_tune_bin(), "autotune", "--config", bench.config, "--record", bench.config},
        bench.dir.file("out.txt"), bench.dir.file("err.txt"));
    ASSERT_TRUE(autotune.wait(30s));
    EXPECT_EQ(autotune.exit_code(), 2);
    EXPECT_NE(autotune.err().find("--record " + bench.config + " is the same file as --config " +
                                  bench.config),
              std::string::npos)
        << autotune.err();
    EXPECT_EQ(autotune.err().find("running"), std::string::npos) << autotune.err();
    EXPECT_EQ(read_file(bench.config), bench.original);
    EXPECT_FALSE(fs::exists(bench.config + ".bak"));
}

}  // namespace
}  // namespace hapticd::testing
