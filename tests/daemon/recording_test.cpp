// record start / record stop (daemon/recording.hpp) against a stand-in servo thread that ticks
// and pushes to whatever ring is attached, as ServoLoop::record does: every tick from the start
// to the stop is in the file, once and in order, in the --log format the product's own reader
// reads; and each refusal says why.
#include "hapticd/daemon/recording.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

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

Recording recording_of(FakeServo& servo) {
    return Recording([&servo](servo::TelemetryRing* ring) { servo.attach(ring); },
                     [&servo] { return servo.tick(); }, /*axes=*/1, /*lockstep=*/false);
}

TEST(DaemonRecording, EveryTickFromTheStartToTheStopIsInTheFileOnce) {
    const ScratchDir dir;
    FakeServo servo;
    Recording recording = recording_of(servo);
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

TEST(DaemonRecording, EachRefusalSaysWhyAndNothingIsOverwritten) {
    const ScratchDir dir;
    FakeServo servo;
    Recording recording = recording_of(servo);
    const RecordingResult idle_stop = recording.stop();
    EXPECT_FALSE(idle_stop.ok);
    EXPECT_NE(idle_stop.message.find("not recording"), std::string::npos) << idle_stop.message;

    const std::string existing = dir.write("kept.csv", "precious\n");
    const RecordingResult over = recording.start(existing);
    EXPECT_FALSE(over.ok);
    EXPECT_NE(over.message.find("cannot create " + existing +
                                ": it exists, and a recording never overwrites a file"),
              std::string::npos)
        << over.message;
    EXPECT_EQ(hapticd::testing::read_file(existing), "precious\n");

    const RecordingResult nowhere = recording.start(dir.file("no/such/dir/run.csv"));
    EXPECT_FALSE(nowhere.ok);
    EXPECT_NE(nowhere.message.find("No such file or directory"), std::string::npos)
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
    FakeServo servo;
    Recording recording = recording_of(servo);
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

}  // namespace
}  // namespace hapticd::daemon
