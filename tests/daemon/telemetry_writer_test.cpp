// The telemetry writer drains the ring into CSV; on a clean stop the file is complete.
#include "hapticd/daemon/telemetry_writer.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "hapticd/servo/telemetry_csv.hpp"
#include "scratch_dir.hpp"
#include "text_file.hpp"

namespace hapticd::daemon {
namespace {

std::vector<std::string> lines_of(const std::string& path) { return testing::lines_of_file(path); }

using testing::ScratchDir;

TEST(DaemonTelemetryWriter, EveryPushedRecordIsInTheFileInOrder) {
    // A producer pushing faster than a small ring drains, without backpressure: every record
    // the ring accepted is in the file, and accepted + dropped = pushed.
    servo::TelemetryRing ring(64);
    const ScratchDir dir;
    const std::string path = dir.file("order.csv");
    TelemetryWriter writer(ring, path, 2);
    writer.start();
    constexpr std::uint64_t kRecords = 200'000;
    std::uint64_t accepted = 0;
    for (std::uint64_t n = 0; n < kRecords; ++n) {
        servo::TelemetryRecord record;
        record.tick = n;
        record.t_s = static_cast<double>(n) * 1e-3;
        record.x_m[1] = -0.25 * static_cast<double>(n);
        if (ring.try_push(record)) ++accepted;
    }
    writer.finish();
    const std::vector<std::string> lines = lines_of(path);
    ASSERT_EQ(lines.size(), accepted + 1);
    EXPECT_EQ(lines.front(), servo::csv_header(2));
    EXPECT_EQ(writer.records_written(), accepted);
    EXPECT_EQ(accepted + ring.dropped(), kRecords);
    std::uint64_t previous_tick = 0;
    for (std::size_t i = 1; i < lines.size(); ++i) {
        const std::uint64_t tick = std::stoull(lines[i].substr(0, lines[i].find(',')));
        if (i > 1) {
            EXPECT_GT(tick, previous_tick);
        }
        previous_tick = tick;
    }
}

TEST(DaemonTelemetryWriter, RecordsLeftInTheRingAtStopAreWritten) {
    servo::TelemetryRing ring(1024);
    const ScratchDir dir;
    const std::string path = dir.file("drain.csv");
    TelemetryWriter writer(ring, path, 1);  // never started: finish() drains alone
    for (std::uint64_t n = 0; n < 700; ++n) {
        servo::TelemetryRecord record;
        record.tick = n;
        ASSERT_TRUE(ring.try_push(record));
    }
    writer.finish();
    const std::vector<std::string> lines = lines_of(path);
    ASSERT_EQ(lines.size(), 701u);
    EXPECT_EQ(lines[700].substr(0, 4), "699,");
}

TEST(DaemonTelemetryWriter, AnUncreatableFileIsNamed) {
    servo::TelemetryRing ring(16);
    try {
        TelemetryWriter writer(ring, "/nonexistent-dir/run.csv", 1);
        FAIL() << "expected an error";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("--log /nonexistent-dir/run.csv: cannot create"),
                  std::string::npos)
            << e.what();
    }
}

TEST(DaemonTelemetryWriter, AFullDiskIsReported) {
    if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
    servo::TelemetryRing ring(16);
    TelemetryWriter writer(ring, "/dev/full", 1);
    servo::TelemetryRecord record;
    ASSERT_TRUE(ring.try_push(record));
    try {
        writer.finish();
        FAIL() << "expected an error";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("--log /dev/full: writing telemetry failed"),
                  std::string::npos)
            << e.what();
    }
}

TEST(DaemonTelemetryWriter, RecordsReachTheFileWithinTheFlushIntervalWithoutFinish) {
    // What a SIGKILL would find: the records are in the file kFlushInterval after they were
    // pushed, each line whole, although finish() was never called and the buffer is far
    // from full.
    servo::TelemetryRing ring(1024);
    const ScratchDir dir;
    const std::string path = dir.file("timer.csv");
    TelemetryWriter writer(ring, path, 1);
    writer.start();
    for (std::uint64_t n = 0; n < 50; ++n) {
        servo::TelemetryRecord record;
        record.tick = n;
        ASSERT_TRUE(ring.try_push(record));
    }
    std::this_thread::sleep_for(TelemetryWriter::kFlushInterval + std::chrono::milliseconds(60));
    std::ifstream in(path, std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 51);
    ASSERT_FALSE(text.empty());
    EXPECT_EQ(text.back(), '\n');
    EXPECT_EQ(writer.records_written(), 50u);
    writer.finish();
}

