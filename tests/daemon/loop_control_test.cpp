// InboxServoControl (src/daemon/socket/loop_ports.hpp): the control socket reads the servo's status
// at most once per kStatusMaxAge, however often its clients ask, so that the status's cache lines
// cross to the socket's core a bounded number of times a second (docs/benchmarks.md, "The
// servo under socket abuse").
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "socket/loop_ports.hpp"

namespace hapticd::daemon {
namespace {

/// What InboxServoControl calls on a loop, counting the status reads.
struct CountingLoop {
    mutable int status_reads = 0;
    std::uint64_t tick = 0;
    servo::StatusSnapshot status() const noexcept {
        ++status_reads;
        servo::StatusSnapshot s;
        s.tick = tick;
        return s;
    }
    void arm() noexcept {}
    void disarm() noexcept {}
    void request_fault_reset() noexcept {}
    void request_coupling(const servo::CouplingGains& /*gains*/) noexcept {}
    void mark(std::uint32_t /*number*/) noexcept {}
};

TEST(DaemonLoopControl, ServesOneStatusReadToEveryAskerWithinItsMaxAgeThenReadsAgain) {
    CountingLoop loop;
    InboxServoControl<CountingLoop> control(loop, servo::CouplingGains{});
    loop.tick = 7;
    const auto first = std::chrono::steady_clock::now();
    EXPECT_EQ(control.recent_status().tick, 7u);
    loop.tick = 8;  // the servo ticks on; the socket serves the copy it has
    for (int asked = 0; asked < 1000; ++asked) control.recent_status();
    const auto elapsed = std::chrono::steady_clock::now() - first;
    // A thousand asks (microseconds, unless the machine stalled this thread): one read per
    // kStatusMaxAge that passed, where asking the loop each time would be a thousand.
    EXPECT_LE(loop.status_reads, 1 + static_cast<int>(elapsed / kStatusMaxAge));
    std::this_thread::sleep_for(kStatusMaxAge + std::chrono::milliseconds(1));
    const int before = loop.status_reads;
    EXPECT_EQ(control.recent_status().tick, 8u);
    EXPECT_EQ(loop.status_reads, before + 1);
}

TEST(DaemonLoopControl, StatusForARequestThatDecidesIsTheLoopsLatest) {
    CountingLoop loop;
    InboxServoControl<CountingLoop> control(loop, servo::CouplingGains{});
    loop.tick = 7;
    EXPECT_EQ(control.recent_status().tick, 7u);
    loop.tick = 8;
    EXPECT_EQ(control.status().tick, 8u);  // not the copy
    EXPECT_EQ(loop.status_reads, 2);
}

}  // namespace
}  // namespace hapticd::daemon
