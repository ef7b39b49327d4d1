// hapticd as a service sees it: an unprivileged user (setpriv to nobody, as bare as the unit's
// user hapticd) whose real-time request is refused, with stderr on a stream that
// JOURNAL_STREAM names (systemd.exec(5)). The refusal is reported when the servo starts, not
// when the run ends, with the remedy in the unit's words; every message line carries its
// journal priority there, and none anywhere else (docs/daemon.md, "As a service").
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "default_config.hpp"
#include "hapticd_run.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "text_file.hpp"

namespace hapticd::testing {
namespace {

std::size_t first_line_with(const std::vector<std::string>& lines, const std::string& text) {
    for (std::size_t i = 0; i < lines.size(); ++i) {
        if (lines[i].find(text) != std::string::npos) return i;
    }
    return lines.size();
}

struct ServiceRun {
    int exit_code = -1;
    std::vector<std::string> stderr_lines;
};

/// The default config (realtime = "warn") with an overrun budget no stall of a loaded host
/// exhausts, readable by nobody: these tests judge the journal's lines, not whether the host
/// kept time for an unprivileged daemon (a 24 ms stall latched overrun_budget, exit 1, while
/// other work loaded both cores).
std::string service_config(const ScratchDir& dir) {
    std::string path = dir.write("service.toml", config_with_room(""));
    EXPECT_EQ(::chmod(path.c_str(), 0644), 0);
    return path;
}

/// `config` (service_config() when empty) for 0.3 s as user nobody, started as systemd starts
/// a service (INVOCATION_ID), with stderr on the journal's stream when `journal`.
ServiceRun run_as_service(const ScratchDir& dir, bool journal, std::string config = {}) {
    if (config.empty()) config = service_config(dir);
    const std::string err = dir.file(journal ? "journal.txt" : "terminal.txt");
    std::string command = "exec 2>" + shell_quote(err) + "; ";
    if (journal) command += "JOURNAL_STREAM=$(stat -c %d:%i " + shell_quote(err) + ") ";
    command +=
        "INVOCATION_ID=0123456789abcdef setpriv --reuid=65534 --regid=65534 "
        "--clear-groups " +
        shell_quote(HAPTICD_BIN) + " --no-status --duration 0.3 --config " + shell_quote(config);
    ServiceRun run;
    run.exit_code = run_command("sh -c " + shell_quote(command)).exit_code;
    run.stderr_lines = lines_of_file(err);
    return run;
}

class HilJournalRealtime : public ::testing::Test {
  protected:
    void SetUp() override {
        if (::geteuid() != 0) GTEST_SKIP() << "needs root, to run hapticd as nobody";
        ASSERT_EQ(::chmod(dir_.path().c_str(), 0777), 0);
    }
    ScratchDir dir_;
};

TEST_F(HilJournalRealtime, ARefusalIsAWarningAtTheStartWithTheUnitsRemedy) {
    const ServiceRun run = run_as_service(dir_, /*journal=*/true);
    ASSERT_EQ(run.exit_code, 0);
    const auto& lines = run.stderr_lines;
    const std::size_t refusal = first_line_with(lines, "refused: SCHED_FIFO 80");
    ASSERT_LT(refusal, lines.size()) << ::testing::PrintToString(lines);
    const std::string& line = lines[refusal];
    EXPECT_TRUE(line.starts_with("<4>hapticd: realtime warn: ")) << line;
    // Nobody's RLIMIT_RTPRIO is 0 and RLIMIT_MEMLOCK 8 MiB: the unit's settings grant them.
    EXPECT_NE(line.find("LimitRTPRIO=80"), std::string::npos) << line;
    EXPECT_NE(line.find("LimitMEMLOCK=infinity"), std::string::npos) << line;
    EXPECT_NE(line.find("/dev/cpu_dma_latency must be writable"), std::string::npos) << line;
    // At the start: before the summary, which comes when the run ends, and said once.
    const std::size_t summary = first_line_with(lines, "hapticd summary:");
    ASSERT_LT(summary, lines.size());
    EXPECT_LT(refusal, summary);
    EXPECT_EQ(first_line_with(std::vector<std::string>(
                                  lines.begin() + static_cast<long>(refusal) + 1, lines.end()),
                              "refused: SCHED_FIFO"),
              lines.size() - refusal - 1);
}

TEST_F(HilJournalRealtime, EveryPriorityIsOneJournaldKnowsAndOnlyTheJournalGetsThem) {
    const ServiceRun journal = run_as_service(dir_, /*journal=*/true);
    const std::regex priority("^<[3-6]>hapticd: .*");
    int prefixed = 0;
    for (const std::string& line : journal.stderr_lines) {
        if (line.starts_with("<")) {
            EXPECT_TRUE(std::regex_match(line, priority)) << line;
            ++prefixed;
        }
    }
    EXPECT_GE(prefixed, 1);
    const ServiceRun terminal = run_as_service(dir_, /*journal=*/false);
    ASSERT_EQ(terminal.exit_code, 0);
    ASSERT_GE(terminal.stderr_lines.size(), 3u);
    for (const std::string& line : terminal.stderr_lines)
        EXPECT_FALSE(line.starts_with("<")) << line;
    EXPECT_LT(first_line_with(terminal.stderr_lines, "hapticd: realtime warn: "),
              terminal.stderr_lines.size());
}

TEST_F(HilJournalRealtime, EnforceRefusesToRunAndSaysHowToGrantItAsAnError) {
    std::string config = read_file(HAPTICD_SOURCE_DIR "/config/hapticd.toml");
    const std::string warn = "realtime = \"warn\"";
    ASSERT_NE(config.find(warn), std::string::npos);
    config.replace(config.find(warn), warn.size(), "realtime = \"enforce\"");
    const std::string scene = "file = \"scenes/demo-wall.toml\"";
    ASSERT_NE(config.find(scene), std::string::npos);
    config.replace(config.find(scene), scene.size(),
                   "file = \"" HAPTICD_SOURCE_DIR "/config/scenes/demo-wall.toml\"");
    const std::string path = dir_.write("enforce.toml", config);
    ASSERT_EQ(::chmod(path.c_str(), 0644), 0);

    const ServiceRun run = run_as_service(dir_, /*journal=*/true, path);
    // 2, as a bad config: every start would be refused alike, so the unit does not restart.
    EXPECT_EQ(run.exit_code, 2);
    const auto& lines = run.stderr_lines;
    const std::size_t refused = first_line_with(lines, "the servo loop could not run");
    ASSERT_LT(refused, lines.size()) << ::testing::PrintToString(lines);
    EXPECT_TRUE(lines[refused].starts_with("<3>")) << lines[refused];
    const std::size_t remedy = first_line_with(lines, "LimitRTPRIO=80");
    ASSERT_LT(remedy, lines.size()) << ::testing::PrintToString(lines);
    EXPECT_TRUE(lines[remedy].starts_with("<3>hapticd: SCHED_FIFO 80 is above")) << lines[remedy];
}

}  // namespace
}  // namespace hapticd::testing
