// haptic-tune autotune, end to end through the real executables: a commented lab config,
// logs of the sim device made in-process (tests/support/identification_sim_run.hpp) or by
// `hapticd --identify --lockstep`, and the files autotune leaves: the edited config (every
// other line and comment kept; the daemon's start-up check and the exact model pass it),
// the backup (identical to the original), and nothing at all when it refuses.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/startup_check.hpp"
#include "hapticd/tune/coupling_sizing.hpp"
#include "hapticd/tune/exact_model.hpp"
#include "identification_sim_run.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"

namespace hapticd {
namespace {

namespace fs = std::filesystem;
using hapticd::testing::CommandResult;
using hapticd::testing::run_command;
using hapticd::testing::ScratchDir;
using nlohmann::json;

/// A lab's config: comments everywhere, a wrong guess in [device.model], and the sim device
/// whose truth (m = 0.1 kg, b = 2 N s/m, 0.2 N Coulomb friction) the run should find.
std::string lab_config(int axes = 1, const std::string& identify = "",
                       const std::string& sim_extra = "") {
    std::ostringstream out;
    out << "# Bench 3: the pen display, on the sim until the hardware arrives.\n"
           "# Every comment here must survive haptic-tune autotune.\n"
           "\n"
           "[servo]\n"
           "rate_hz = 1000.0        # Hz\n"
           "realtime = \"off\"        # a test machine\n"
           "\n"
           "[device]\n"
           "plugin = \"sim\"\n"
           "axes = "
        << axes
        << "\n"
           "\n"
           "[device.model]          # a guess, before identification\n"
           "mass = 0.12             # kg\n"
           "damping = 1.5           # N s/m\n"
           "\n"
           "# The coupling, to be sized.\n"
           "[coupling]\n"
           "stiffness = 2000.0      # N/m: 2/3 of 2b/T for the guess\n"
           "damping = 0.0           # N s/m\n"
           "check = \"passive\"       # the start-up check's model\n"
           "\n"
           "[scene]\n"
           "file = \""
        << HAPTICD_SOURCE_DIR
        << "/config/scenes/demo-wall.toml\"\n"
           "\n"
           "[safety]\n"
           "max_force = 20.0        # N\n"
           "max_speed = 1.0         # m/s\n"
           "\n"
           "[device.sim]            # the truth\n"
           "mass = 0.1              # kg\n"
           "damping = 2.0           # N s/m\n"
           "counts_per_meter = 1e5  # 10 um per count\n"
           "force_limit = 20.0      # N\n"
           "coulomb = 0.2           # N\n"
           "clock = \"lockstep\"\n"
        << sim_extra;
    if (!identify.empty()) out << "\n[identify]\n" << identify;
    return out.str();
}

std::string read(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) out.push_back(line);
    return out;
}

std::string quoted(const std::string& s) { return "'" + s + "'"; }

/// `text` without its lines equal to `line`.
std::string without_line(const std::string& text, const std::string& line) {
    std::string out;
    for (const std::string& l : lines(text)) {
        if (l != line) out += l + "\n";
    }
    return out;
}

/// A 10 s open-loop run of the sim (tune/identification_sim_run.hpp), as the daemon's CSV.
std::string write_sim_log(const ScratchDir& dir, tune::testing::SimulatedRun run = {},
                          const std::string& name = "run.csv") {
    const auto records = tune::testing::simulate_run(run);
    return dir.write(name, tune::testing::daemon_csv(records, run.axes));
}

struct Bench {
    ScratchDir dir;
    std::string config;
    std::string original;
    explicit Bench(const std::string& text = lab_config()) {
        config = dir.write("lab.toml", text);
        original = text;
    }
    CommandResult autotune(const std::string& args, const std::string& prefix = "") const {
        return run_command(prefix + quoted(HAPTIC_TUNE) + " autotune --config " + quoted(config) +
                           " " + args);
    }
    /// Nothing written: the config is the original and no backup or temporary is left.
    void expect_untouched() const {
        EXPECT_EQ(read(config), original);
        EXPECT_FALSE(fs::exists(config + ".bak"));
        EXPECT_FALSE(fs::exists(config + ".tmp"));
    }
};

/// The passive bound at b_c = 0: what `haptic-tune size` computes.
double passive_bound(double mass_kg, double damping_n_s_per_m, double rate_hz,
                     double delay_periods = 0.0) {
    tune::ImpedanceSizingRequest request;
    request.device = {mass_kg, damping_n_s_per_m};
    request.rate_hz = rate_hz;
    request.model = {theory::HoldModel::passive, delay_periods};
    request.coupling_damping_n_s_per_m = 0.0;
    return tune::size_impedance_coupling(request).coupling.stiffness_n_per_m;
}

/// The tuned config as the daemon reads it: identified m and b within `tolerance` of the
/// sim's, k_c = margin x haptic-tune size's bound for the written m and b (to the 6
/// significant digits written), b_c = 0; the start-up check and the exact model pass it.
void expect_tuned(const std::string& path, double margin, double tolerance) {
    const daemon::Config config = daemon::load_config(path);
    ASSERT_TRUE(config.device.model.mass_kg && config.device.model.damping_n_s_per_m);
    const double mass = *config.device.model.mass_kg;
    const double damping = *config.device.model.damping_n_s_per_m;
    EXPECT_NEAR(mass, 0.1, tolerance * 0.1);
    EXPECT_NEAR(damping, 2.0, tolerance * 2.0);
    const double bound = passive_bound(mass, damping, config.servo.rate_hz);
    EXPECT_NEAR(config.coupling.stiffness_n_per_m, margin * bound, 5e-6 * margin * bound);
    EXPECT_LE(config.coupling.stiffness_n_per_m, bound);
    EXPECT_EQ(config.coupling.damping_n_s_per_m, 0.0);

    const daemon::StartupCheck startup = daemon::check_coupling_at_startup(config);
    EXPECT_TRUE(startup.passed) << startup.describe();
    const tune::ExactCheck exact = tune::check_exact(
        {mass, damping}, {config.coupling.stiffness_n_per_m, config.coupling.damping_n_s_per_m},
        config.servo.rate_hz);
    EXPECT_TRUE(exact.stable) << exact.worst_operator.describe();
}

/// Every line of `before` is in `after`, in order, unchanged, except the values of the
/// four keys autotune sets: those keep their key, their spacing before '=' and their
/// comment.
void expect_only_the_four_values_changed(const std::string& before, const std::string& after) {
    const std::vector<std::string> a = lines(before);
    const std::vector<std::string> b = lines(after);
    ASSERT_EQ(a.size(), b.size()) << after;
    std::string table;
    int edited = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        if (!a[i].empty() && a[i][0] == '[') table = a[i].substr(0, a[i].find(']') + 1);
        const std::string key = a[i].substr(0, a[i].find(' '));
        const bool autotuned = (table == "[device.model]" && (key == "mass" || key == "damping")) ||
                               (table == "[coupling]" && (key == "stiffness" || key == "damping"));
        if (!autotuned) {
            EXPECT_EQ(b[i], a[i]) << "line " << i + 1;
            continue;
        }
        ++edited;
        EXPECT_EQ(b[i].substr(0, b[i].find('=') + 1), a[i].substr(0, a[i].find('=') + 1));
        const auto comment = [](const std::string& line) {
            const std::size_t hash = line.find('#');
            return hash == std::string::npos ? std::string() : line.substr(hash);
        };
        EXPECT_EQ(comment(b[i]), comment(a[i])) << "line " << i + 1;
    }
    EXPECT_EQ(edited, 4);
}

