// Several devices per PC: two hapticd instances side by side, each on its own simulated
// device, CPU and summary, in real time (docs/install.md, "Running it as a service"). Each
// keeps its rate while the other runs.
#include <gtest/gtest.h>
#include <unistd.h>

#include <nlohmann/json.hpp>
#include <string>

#include "default_config.hpp"
#include "hapticd_run.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "text_file.hpp"

namespace hapticd::testing {
namespace {

constexpr double kDurationS = 2.0;

/// The default config, its servo thread pinned to `cpu`, with an overrun budget that a
/// stall of the shared VM (tens of ms) does not exhaust (config_with_room): what this test
/// judges is each instance's rate, below, not whether the host stalled once.
std::string instance_config(int cpu) {
    return config_with_room("", "cpu = " + std::to_string(cpu) + "\n");
}

TEST(HilTwoInstances, EachKeepsItsRateOnItsOwnCpuAndWritesItsOwnSummary) {
    if (::sysconf(_SC_NPROCESSORS_ONLN) < 2) GTEST_SKIP() << "needs two CPUs";
    const ScratchDir dir;
    std::string command;
    for (const int cpu : {0, 1}) {
        const std::string name = "lab" + std::to_string(cpu);
        const std::string config = dir.write(name + ".toml", instance_config(cpu));
        command += shell_quote(HAPTICD_BIN) + " --no-status --duration " +
                   std::to_string(kDurationS) + " --config " + shell_quote(config) + " --summary " +
                   shell_quote(dir.file(name + "-{start}.json")) + " 2>" +
                   shell_quote(dir.file(name + ".err")) + " & pid" + std::to_string(cpu) + "=$!; ";
    }
    // Both at once, and each one's exit status.
    command += "wait $pid0; a=$?; wait $pid1; b=$?; echo $a $b";
    const CommandResult both = run_command("sh -c " + shell_quote(command));
    ASSERT_EQ(both.out, "0 0\n") << read_file(dir.file("lab0.err"))
                                 << read_file(dir.file("lab1.err"));

    int summaries = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
        const std::string file = entry.path().filename().string();
        if (!file.ends_with(".json")) continue;
        ++summaries;
        const int cpu = file.starts_with("lab0-") ? 0 : 1;
        const nlohmann::json s = nlohmann::json::parse(read_file(entry.path().string()));
        SCOPED_TRACE(file);
        EXPECT_EQ(s["exit"], "duration");
        EXPECT_TRUE(s["faults"].empty()) << s.dump(2);
        EXPECT_EQ(s["rate_hz"], 1000.0);
        // --duration counts servo time from the first tick, and the supervising thread
        // looks every 10 ms (run_watcher.cpp), so the run ends about 10 periods late, or
        // later when a loaded host runs that (not real-time) thread late (2016 periods of a
        // 2 s run once, with other tests on both cores): every period is a tick or a period
        // a late wake missed, whatever the other instance does, and almost all are ticks.
        const double periods = s["ticks"].get<double>() + s["missed_periods"].get<double>();
        EXPECT_GE(periods, kDurationS * 1000.0 - 1.0);
        EXPECT_LE(periods, kDurationS * 1000.0 + 100.0);
        EXPECT_GE(s["ticks"].get<double>(), 0.98 * kDurationS * 1000.0);
        EXPECT_EQ(s["realtime"]["cpu"], cpu);
        if (::geteuid() == 0) {
            EXPECT_TRUE(s["realtime"]["affinity_set"].get<bool>());
        }
        EXPECT_TRUE(
            s["config_path"].get<std::string>().ends_with("/lab" + std::to_string(cpu) + ".toml"));
    }
    EXPECT_EQ(summaries, 2);
}

}  // namespace
}  // namespace hapticd::testing
