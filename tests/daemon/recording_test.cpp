// record start / record stop (src/daemon/socket/recording.hpp) against a stand-in servo thread that
// ticks and pushes to whatever ring is attached, as ServoLoop::record does: every tick from the
// start to the stop is in the file, once and in order, in the --log format the product's own reader
// reads; and each refusal says why.
#include "socket/recording.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "outputs/outputs_directory.hpp"
#include "scratch_dir.hpp"
#include "telemetry_csv.hpp"
#include "text_file.hpp"

namespace hapticd::daemon {
namespace {

using hapticd::testing::ScratchDir;
using namespace std::chrono_literals;

// Ticks about every 100 us, pushing each tick's record to the attached ring, and publishes
// the tick after the push, as the loop publishes its status after its record.
class FakeServo {
  public:
    FakeServo()
        : thread_([this] {
              std::uint64_t tick = 0;
              while (!stop_.load()) {
                  servo::TelemetryRecord record;
                  record.tick = tick;
                  record.t_s = static_cast<double>(tick) * 1e-3;
                  record.x_m = {1e-6 * static_cast<double>(tick), 0.0, 0.0};
                  if (servo::TelemetryRing* ring = ring_.load()) ring->try_push(record);
                  published_.store(tick);
                  ++tick;
                  std::this_thread::sleep_for(100us);
              }
          }) {}
    ~FakeServo() { halt(); }
    void halt() {
        stop_ = true;
        if (thread_.joinable()) thread_.join();
    }
    void attach(servo::TelemetryRing* ring) { ring_.store(ring); }
    std::uint64_t tick() const { return published_.load(); }