// --- from a log -------------------------------------------------------------------------

TEST(AutotuneCli, WritesTheIdentifiedModelAndTheMarginTimesTheBoundKeepingEverythingElse) {
    const Bench bench;
    const std::string log = write_sim_log(bench.dir);
    const CommandResult r = bench.autotune("--log " + quoted(log));
    ASSERT_EQ(r.exit_code, 0) << r.err << r.out;

    const std::string tuned = read(bench.config);
    expect_only_the_four_values_changed(bench.original, tuned);
    // The accuracy target: m and b within 2 % (force noise, friction, 10 um counts).
    expect_tuned(bench.config, 0.9, 0.02);
    EXPECT_EQ(read(bench.config + ".bak"), bench.original);
    EXPECT_FALSE(fs::exists(bench.config + ".tmp"));
    // The backup has the config's permissions.
    EXPECT_EQ(fs::status(bench.config + ".bak").permissions(),
              fs::status(bench.config).permissions());

    // What changed and why.
    for (const char* expected :
         {"[device.model] mass", "0.12 -> ", "[coupling] stiffness", "2000.0 -> ", "(unchanged)",
          "margin 0.9 x ", "+- ", "verified: the exact model",
          "start-up check of the edited config", "backup: "}) {
        EXPECT_NE(r.out.find(expected), std::string::npos) << expected << " in\n" << r.out;
    }
}

