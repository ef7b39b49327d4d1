// The flight recorder's file (src/daemon/flight_file.hpp): a new file in the run's outputs
// directory, never over a file and never through a link planted under its name (issue 28:
// a planted link made it overwrite another file, which it truncated first).
#include "outputs/flight_file.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "hapticd/daemon/exit_code.hpp"
#include "outputs/flight_writer.hpp"
#include "run/run_ending.hpp"
#include "scratch_dir.hpp"
#include "telemetry_csv.hpp"
#include "text_file.hpp"

namespace hapticd::daemon {
namespace {

using hapticd::testing::ScratchDir;

std::vector<servo::TelemetryRecord> ticks_to(std::uint64_t last) {
    std::vector<servo::TelemetryRecord> records(last + 1);
    for (std::uint64_t i = 0; i <= last; ++i) records[i].tick = i;
    return records;
}

TEST(DaemonFlightFile, ItIsANewFileAndNeverGoesThroughAPlantedLink) {
    const ScratchDir dir;
    const OutputsDirectory outputs(dir.path().string());
    const FlightFile written = write_flight_file(outputs, "run1", ticks_to(9), 1);
    ASSERT_EQ(written.error, "");
    EXPECT_EQ(written.path, dir.file("flight-run1-tick9.csv"));
    EXPECT_EQ(hapticd::testing::read_telemetry(written.path).rows(), 10u);

    const std::string victim = dir.write("victim.txt", "precious\n");
    std::filesystem::create_symlink(victim, dir.file("flight-run1-tick20.csv"));
    const FlightFile planted = write_flight_file(outputs, "run1", ticks_to(20), 1);
    EXPECT_EQ(planted.error, "cannot create " + dir.file("flight-run1-tick20.csv") +
                                 ": it exists, and no file is ever overwritten");
    EXPECT_EQ(hapticd::testing::read_file(victim), "precious\n");
    // Nor over its own: a second fault at the same tick (a reset loop) is refused too.
    const FlightFile again = write_flight_file(outputs, "run1", ticks_to(9), 1);
    EXPECT_NE(again.error.find("it exists"), std::string::npos) << again.error;
}

// A fault that keeps returning (a reset loop made 247 files, 48 MB, in 5 s) writes at most
// the run's cap; the rest are counted for the summary, and said once.
TEST(DaemonFlightFile, ARunWritesAtMostItsCapAndCountsTheRest) {
    const ScratchDir dir;
    const OutputsDirectory outputs(dir.path().string());
    FlightWriter writer(&outputs, /*rate_hz=*/1000.0, /*axes=*/1);
    RunContext context;
    context.stamp.start_name = "run1";
    std::ostringstream log;
    constexpr int kFaults = kMaxFlightFilesPerRun + 5;
    std::uint64_t tick = 0;
    for (int fault = 0; fault < kFaults; ++fault) {
        for (int i = 0; i < 10; ++i) {
            servo::TelemetryRecord record;
            record.tick = tick++;
            record.faults = i == 9 ? 1U : 0U;
            ASSERT_TRUE(writer.recorder().record(record));
        }
        writer.recorder().freeze();
        writer.write_frozen(context, log);
        EXPECT_FALSE(writer.recorder().frozen());  // thawed whether written or not
    }
    EXPECT_EQ(context.flight_records.size(), static_cast<std::size_t>(kMaxFlightFilesPerRun));
    EXPECT_EQ(context.flight_records_not_written, 5u);
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                            std::filesystem::directory_iterator{}),
              kMaxFlightFilesPerRun);
    const std::string said = log.str();
    const std::string cap = "are capped at 16 files and 32 MiB";
    ASSERT_NE(said.find(cap), std::string::npos) << said;
    EXPECT_EQ(said.find(cap, said.find(cap) + 1), std::string::npos) << "said more than once";
}

// A flight record that could not be written is an output not whole: the summary says so and
// a run that ends without a fault exits 3, as for an incomplete --log.
TEST(DaemonFlightFile, AFailedWriteMakesTheRunsOutputsNotWhole) {
    const ScratchDir dir;
    const OutputsDirectory outputs(dir.path().string());
    FlightWriter writer(&outputs, /*rate_hz=*/1000.0, /*axes=*/1);
    RunContext context;
    context.stamp.start_name = "run1";
    dir.write("flight-run1-tick4.csv", "planted\n");  // the name its record would take
    for (std::uint64_t tick = 0; tick < 5; ++tick) {
        servo::TelemetryRecord record;
        record.tick = tick;
        record.faults = tick == 4 ? 1U : 0U;
        ASSERT_TRUE(writer.recorder().record(record));
    }
    writer.recorder().freeze();
    std::ostringstream log;
    writer.write_frozen(context, log);
    EXPECT_FALSE(context.flight_records_complete);
    EXPECT_EQ(context.flight_records_not_written, 1u);
    EXPECT_NE(log.str().find("not written: cannot create"), std::string::npos) << log.str();
    const servo::Summary summary{};
    EXPECT_EQ(check_outputs_whole(kExitOk, /*summary_written=*/true, summary, context, log),
              kExitOutput);
    context.flight_records_complete = true;
    EXPECT_EQ(check_outputs_whole(kExitOk, /*summary_written=*/true, summary, context, log),
              kExitOk);
}

}  // namespace
}  // namespace hapticd::daemon