  private:
    std::atomic<servo::TelemetryRing*> ring_{nullptr};
    std::atomic<std::uint64_t> published_{0};
    std::atomic<bool> stop_{false};
    std::thread thread_;
};

Recording recording_of(FakeServo& servo, const OutputsDirectory* directory) {
    return Recording([&servo](servo::TelemetryRing* ring) { servo.attach(ring); },
                     [&servo] { return servo.tick(); }, /*axes=*/1, /*lockstep=*/false, directory);
}

TEST(DaemonRecording, EveryTickFromTheStartToTheStopIsInTheFileOnce) {
    const ScratchDir dir;
    const OutputsDirectory outputs(dir.path().string());
    FakeServo servo;
    Recording recording = recording_of(servo, &outputs);
    const std::string path = dir.file("first.csv");
    for (int round = 0; round < 2; ++round) {  // the ring serves one recording after another
        const std::string file = round == 0 ? path : dir.file("second.csv");
        const RecordingResult started = recording.start(file);
        ASSERT_TRUE(started.ok) << started.message;
        EXPECT_EQ(recording.active_path(), file);
        std::this_thread::sleep_for(200ms);
        const std::uint64_t before_stop = servo.tick();
        const RecordingResult stopped = recording.stop();
        ASSERT_TRUE(stopped.ok) << stopped.message;
        EXPECT_FALSE(recording.active_path().has_value());
        EXPECT_EQ(stopped.dropped, 0u);
        const hapticd::testing::TelemetryLog log = hapticd::testing::read_telemetry(file);
        ASSERT_EQ(log.rows(), stopped.records);
        ASSERT_GT(log.rows(), 100u) << "200 ms of ticks every 100 us or so";
        const std::vector<double>& tick = log.column("tick");
        EXPECT_EQ(tick.front(), static_cast<double>(started.first_tick));
        for (std::size_t i = 1; i < tick.size(); ++i) {
            ASSERT_EQ(tick[i], tick[i - 1] + 1.0) << "a tick lost or repeated at row " << i;
        }
        EXPECT_GE(tick.back(), static_cast<double>(before_stop));  // to the stop, not short
        EXPECT_DOUBLE_EQ(log.column("x0_m")[5], 1e-6 * tick[5]);
    }
}

// Each recording begins with the preamble as it is when the recording starts (the gains and
// scene in force then), and counts only records.
TEST(DaemonRecording, EachRecordingBeginsWithThePreambleOfItsStart) {
    const ScratchDir dir;
    const OutputsDirectory outputs(dir.path().string());
    FakeServo servo;
    int starts = 0;
    Recording recording(
        [&servo](servo::TelemetryRing* ring) { servo.attach(ring); },
        [&servo] { return servo.tick(); }, /*axes=*/1, /*lockstep=*/false, &outputs,
        [&starts] { return "# name: rig 2\n# start: " + std::to_string(++starts) + "\n"; });
    for (int round = 1; round <= 2; ++round) {
        const std::string file = dir.file("named" + std::to_string(round) + ".csv");
        ASSERT_TRUE(recording.start(file).ok);
        std::this_thread::sleep_for(50ms);
        const RecordingResult stopped = recording.stop();
        ASSERT_TRUE(stopped.ok) << stopped.message;
        const std::vector<std::string> lines = hapticd::testing::lines_of_file(file);
        ASSERT_GE(lines.size(), 3u);
        EXPECT_EQ(lines[0], "# name: rig 2");
        EXPECT_EQ(lines[1], "# start: " + std::to_string(round));
        EXPECT_EQ(lines[2].rfind("tick,", 0), 0u) << lines[2];
        EXPECT_EQ(lines.size(), stopped.records + 3);
    }
}

TEST(DaemonRecording, EachRefusalSaysWhyAndNothingIsOverwritten) {
    const ScratchDir dir;
    const OutputsDirectory outputs(dir.path().string());
    FakeServo servo;
    Recording recording = recording_of(servo, &outputs);
    const RecordingResult idle_stop = recording.stop();
    EXPECT_FALSE(idle_stop.ok);
    EXPECT_NE(idle_stop.message.find("not recording"), std::string::npos) << idle_stop.message;

    const std::string existing = dir.write("kept.csv", "precious\n");
    const RecordingResult over = recording.start(existing);
    EXPECT_FALSE(over.ok);
    EXPECT_NE(over.message.find("cannot create " + existing +
                                ": it exists, and no file is ever overwritten"),
              std::string::npos)
        << over.message;
    EXPECT_EQ(hapticd::testing::read_file(existing), "precious\n");

    const RecordingResult nowhere = recording.start(dir.file("no/such/dir/run.csv"));
    EXPECT_FALSE(nowhere.ok);
    EXPECT_NE(nowhere.message.find("is outside this daemon's directory for a client's files"),
              std::string::npos)
        << nowhere.message;

    ASSERT_TRUE(recording.start(dir.file("a.csv")).ok);
    const RecordingResult twice = recording.start(dir.file("b.csv"));
    EXPECT_FALSE(twice.ok);
    EXPECT_NE(twice.message.find("already recording to " + dir.file("a.csv")), std::string::npos)
        << twice.message;
    EXPECT_FALSE(std::filesystem::exists(dir.file("b.csv")));
    EXPECT_TRUE(recording.stop().ok);
}

// The run ends while recording: the file is closed with every tick the servo ran.
TEST(DaemonRecording, ARecordingStillRunningAtTheEndIsClosedWhole) {
    const ScratchDir dir;
    const OutputsDirectory outputs(dir.path().string());
    FakeServo servo;
    Recording recording = recording_of(servo, &outputs);
    EXPECT_FALSE(recording.finish_at_exit().has_value());
    ASSERT_TRUE(recording.start(dir.file("end.csv")).ok);
    std::this_thread::sleep_for(100ms);
    servo.halt();
    const std::uint64_t last = servo.tick();
    const std::optional<RecordingResult> ended = recording.finish_at_exit();
    ASSERT_TRUE(ended.has_value());
    ASSERT_TRUE(ended->ok) << ended->message;
    EXPECT_EQ(ended->dropped, 0u);
    const hapticd::testing::TelemetryLog log =
        hapticd::testing::read_telemetry(dir.file("end.csv"));
    ASSERT_EQ(log.rows(), ended->records);
    EXPECT_EQ(log.column("tick").back(), static_cast<double>(last));
}

// The path policy (docs/control.md, "Paths and strings"): a client's file is a new file directly in
// the run's outputs directory, named alone or by an absolute path to that directory however it is
// spelled; nothing else, whatever '..' or links the path holds, and never through a link
// planted there (issue 28: a non-root client made the root daemon create a root-owned file in
// a 0700 directory through '..'; a planted link made the flight recorder overwrite a file).
TEST(DaemonRecording, AClientsFileIsANewFileInTheOutputsDirectoryAndNowhereElse) {
    const ScratchDir dir;
    std::filesystem::create_directory(dir.file("out"));
    std::filesystem::create_directory(dir.file("private"));
    std::filesystem::permissions(dir.file("private"), std::filesystem::perms::owner_all);
    const std::string victim = dir.write("private/victim.csv", "precious\n");
    const OutputsDirectory outputs(dir.file("out"));
    FakeServo servo;
    Recording recording = recording_of(servo, &outputs);

    // Refused, and nothing made anywhere.
    std::filesystem::create_directory_symlink(dir.file("private"), dir.file("out/into"));
    std::filesystem::create_symlink(victim, dir.file("out/planted.csv"));
    struct Case {
        std::string path;
        std::string says;
    };
    const Case refused[] = {
        {dir.file("out/../private/x.csv"), "is not in normal form"},
        {dir.file("out/./x.csv"), "is not in normal form"},
        {dir.file("out") + "//x.csv", "is not in normal form"},
        {dir.file("private/x.csv"), "is outside this daemon's directory for a client's files"},
        {dir.file("out/into/x.csv"), "is outside this daemon's directory"},
        {"into/x.csv", "is a relative path"},
        {"../x.csv", "is a relative path"},
        {".hidden.csv", "is no file name a client may have"},
        {"..", "is no file name a client may have"},
        {std::string(256, 'a'), "has a name longer than 255 bytes"},
        {"planted.csv", "it exists, and no file is ever overwritten"},
        {dir.file("out/planted.csv"), "it exists, and no file is ever overwritten"},
    };
    for (const Case& c : refused) {
        SCOPED_TRACE(c.path);
        const RecordingResult r = recording.start(c.path);
        EXPECT_FALSE(r.ok);
        EXPECT_NE(r.message.find(c.says), std::string::npos) << r.message;
        if (c.says.find("exists") == std::string::npos) {
            EXPECT_NE(r.message.find("allowed a file name alone (take1.csv), or an absolute path "
                                     "to a file directly in " +
                                     dir.file("out")),
                      std::string::npos)
                << r.message;
        }
    }
    EXPECT_EQ(hapticd::testing::read_file(victim), "precious\n");
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.file("private")),
                            std::filesystem::directory_iterator{}),
              1);

    // A name alone, and the directory by another spelling (a link to it): made in it.
    const RecordingResult bare = recording.start("take1.csv");
    ASSERT_TRUE(bare.ok) << bare.message;
    EXPECT_EQ(bare.path, dir.file("out/take1.csv"));
    ASSERT_TRUE(recording.stop().ok);
    std::filesystem::create_directory_symlink(dir.file("out"), dir.file("elsewhere"));
    const RecordingResult spelled = recording.start(dir.file("elsewhere/take2.csv"));
    ASSERT_TRUE(spelled.ok) << spelled.message;
    EXPECT_EQ(spelled.path, dir.file("out/take2.csv"));
    ASSERT_TRUE(recording.stop().ok);
    EXPECT_TRUE(std::filesystem::is_regular_file(dir.file("out/take2.csv")));
    struct stat st {};
    ASSERT_EQ(::stat(dir.file("out/take2.csv").c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 0777U, 0640U);
}

TEST(DaemonRecording, ARunWithoutAnOutputsDirectoryRecordsNowhere) {
    FakeServo servo;
    Recording recording = recording_of(servo, nullptr);
    const RecordingResult r = recording.start("take1.csv");
    EXPECT_FALSE(r.ok);
    EXPECT_EQ(r.message, kNoOutputsDirectory);
}

// --log or --summary that is no regular file names no directory for the run's files
// (issue 28: --summary /dev/null put the flight records in /dev).
TEST(DaemonOutputsDirectory, OnlyARegularOutputFileNamesItsDirectory) {
    const ScratchDir dir;
    RunOptions options;
    options.summary_path = "/dev/null";
    EXPECT_EQ(outputs_directory_path(options), std::nullopt);
    options.log_path = "/dev/null";
    EXPECT_EQ(outputs_directory_path(options), std::nullopt);
    options.summary_path = dir.file("summary.json");  // not made yet: its directory counts
    EXPECT_EQ(outputs_directory_path(options), dir.path().string());
    options.log_path = dir.write("run.csv", "");
    options.summary_path = "-";
    EXPECT_EQ(outputs_directory_path(options), dir.path().string());
}

}  // namespace
}  // namespace hapticd::daemon
