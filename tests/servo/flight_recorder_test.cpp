// The flight recorder (docs/architecture.md §7.12): the last ticks, oldest first; frozen by
// the tick that latches a new fault, holding that tick as its last; thawed by its reader.
#include "hapticd/servo/flight_recorder.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

#include "hapticd/servo/servo_loop.hpp"
#include "servo_fakes.hpp"

namespace hapticd::servo {
namespace {

TelemetryRecord record_of_tick(std::uint64_t tick) {
    TelemetryRecord r;
    r.tick = tick;
    r.t_s = static_cast<double>(tick) * 1e-3;
    return r;
}

TEST(ServoFlightRecorder, HoldsTheLastTicksOldestFirstOnlyWhileFrozen) {
    FlightRecorder recorder(4);
    for (std::uint64_t t = 0; t < 3; ++t) recorder.record(record_of_tick(t));
    EXPECT_TRUE(recorder.frozen_records().empty());  // not frozen: nothing to read
    recorder.freeze();
    std::vector<TelemetryRecord> held = recorder.frozen_records();
    ASSERT_EQ(held.size(), 3u);
    EXPECT_EQ(held.front().tick, 0u);
    EXPECT_EQ(held.back().tick, 2u);
    recorder.record(record_of_tick(99));  // frozen: the servo's records are not kept
    EXPECT_EQ(recorder.frozen_records().back().tick, 2u);
    recorder.thaw();
    for (std::uint64_t t = 3; t < 11; ++t) recorder.record(record_of_tick(t));
    recorder.freeze();
    held = recorder.frozen_records();
    ASSERT_EQ(held.size(), 4u);  // wrapped: the last four, in order
    for (std::size_t i = 0; i < held.size(); ++i) EXPECT_EQ(held[i].tick, 7u + i);
}

TEST(ServoFlightRecorder, ACapacityOfZeroIsRefused) {
    EXPECT_THROW(FlightRecorder(0), std::invalid_argument);
}

// In the loop: a scene that turns non-finite after 300 evaluations latches non_finite; the
// recorder freezes in that tick, with that tick last and the clean ticks before it.
TEST(ServoFlightRecorder, TheTickThatLatchesAFaultFreezesItAsItsLastRecord) {
    fakes::VirtualTime time;
    fakes::FakeDevice device;
    fakes::NanAfter environment{.after_evaluations = 300};
    ServoConfig config;
    config.axes = 1;
    config.counts_per_meter = 1e6;
    config.coupling = {.stiffness_n_per_m = 1000.0, .damping_n_s_per_m = 1.0};
    config.safety.soft_start = {.still_speed_mps = 1.0, .still_time_s = 0.0, .ramp_time_s = 0.0};
    ServoLoop<fakes::FakeDevice, fakes::NanAfter, fakes::FakeClock> loop(
        device, environment, config, nullptr, fakes::FakeClock{&time});
    FlightRecorder recorder(100);
    loop.attach_flight_recorder(&recorder);
    std::uint64_t fault_tick = 0;
    for (std::uint64_t n = 0; n < 1000 && !recorder.frozen(); ++n) {
        fault_tick = loop.tick().tick;
    }
    ASSERT_TRUE(recorder.frozen());
    ASSERT_EQ(loop.faults(), std::uint32_t{kFaultNonFinite});
    const std::vector<TelemetryRecord> held = recorder.frozen_records();
    ASSERT_EQ(held.size(), 100u);
    EXPECT_EQ(held.back().tick, fault_tick);
    EXPECT_EQ(held.back().faults, std::uint32_t{kFaultNonFinite});
    for (std::size_t i = 0; i + 1 < held.size(); ++i) {
        EXPECT_EQ(held[i].faults, 0u) << "tick " << held[i].tick;
        EXPECT_EQ(held[i + 1].tick, held[i].tick + 1);
    }
    // The fault stays latched: thawed, the recorder keeps recording, and the same fault
    // does not freeze it again; a reset and a new fault would.
    recorder.thaw();
    for (int n = 0; n < 10; ++n) loop.tick();
    EXPECT_FALSE(recorder.frozen());
}

}  // namespace
}  // namespace hapticd::servo