TEST(DaemonTelemetryWriter, AFullDeviceCountsOnlyTheRecordsOnDisk) {
    servo::TelemetryRing ring(1024);
    const int fd = ::open("/dev/full", O_WRONLY | O_CLOEXEC);
    ASSERT_GE(fd, 0);
    TelemetryWriter writer(ring, fd, "/dev/full", 1);
    writer.start();
    for (std::uint64_t n = 0; n < 10; ++n) ASSERT_TRUE(ring.try_push(servo::TelemetryRecord{}));
    try {
        writer.finish();
        FAIL() << "finish() did not report the failed write";
    } catch (const std::runtime_error& e) {
        EXPECT_EQ(std::string(e.what()),
                  "--log /dev/full: writing telemetry failed: No space left on device; the file "
                  "holds the first 0 of 10 records, each line whole");
    }
    EXPECT_EQ(writer.records_taken(), 10u);
    EXPECT_EQ(writer.records_written(), 0u);
    EXPECT_FALSE(writer.complete());
}

TelemetryHeader left_arm_header() {
    return {.version = "0.1.0",
            .name = "left arm",
            .started_at = "2026-12-07T12:00:00.000Z",
            .host = "lab-pc",
            .device = "sim device, 1 axis",
            .config = "/etc/hapticd/left.toml",
            .config_sha256 = std::string(64, 'a'),
            .rate_hz = 1000.0,
            .stiffness_n_per_m = 2000.0,
            .damping_n_s_per_m = 0.5,
            .stability = "passed: passive model",
            .scene = "wall (impedance, /etc/hapticd/wall.toml)"};
}

std::string file_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {(std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()};
}

// The preamble names the run as "# key: value" lines, one line each whatever a value holds.
TEST(DaemonTelemetryWriter, ThePreambleNamesTheGainsVerdictSceneDeviceAndConfig) {
    TelemetryHeader header = left_arm_header();
    const std::string text = telemetry_preamble(header);
    for (const char* line :
         {"# version: 0.1.0\n", "# name: left arm\n", "# started: 2026-12-07T12:00:00.000Z\n",
          "# host: lab-pc\n", "# device: sim device, 1 axis\n",
          "# config: /etc/hapticd/left.toml\n", "# rate_hz: 1000\n",
          "# coupling_stiffness_n_per_m: 2000\n", "# coupling_damping_n_s_per_m: 0.5\n",
          "# stability: passed: passive model\n",
          "# scene: wall (impedance, /etc/hapticd/wall.toml)\n"}) {
        EXPECT_NE(text.find(line), std::string::npos) << line << " in\n" << text;
    }
    EXPECT_NE(text.find("# config_sha256: " + std::string(64, 'a') + "\n"), std::string::npos);
    for (const std::string& line : testing::lines_of_text(text)) EXPECT_EQ(line.front(), '#');

    header.name.clear();
    header.coupling_enabled = false;
    header.scene = "evil\n0,0,0\x1b[2J";  // a scene file's name: one line, no escape
    const std::string rigid = telemetry_preamble(header);
    EXPECT_EQ(rigid.find("# name:"), std::string::npos);
    EXPECT_EQ(rigid.find("coupling_stiffness"), std::string::npos);
    EXPECT_NE(rigid.find("# coupling: off"), std::string::npos);
    EXPECT_NE(rigid.find("# scene: evil\\x0a0,0,0\\x1b[2J\n"), std::string::npos) << rigid;
}

// The preamble is no record, on a disk that takes everything and on one that fails at once.
TEST(DaemonTelemetryWriter, APreambleComesFirstAndIsNoRecord) {
    const std::string preamble = telemetry_preamble(left_arm_header());
    const auto preamble_lines = std::count(preamble.begin(), preamble.end(), '\n');
    servo::TelemetryRing ring(1024);
    const ScratchDir dir;
    const std::string path = dir.file("named.csv");
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    ASSERT_GE(fd, 0);
    TelemetryWriter writer(ring, fd, path, 1, std::chrono::milliseconds{0}, preamble);
    writer.start();
    for (std::uint64_t n = 0; n < 20; ++n) {
        servo::TelemetryRecord record;
        record.tick = n;
        ASSERT_TRUE(ring.try_push(record));
    }
    writer.finish();
    EXPECT_EQ(writer.records_written(), 20u);
    const std::string text = file_text(path);
    EXPECT_EQ(text.rfind(preamble + servo::csv_header(1) + "\n", 0), 0u) << text;
    EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), preamble_lines + 21);

    servo::TelemetryRing full_ring(1024);
    const int full = ::open("/dev/full", O_WRONLY | O_CLOEXEC);
    ASSERT_GE(full, 0);
    TelemetryWriter failing(full_ring, full, "/dev/full", 1, std::chrono::milliseconds{0},
                            preamble);
    failing.start();
    for (std::uint64_t n = 0; n < 10; ++n) {
        ASSERT_TRUE(full_ring.try_push(servo::TelemetryRecord{}));
    }
    EXPECT_THROW(failing.finish(), std::runtime_error);
    EXPECT_EQ(failing.records_written(), 0u);
}

// Records 0..count-1, the mark going up by one every `every` ticks (from 0).
void push_marked(servo::TelemetryRing& ring, std::uint64_t count, std::uint64_t every) {
    for (std::uint64_t n = 0; n < count; ++n) {
        servo::TelemetryRecord record;
        record.tick = n;
        record.mark = static_cast<std::uint32_t>(n / every);
        while (!ring.try_push(record)) std::this_thread::yield();
    }
}

