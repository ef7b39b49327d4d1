// The stamp of a run (run_stamp.hpp): its start time as ISO 8601 and as a file name, and the
// `{start}` placeholder of --log and --summary.
#include "run/run_stamp.hpp"

#include <gtest/gtest.h>

#include <chrono>

namespace hapticd::daemon {
namespace {

using namespace std::chrono;

// 2026-12-03T12:41:00.123Z: 1796301660 s after the epoch (date -u -d @1796301660).
const system_clock::time_point kStart = system_clock::time_point(seconds(1796301660)) + 123ms;

TEST(RunStamp, TheStartIsIso8601InUtcToTheMillisecond) {
    const RunStamp stamp = stamp_run(kStart);
    EXPECT_EQ(stamp.started_at, "2026-12-03T12:41:00.123Z");
    EXPECT_EQ(stamp.start_name, "20261203T124100.123Z");
    EXPECT_FALSE(stamp.version.empty());
    EXPECT_FALSE(stamp.host.empty());
}

TEST(RunStamp, MillisecondsAreZeroPaddedAndNeverRoundedIntoTheNextSecond) {
    EXPECT_EQ(stamp_run(system_clock::time_point(seconds(1796301660)) + 7ms).started_at,
              "2026-12-03T12:41:00.007Z");
    EXPECT_EQ(stamp_run(system_clock::time_point(seconds(1796301660)) + 999999us).started_at,
              "2026-12-03T12:41:00.999Z");
}

TEST(RunStamp, EveryStartPlaceholderIsReplacedAndNothingElse) {
    const RunStamp stamp = stamp_run(kStart);
    EXPECT_EQ(with_start("/var/log/hapticd/sim/summary-{start}.json", stamp),
              "/var/log/hapticd/sim/summary-20261203T124100.123Z.json");
    EXPECT_EQ(with_start("{start}/{start}.csv", stamp),
              "20261203T124100.123Z/20261203T124100.123Z.csv");
    EXPECT_EQ(with_start("/tmp/summary.json", stamp), "/tmp/summary.json");
    EXPECT_EQ(with_start("{start", stamp), "{start");
    EXPECT_EQ(with_start("{{start}}", stamp), "{20261203T124100.123Z}");
}

}  // namespace
}  // namespace hapticd::daemon
