// LoopControl (src/daemon/loop_control.hpp): the control socket reads the servo's status at
// most once per kStatusMaxAge, however often its clients ask, so that the status's cache lines
// cross to the socket's core a bounded number of times a second (docs/benchmarks.md, "The
// servo under socket abuse").
#include "../../src/daemon/loop_control.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

namespace hapticd::daemon {
namespace {

/// What LoopControl calls on a loop, counting the status reads.
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
};

TEST(DaemonLoopControl, ServesOneStatusReadToEveryAskerWithinItsMaxAgeThenReadsAgain) {
    CountingLoop loop;
    LoopControl<CountingLoop> control(loop, servo::CouplingGains{});
    loop.tick = 7;
    const auto first = std::chrono::steady_clock::now();
    EXPECT_EQ(control.status().tick, 7u);
    loop.tick = 8;  // the servo ticks on; the socket serves the copy it has
    int asked = 1;
    while (std::chrono::steady_clock::now() - first < kStatusMaxAge / 2) {
        EXPECT_EQ(control.status().tick, 7u);
        ++asked;
    }
    EXPECT_GT(asked, 100);
    EXPECT_EQ(loop.status_reads, 1);
    std::this_thread::sleep_for(kStatusMaxAge + std::chrono::milliseconds(1));
    EXPECT_EQ(control.status().tick, 8u);
    EXPECT_EQ(loop.status_reads, 2);
}

}  // namespace
}  // namespace hapticd::daemon