// "# mark N: TEXT" stands before the first record that carries N; a file that starts mid-trial
// (a recording) names the trial it starts in first.
TEST(DaemonTelemetryWriter, EachMarkIsNamedBeforeItsFirstRecord) {
    RunNotes notes;
    std::uint32_t published = 0;
    for (const char* text : {"trial A", "coupling k_c 1000 N/m", "trial B \xc3\xa9"}) {
        ASSERT_TRUE(notes.add(text, [&](std::uint32_t n) { published = n; }));
    }
    EXPECT_EQ(published, 3u);
    EXPECT_EQ(notes.text(2), "coupling k_c 1000 N/m");
    EXPECT_EQ(notes.text(4), "");

    const ScratchDir dir;
    for (const std::uint64_t first_tick : {std::uint64_t{0}, std::uint64_t{25}}) {
        SCOPED_TRACE(first_tick);
        servo::TelemetryRing ring(4096);
        const std::string path = dir.file("marks" + std::to_string(first_tick) + ".csv");
        const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
        ASSERT_GE(fd, 0);
        TelemetryWriter writer(ring, fd, path, 1, std::chrono::milliseconds{0}, "", &notes);
        writer.skip_ticks_before(first_tick);
        writer.start();
        push_marked(ring, 40, 10);  // marks 0, 1, 2, 3 from ticks 0, 10, 20, 30
        writer.finish();
        EXPECT_EQ(writer.records_written(), 40 - first_tick);
        const std::vector<std::string> lines = lines_of(path);
        std::vector<std::string> expected = {servo::csv_header(1)};
        for (std::uint64_t n = first_tick; n < 40; ++n) {
            const auto mark = n / 10;
            if (mark > 0 && (n % 10 == 0 || n == first_tick)) {
                expected.push_back("# mark " + std::to_string(mark) + ": " +
                                   notes.text(static_cast<std::uint32_t>(mark)));
            }
            expected.push_back(std::to_string(n));
        }
        ASSERT_EQ(lines.size(), expected.size());
        for (std::size_t i = 0; i < lines.size(); ++i) {
            if (expected[i].starts_with('#') || i == 0) {
                EXPECT_EQ(lines[i], expected[i]);
            } else {
                EXPECT_EQ(lines[i].substr(0, lines[i].find(',')), expected[i]);
                EXPECT_EQ(lines[i].substr(lines[i].rfind(',') + 1),
                          std::to_string(std::stoull(expected[i]) / 10));
            }
        }
    }
}

// A disk that fills mid-file: the count of records on disk leaves out the preamble, the
// header and the marks' lines, whole lines only. The file size limit (RLIMIT_FSIZE, in a
// child process of its own) cuts a write part way, as a full disk does.
TEST(DaemonTelemetryWriter, ACutFileCountsItsRecordsNotItsMarks) {
    RunNotes notes;
    for (int n = 0; n < 20; ++n) {
        ASSERT_TRUE(notes.add("trial " + std::to_string(n), [](std::uint32_t) {}));
    }
    const ScratchDir dir;
    const std::string path = dir.file("cut.csv");
    const std::string preamble = telemetry_preamble(left_arm_header());
    int report[2];
    ASSERT_EQ(::pipe(report), 0);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        ::signal(SIGXFSZ, SIG_IGN);
        const rlimit limit{.rlim_cur = 3000, .rlim_max = RLIM_INFINITY};
        ::setrlimit(RLIMIT_FSIZE, &limit);
        servo::TelemetryRing ring(4096);
        const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
        TelemetryWriter writer(ring, fd, path, 1, std::chrono::milliseconds{0}, preamble, &notes);
        push_marked(ring, 200, 10);
        try {
            writer.finish();
        } catch (const std::runtime_error&) {
        }
        const std::uint64_t written = writer.records_written();
        (void)!::write(report[1], &written, sizeof written);
        ::_exit(0);
    }
    ::close(report[1]);
    std::uint64_t written = 0;
    ASSERT_EQ(::read(report[0], &written, sizeof written), static_cast<ssize_t>(sizeof written));
    ::close(report[0]);
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    const std::string text = file_text(path);
    EXPECT_LE(text.size(), 3000u);
    EXPECT_EQ(text.back(), '\n');
    const std::vector<std::string> lines = testing::lines_of_text(text);
    const auto records = std::count_if(lines.begin(), lines.end(), [](const std::string& line) {
        return !line.empty() && std::isdigit(static_cast<unsigned char>(line.front()));
    });
    const auto marks = std::count_if(lines.begin(), lines.end(), [](const std::string& line) {
        return line.starts_with("# mark ");
    });
    EXPECT_GT(records, 10);
    EXPECT_LT(records, 200);
    EXPECT_GT(marks, 0);
    EXPECT_EQ(written, static_cast<std::uint64_t>(records));
}

}  // namespace
}  // namespace hapticd::daemon