TEST(AutotuneCli, JsonSaysTheSameAndTheMarginIsAnOption) {
    const Bench bench;
    const std::string log = write_sim_log(bench.dir);
    const CommandResult r = bench.autotune("--log " + quoted(log) + " --margin 0.8 --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json j = json::parse(r.out);
    EXPECT_TRUE(j.at("written").get<bool>());
    EXPECT_EQ(j.at("backup"), bench.config + ".bak");
    EXPECT_TRUE(j.at("verified").get<bool>());
    EXPECT_EQ(j.at("margin").get<double>(), 0.8);
    EXPECT_EQ(j.at("model"), "passive");
    EXPECT_EQ(j.at("rate_hz").get<double>(), 1000.0);
    EXPECT_EQ(j.at("binding_axis").get<int>(), 0);
    const json& axis = j.at("axes").at(0);
    EXPECT_GT(axis.at("mass_std_error").get<double>(), 0.0);
    EXPECT_GT(axis.at("damping_std_error").get<double>(), 0.0);
    EXPECT_NEAR(axis.at("coulomb").get<double>(), 0.2, 0.02);
    EXPECT_GT(j.at("bound").at("stiffness_std_error").get<double>(), 0.0);
    const double bound = j.at("bound").at("stiffness").get<double>();
    EXPECT_NEAR(j.at("stiffness").get<double>(), 0.8 * bound, 5e-6 * 0.8 * bound);
    EXPECT_TRUE(j.at("exact_check").at("stable").get<bool>());
    EXPECT_FALSE(j.at("exact_check").at("worst_operator").get<std::string>().empty());
    ASSERT_EQ(j.at("changes").size(), 4u);
    EXPECT_EQ(j.at("changes").at(0).at("table"), "device.model");
    EXPECT_EQ(j.at("changes").at(0).at("key"), "mass");
    EXPECT_EQ(j.at("changes").at(0).at("old"), "0.12");
    EXPECT_EQ(j.at("changes").at(3).at("changed").get<bool>(), false);  // b_c 0.0 -> 0.0
    expect_tuned(bench.config, 0.8, 0.02);
}

TEST(AutotuneCli, DryRunWritesNothing) {
    const Bench bench;
    const std::string log = write_sim_log(bench.dir);
    const CommandResult r = bench.autotune("--log " + quoted(log) + " --dry-run");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    bench.expect_untouched();
    EXPECT_NE(r.out.find("changes (not written):"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("dry run: "), std::string::npos) << r.out;
    const CommandResult j = bench.autotune("--log " + quoted(log) + " --dry-run --json");
    ASSERT_EQ(j.exit_code, 0) << j.err;
    EXPECT_FALSE(json::parse(j.out).at("written").get<bool>());
    bench.expect_untouched();
}

// An older backup is never overwritten: the next one is FILE.bak.1, then .2.
TEST(AutotuneCli, KeepsOlderBackups) {
    const Bench bench;
    const std::string log = write_sim_log(bench.dir);
    ASSERT_EQ(bench.autotune("--log " + quoted(log) + " --margin 0.7").exit_code, 0);
    const std::string first = read(bench.config);
    const CommandResult second = bench.autotune("--log " + quoted(log) + " --json");
    ASSERT_EQ(second.exit_code, 0) << second.err;
    EXPECT_EQ(json::parse(second.out).at("backup"), bench.config + ".bak.1");
    EXPECT_EQ(read(bench.config + ".bak"), bench.original);
    EXPECT_EQ(read(bench.config + ".bak.1"), first);
    expect_tuned(bench.config, 0.9, 0.02);
}

TEST(AutotuneCli, SizesForTheBindingAxisOfAMultiAxisDevice) {
    const Bench bench(lab_config(2));
    tune::testing::SimulatedRun run;
    run.axes = 2;
    const std::string log = write_sim_log(bench.dir, run);
    const CommandResult r = bench.autotune("--log " + quoted(log) + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json j = json::parse(r.out);
    ASSERT_EQ(j.at("axes").size(), 2u);
    const int binding = j.at("binding_axis").get<int>();
    const json& a0 = j.at("axes").at(0);
    const json& a1 = j.at("axes").at(1);
    const double k0 = a0.at("bound").at("stiffness").get<double>();
    const double k1 = a1.at("bound").at("stiffness").get<double>();
    EXPECT_EQ(binding, k1 < k0 ? 1 : 0);
    EXPECT_EQ(j.at("bound").at("stiffness").get<double>(), std::min(k0, k1));
    EXPECT_TRUE(a0.at("exact_check").at("stable").get<bool>());
    EXPECT_TRUE(a1.at("exact_check").at("stable").get<bool>());
    expect_tuned(bench.config, 0.9, 0.02);
}

// --- refusals: exit 2 (input) or 1 (the exact model), and the file untouched -------------

TEST(AutotuneCli, ARefusedLogExitsTwoNamingTheReason) {
    const Bench bench;
    tune::testing::SimulatedRun run;
    run.duration_s = 0.5;
    const std::string log = write_sim_log(bench.dir, run);
    const CommandResult r = bench.autotune("--log " + quoted(log));
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("cannot identify the device"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("[too_short]"), std::string::npos) << r.err;
    bench.expect_untouched();
}

TEST(AutotuneCli, ALogOfAnotherDeviceIsRefused) {
    const Bench bench(lab_config(2));
    const std::string log = write_sim_log(bench.dir);  // one axis
    const CommandResult r = bench.autotune("--log " + quoted(log));
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("[device] axes = 2"), std::string::npos) << r.err;
    bench.expect_untouched();
}

// A loop delay (here one period, as over USB) sizes softer gains: k_c = margin x b/(2T)
// against every passive environment; autotune writes the delay beside them, and the
// start-up check of the edited config includes it.
TEST(AutotuneCli, TheLoopDelaySizesTheGainsAndIsWrittenBeside) {
    const Bench bench;
    const std::string log = write_sim_log(bench.dir);
    const CommandResult r = bench.autotune("--log " + quoted(log) + " --delay 0.001 --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json j = json::parse(r.out);
    EXPECT_EQ(j.at("delay_s").get<double>(), 0.001);
    const daemon::Config config = daemon::load_config(bench.config);
    EXPECT_EQ(config.device.model.delay_s, 0.001);
    const double bound = passive_bound(*config.device.model.mass_kg,
                                       *config.device.model.damping_n_s_per_m, 1000.0, 1.0);
    EXPECT_NEAR(bound, *config.device.model.damping_n_s_per_m / (2.0 * 1e-3), 1e-3);
    EXPECT_NEAR(config.coupling.stiffness_n_per_m, 0.9 * bound, 5e-6 * bound);
    const daemon::StartupCheck startup = daemon::check_coupling_at_startup(config);
    EXPECT_TRUE(startup.passed) << startup.describe();
    EXPECT_EQ(startup.delay_s, 0.001);

    // A delay of ten periods or more is refused, and nothing is written.
    const Bench second;
    const CommandResult bad = second.autotune("--log " + quoted(log) + " --delay 0.01");
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_NE(bad.err.find("loop delay = 10 periods is out of range"), std::string::npos)
        << bad.err;
    second.expect_untouched();
}

TEST(AutotuneCli, AMarginOutsideZeroToOneIsAUsageError) {
    const Bench bench;
    const std::string log = write_sim_log(bench.dir);
    for (const char* margin : {"0", "1.5", "-0.2", "abc"}) {
        const CommandResult r = bench.autotune("--log " + quoted(log) + " --margin " + margin);
        EXPECT_EQ(r.exit_code, 2) << margin;
        EXPECT_NE(r.err.find("(0, 1]"), std::string::npos) << r.err;
    }
    bench.expect_untouched();
}

/// Runs as an unprivileged user (nobody) when the tests run as root, who can write anything.
std::string unprivileged() {
    if (::geteuid() != 0) return "";
    if (!fs::exists("/usr/bin/setpriv")) return "unavailable";
    return "/usr/bin/setpriv --reuid=65534 --regid=65534 --clear-groups ";
}

TEST(AutotuneCli, AnUnwritableDirectoryIsReportedAndNothingIsLost) {
    const std::string as = unprivileged();
    if (as == "unavailable") GTEST_SKIP() << "running as root without setpriv";
    Bench bench;
    const std::string log = write_sim_log(bench.dir);
    // The file may be written, the directory (backup, temporary) not.
    fs::permissions(bench.config, fs::perms::owner_read | fs::perms::owner_write |
                                      fs::perms::group_read | fs::perms::group_write |
                                      fs::perms::others_read | fs::perms::others_write);
    fs::permissions(bench.dir.path(), fs::perms::owner_all | fs::perms::group_read |
                                          fs::perms::group_exec | fs::perms::others_read |
                                          fs::perms::others_exec);
    fs::permissions(bench.dir.path(), fs::perms::owner_write, fs::perm_options::remove);
    const CommandResult r = bench.autotune("--log " + quoted(log), as);
    fs::permissions(bench.dir.path(), fs::perms::owner_write, fs::perm_options::add);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("cannot create the backup " + bench.config + ".bak"), std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("was not changed"), std::string::npos) << r.err;
    bench.expect_untouched();
}

TEST(AutotuneCli, AReadOnlyConfigIsNotReplaced) {
    const std::string as = unprivileged();
    if (as == "unavailable") GTEST_SKIP() << "running as root without setpriv";
    Bench bench;
    const std::string log = write_sim_log(bench.dir);
    fs::permissions(bench.dir.path(), fs::perms::all);  // anyone may create files here
    fs::permissions(bench.config,
                    fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
    const CommandResult r = bench.autotune("--log " + quoted(log), as);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find(bench.config + " is not writable"), std::string::npos) << r.err;
    bench.expect_untouched();
}

/// The names of the files in `dir`, sorted.
std::vector<std::string> names_in(const fs::path& dir) {
    std::vector<std::string> names;
    for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
        names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
}

// The new config cannot be written after the backup was made (a file size limit just
// above the original's size: the backup fits, the longer edited config does not): the
// config is the original, and neither the redundant backup nor the temporary is left.
TEST(AutotuneCli, AFailedWriteLeavesTheOriginalAndNoStrayFile) {
    if (!fs::exists("/usr/bin/prlimit")) GTEST_SKIP() << "no prlimit";
    // Without the comment to absorb it, the identified mass (6 digits) makes the file longer.
    std::string text = lab_config();
    const std::string guess = "mass = 0.12             # kg";
    text.replace(text.find(guess), guess.size(), "mass = 0.12");
    const Bench bench(text);
    const std::string log = write_sim_log(bench.dir);
    const std::string limit = std::to_string(bench.original.size());
    const CommandResult r = bench.autotune("--log " + quoted(log),
                                           "trap '' XFSZ; /usr/bin/prlimit --fsize=" + limit + " ");
    EXPECT_EQ(r.exit_code, 2) << r.out;
    EXPECT_NE(r.err.find("could not write the new config " + bench.config), std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("File too large"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("the config was not changed"), std::string::npos) << r.err;
    EXPECT_EQ(read(bench.config), bench.original);
    EXPECT_EQ(names_in(bench.dir.path()), (std::vector<std::string>{"lab.toml", "run.csv"}));
}

// --- symlinks and modes -------------------------------------------------------------------

// A config reached through a symlink: the file it points to is updated (the link stays a
// link, to the same place), and the backup is made beside that file.
TEST(AutotuneCli, ASymlinkedConfigHasItsTargetUpdatedAndStaysALink) {
    const Bench bench;
    const std::string log = write_sim_log(bench.dir);
    const std::string link = bench.dir.file("current.toml");
    fs::create_symlink("lab.toml", link);  // relative, as a lab would make it
    const CommandResult r = run_command(quoted(HAPTIC_TUNE) + " autotune --config " + quoted(link) +
                                        " --log " + quoted(log));
    ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
    ASSERT_TRUE(fs::is_symlink(link));
    EXPECT_EQ(fs::read_symlink(link), fs::path("lab.toml"));
    expect_only_the_four_values_changed(bench.original, read(bench.config));
    expect_tuned(bench.config, 0.9, 0.02);
    EXPECT_EQ(read(bench.config + ".bak"), bench.original);
    EXPECT_FALSE(fs::exists(link + ".bak"));
    EXPECT_NE(r.out.find("written: " + link + " (" + bench.config + "; backup: " + bench.config +
                         ".bak)"),
              std::string::npos)
        << r.out;
    EXPECT_EQ(names_in(bench.dir.path()),
              (std::vector<std::string>{"current.toml", "lab.toml", "lab.toml.bak", "run.csv"}));
}

// Symlinks planted at the names autotune once used or uses (FILE.tmp, FILE.bak) are never
// followed: the files they point to are untouched, the config is a plain file again.
TEST(AutotuneCli, PlantedSymlinksAtTheTemporaryAndBackupNamesAreNotFollowed) {
    const Bench bench;
    const std::string log = write_sim_log(bench.dir);
    const std::string victim = bench.dir.write("victim.txt", "precious\n");
    fs::create_symlink(victim, bench.config + ".tmp");
    fs::create_symlink(victim, bench.config + ".bak");
    const CommandResult r = bench.autotune("--log " + quoted(log) + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
    EXPECT_EQ(read(victim), "precious\n");
    EXPECT_EQ(fs::read_symlink(bench.config + ".tmp"), fs::path(victim));
    EXPECT_EQ(fs::read_symlink(bench.config + ".bak"), fs::path(victim));
    EXPECT_FALSE(fs::is_symlink(bench.config));
    expect_tuned(bench.config, 0.9, 0.02);
    EXPECT_EQ(json::parse(r.out).at("backup"), bench.config + ".bak.1");
    EXPECT_EQ(read(bench.config + ".bak.1"), bench.original);
    EXPECT_EQ(names_in(bench.dir.path()),
              (std::vector<std::string>{"lab.toml", "lab.toml.bak", "lab.toml.bak.1",
                                        "lab.toml.tmp", "run.csv", "victim.txt"}));
}

// A config without its owner's write bit is a statement: refused as root too (st_mode, not
// access(2)), before any run, with the mode in the message; nothing changes.
TEST(AutotuneCli, AConfigWithoutTheOwnerWriteBitIsRefusedEvenAsRoot) {
    const Bench bench;
    const std::string log = write_sim_log(bench.dir);
    fs::permissions(bench.config,
                    fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
    for (const std::string& args : {"--log " + quoted(log), std::string()}) {
        const CommandResult r = bench.autotune(args);
        EXPECT_EQ(r.exit_code, 2) << args << r.out;
        EXPECT_NE(
            r.err.find(bench.config + " is not writable: its mode 0444 has no owner write bit"),
            std::string::npos)
            << r.err;
        EXPECT_NE(r.err.find("nothing was written"), std::string::npos) << r.err;
        EXPECT_EQ(r.err.find("running"), std::string::npos) << r.err;  // before the run
        EXPECT_EQ(r.err.find("measuring"), std::string::npos) << r.err;
        EXPECT_EQ(read(bench.config), bench.original);
        EXPECT_EQ(fs::status(bench.config).permissions(),
                  fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
        EXPECT_EQ(names_in(bench.dir.path()), (std::vector<std::string>{"lab.toml", "run.csv"}));
    }
    // --dry-run writes nothing and may look.
    EXPECT_EQ(bench.autotune("--log " + quoted(log) + " --dry-run").exit_code, 0);
}

// The new config has the original's mode and, when autotune runs as root, its owner.
TEST(AutotuneCli, TheWrittenConfigKeepsItsModeAndOwner) {
    const Bench bench;
    const std::string log = write_sim_log(bench.dir);
    ::chmod(bench.config.c_str(), 0640);
    const bool root = ::geteuid() == 0;
    if (root) {
        ASSERT_EQ(::chown(bench.config.c_str(), 65534, 65534), 0);
    }
    struct stat before {};
    ASSERT_EQ(::stat(bench.config.c_str(), &before), 0);
    const CommandResult r = bench.autotune("--log " + quoted(log));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    struct stat after {};
    ASSERT_EQ(::stat(bench.config.c_str(), &after), 0);
    EXPECT_NE(after.st_ino, before.st_ino);  // replaced by a rename, not rewritten in place
    EXPECT_EQ(after.st_mode & 07777, 0640u);
    EXPECT_EQ(after.st_uid, before.st_uid);
    EXPECT_EQ(after.st_gid, before.st_gid);
    struct stat backup {};
    ASSERT_EQ(::stat((bench.config + ".bak").c_str(), &backup), 0);
    EXPECT_EQ(backup.st_mode & 07777, 0640u);
    EXPECT_EQ(backup.st_uid, before.st_uid);
    expect_tuned(bench.config, 0.9, 0.02);
}

// --- the temporary directory ----------------------------------------------------------------

// TMPDIR names where the run's temporary log goes: one that is not a directory is refused
// (exit 2, naming it) before anything runs; autotune does not silently pick another.
TEST(AutotuneCli, ATmpdirThatIsNotADirectoryIsRefusedNamingIt) {
    const Bench bench;
    const CommandResult r = bench.autotune("", "TMPDIR=/nonexistent ");
    EXPECT_EQ(r.exit_code, 2) << r.out;
    EXPECT_NE(r.err.find("TMPDIR=/nonexistent: No such file or directory"), std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("--record FILE"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("running"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("measuring"), std::string::npos) << r.err;
    bench.expect_untouched();
    const CommandResult file = bench.autotune("", "TMPDIR=" + quoted(bench.config) + " ");
    EXPECT_EQ(file.exit_code, 2) << file.out;
    EXPECT_NE(file.err.find("TMPDIR=" + bench.config + " is not a directory"), std::string::npos)
        << file.err;
    bench.expect_untouched();
    // No temporary is needed with --log: TMPDIR does not matter.
    const std::string log = write_sim_log(bench.dir);
    EXPECT_EQ(
        bench.autotune("--log " + quoted(log) + " --dry-run", "TMPDIR=/nonexistent ").exit_code, 0);
}

// --- from a run it starts: hapticd --identify --lockstep ---------------------------------

TEST(AutotuneCli, RunsHapticdIdentifyWhenNoLogIsGiven) {
    // The excitation's default peak comes from [device.model] alone and knows nothing of the
    // 0.2 N friction; identification needs a peak of several times the friction
    // (docs/identification-excitation.md), so the lab sets it.
    const Bench bench(lab_config(1, "force_amplitude = 0.7\n"));
    const std::string record = bench.dir.file("identify.csv");
    const CommandResult r = bench.autotune("--record " + quoted(record));
    ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
    // The hapticd next to haptic-tune, on the sim's lockstep clock.
    const std::string hapticd = (fs::path(HAPTIC_TUNE).parent_path() / "hapticd").string();
    EXPECT_NE(r.err.find("running " + hapticd + " --identify --config " + bench.config + " --log " +
                         record + " --lockstep"),
              std::string::npos)
        << r.err;
    EXPECT_TRUE(fs::exists(record));
    // Before the run it measured the loop delay over the link: the sim has none, and that is
    // written beside the gains sized for it.
    EXPECT_NE(r.err.find("measuring the loop delay over the link"), std::string::npos) << r.err;
    EXPECT_NE(r.out.find("loop delay measured over the link (1999 commands at zero force): "
                         "p50 0 periods, p99 0 periods; sized for 0 s"),
              std::string::npos)
        << r.out;
    const std::string tuned = read(bench.config);
    EXPECT_NE(tuned.find("\ndelay = 0.0\n"), std::string::npos) << tuned;
    expect_only_the_four_values_changed(bench.original, without_line(tuned, "delay = 0.0"));
    // hapticd plans the excitation from [device.model]; from the guess (m 20 % heavy, b 25 %
    // light) against 0.2 N of friction it is weaker than it could be: a few %.
    expect_tuned(bench.config, 0.9, 0.05);
    EXPECT_EQ(read(bench.config + ".bak"), bench.original);

    // A second pass plans the run from the first one's model: the 2 %.
    const std::string first = read(bench.config);
    const std::string tmp = bench.dir.file("tmp");
    fs::create_directory(tmp);
    const CommandResult again = bench.autotune("", "TMPDIR=" + quoted(tmp) + " ");
    ASSERT_EQ(again.exit_code, 0) << again.err << again.out;
    expect_tuned(bench.config, 0.9, 0.02);
    EXPECT_EQ(read(bench.config + ".bak.1"), first);
    // Without --record the run's log was temporary (in TMPDIR) and, on success, is gone.
    EXPECT_NE(again.err.find("--log " + tmp + "/haptic-tune-autotune-"), std::string::npos)
        << again.err;
    EXPECT_NE(again.out.find("identified from the identification run"), std::string::npos)
        << again.out;
    EXPECT_TRUE(names_in(tmp).empty());
}

/// The temporary log a failed autotune names ("the run's log is kept: PATH"), which must be
/// in `tmp`, the only file there, and hold hapticd's rows (a header and more).
void expect_the_log_kept_and_named(const CommandResult& r, const std::string& tmp) {
    const std::string marker = "the run's log is kept: ";
    const std::size_t at = r.err.find(marker);
    ASSERT_NE(at, std::string::npos) << r.err;
    const std::size_t start = at + marker.size();
    const std::string path = r.err.substr(start, r.err.find_first_of(")\n", start) - start);
    EXPECT_EQ(fs::path(path).parent_path(), fs::path(tmp)) << path;
    EXPECT_EQ(names_in(tmp), std::vector<std::string>{fs::path(path).filename().string()});
    std::vector<std::string> rows = lines(read(path));
    std::erase_if(rows, [](const std::string& line) { return line.starts_with('#'); });
    ASSERT_GE(rows.size(), 2u) << path;
    EXPECT_EQ(rows.front().rfind("tick,t_s,", 0), 0u) << rows.front();
}

// The run succeeded but the config cannot be written (its name leaves no room for ".bak"):
// exit 2, the config is the original, and the run's log is kept and named.
TEST(AutotuneCli, AFailedWriteAfterTheRunKeepsTheRunsLogAndNamesIt) {
    ScratchDir dir;
    const std::string text = lab_config(1, "force_amplitude = 0.7\n");
    const std::string config = dir.write(std::string(250, 'c') + ".toml", text);  // 255 bytes
    const std::string tmp = dir.file("tmp");
    fs::create_directory(tmp);
    const CommandResult r = run_command("TMPDIR=" + quoted(tmp) + " " + quoted(HAPTIC_TUNE) +
                                        " autotune --config " + quoted(config));
    EXPECT_EQ(r.exit_code, 2) << r.out;
    EXPECT_NE(r.err.find("cannot create the backup " + config + ".bak: File name too long"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(read(config), text);
    expect_the_log_kept_and_named(r, tmp);
}

TEST(AutotuneCli, MeasuresTheLoopDelayAndSizesTheGainsForIt) {
    // The sim lands each command a quarter period after its sample: autotune measures it over
    // the link (the sim's lockstep clock: exactly), sizes for it and writes it.
    const Bench bench(lab_config(1, "force_amplitude = 0.7\n", "delay = 0.00025\n"));
    const CommandResult r = bench.autotune("--json");
    ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
    const json j = json::parse(r.out);
    EXPECT_EQ(j.at("delay_source"), "measured");
    EXPECT_DOUBLE_EQ(j.at("delay_s").get<double>(), 0.00025);
    EXPECT_TRUE(j.at("delay_measurement").at("measured").get<bool>());
    EXPECT_NEAR(j.at("delay_measurement").at("p99_s").get<double>(), 0.00025, 1e-12);
    const daemon::Config config = daemon::load_config(bench.config);
    EXPECT_DOUBLE_EQ(config.device.model.delay_s, 0.00025);
    // Sized with the quarter period, for the device it identified.
    const double bound = passive_bound(*config.device.model.mass_kg,
                                       *config.device.model.damping_n_s_per_m, 1000.0, 0.25);
    EXPECT_NEAR(config.coupling.stiffness_n_per_m, 0.9 * bound, 5e-6 * 0.9 * bound);
    EXPECT_TRUE(daemon::check_coupling_at_startup(config).passed);

    // --delay overrides the measurement (and nothing is measured).
    const Bench given(lab_config(1, "force_amplitude = 0.7\n", "delay = 0.00025\n"));
    const CommandResult g = given.autotune("--json --delay 0.001");
    ASSERT_EQ(g.exit_code, 0) << g.err;
    EXPECT_EQ(json::parse(g.out).at("delay_source"), "--delay");
    EXPECT_TRUE(json::parse(g.out).at("delay_measurement").is_null());
    EXPECT_EQ(g.err.find("measuring the loop delay"), std::string::npos) << g.err;
}

TEST(AutotuneCli, IdentifiesWithTheMeasuredDelay) {
    // One period, as a serial board on the host-paced schedule: the identification shifts the
    // logged forces by the measured p50, so m and b come out as on a device without delay
    // (ignoring it puts b about 5 % low: Identification.TheLoopDelayIsTakenIntoAccount).
    const Bench bench(lab_config(1, "force_amplitude = 0.7\n", "delay = 0.001\n"));
    const CommandResult r = bench.autotune("--json");
    ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
    const json j = json::parse(r.out);
    EXPECT_EQ(j.at("delay_source"), "measured");
    const json& axis = j.at("axes").at(0);
    EXPECT_DOUBLE_EQ(axis.at("delay_s").get<double>(),
                     j.at("delay_measurement").at("p50_s").get<double>());
    EXPECT_NEAR(axis.at("delay_s").get<double>(), 0.001, 1e-12);
    EXPECT_NEAR(axis.at("mass").get<double>(), 0.1, 0.001);
    EXPECT_NEAR(axis.at("damping").get<double>(), 2.0, 0.02);
    EXPECT_NEAR(axis.at("coulomb").get<double>(), 0.2, 0.01);
}

TEST(AutotuneCli, FromALogTheDelayIsNotMeasuredAndSaysSo) {
    const Bench bench;
    const std::string log = write_sim_log(bench.dir);
    const CommandResult r = bench.autotune("--log " + quoted(log));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("loop delay 0: not measured (from --log there is no device to run)"),
              std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("warning: sized for no loop delay"), std::string::npos) << r.out;
    EXPECT_EQ(r.err.find("measuring the loop delay"), std::string::npos) << r.err;
}

TEST(AutotuneCli, AMissingHapticdIsNamed) {
    const Bench bench;
    const CommandResult r = bench.autotune("--hapticd /nonexistent/hapticd");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("cannot run /nonexistent/hapticd for the identification run"),
              std::string::npos)
        << r.err;
    bench.expect_untouched();
}

TEST(AutotuneCli, AFailedIdentificationRunIsNamed) {
    // A push far too strong for a 0.5 mm workspace: hapticd stops the excitation at its
    // edge and exits 1. (The model, 100 times the device's impedance with the same corner,
    // predicts a swing inside it: told the truth, hapticd would refuse before the run.)
    std::string config = lab_config(1, "force_amplitude = 0.5\nworkspace = 0.0005\n");
    config.replace(config.find("mass = 0.12  "), 13, "mass = 12.0  ");
    config.replace(config.find("damping = 1.5  "), 15, "damping = 150.0");
    const Bench bench(config);
    const std::string tmp = bench.dir.file("tmp");
    fs::create_directory(tmp);
    const CommandResult r = bench.autotune("", "TMPDIR=" + quoted(tmp) + " ");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("the identification run failed"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("exited with status 1"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("nothing was written"), std::string::npos) << r.err;
    bench.expect_untouched();
    // The log hapticd's last message names is kept, and autotune says where.
    expect_the_log_kept_and_named(r, tmp);
}

}  // namespace
}  // namespace hapticd
