// The telemetry writer drains the ring into CSV; on a clean stop the file is complete.
#include "hapticd/daemon/telemetry_writer.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
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

// A named instance's files begin with "# name: NAME" (telemetry_preamble()); the preamble
// is no record, on a disk that takes everything and on one that fails mid-way.
TEST(DaemonTelemetryWriter, APreambleComesFirstAndIsNoRecord) {
    EXPECT_EQ(telemetry_preamble(""), "");
    EXPECT_EQ(telemetry_preamble("left arm"), "# name: left arm\n");
    servo::TelemetryRing ring(1024);
    const ScratchDir dir;
    const std::string path = dir.file("named.csv");
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    ASSERT_GE(fd, 0);
    TelemetryWriter writer(ring, fd, path, 1, std::chrono::milliseconds{0},
                           telemetry_preamble("left arm"));
    writer.start();
    for (std::uint64_t n = 0; n < 20; ++n) {
        servo::TelemetryRecord record;
        record.tick = n;
        ASSERT_TRUE(ring.try_push(record));
    }
    writer.finish();
    EXPECT_EQ(writer.records_written(), 20u);
    std::ifstream in(path, std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(text.rfind("# name: left arm\n" + servo::csv_header(1) + "\n", 0), 0u) << text;
    EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 22);

    servo::TelemetryRing full_ring(1024);
    const int full = ::open("/dev/full", O_WRONLY | O_CLOEXEC);
    ASSERT_GE(full, 0);
    TelemetryWriter failing(full_ring, full, "/dev/full", 1, std::chrono::milliseconds{0},
                            telemetry_preamble("left arm"));
    failing.start();
    for (std::uint64_t n = 0; n < 10; ++n) {
        ASSERT_TRUE(full_ring.try_push(servo::TelemetryRecord{}));
    }
    EXPECT_THROW(failing.finish(), std::runtime_error);
    EXPECT_EQ(failing.records_written(), 0u);
}

}  // namespace
}  // namespace hapticd::daemon
