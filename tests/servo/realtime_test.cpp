// Real-time setup: modes and reporting. Runs the requests on a helper thread so that the
// test process's main thread keeps its normal scheduling.
#include "hapticd/servo/realtime.hpp"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <thread>

namespace hapticd::servo {
namespace {

TEST(ServoRealtime, ParsesTheConfigWords) {
    EXPECT_EQ(parse_realtime_mode("enforce"), RealtimeMode::enforce);
    EXPECT_EQ(parse_realtime_mode("warn"), RealtimeMode::warn);
    EXPECT_EQ(parse_realtime_mode("off"), RealtimeMode::off);
    try {
        parse_realtime_mode("always");
        FAIL() << "no exception";
    } catch (const std::invalid_argument& error) {
        EXPECT_NE(std::string(error.what()).find("always"), std::string::npos);
    }
}

TEST(ServoRealtime, OffDoesNothing) {
    RealtimeSession session;
    const RealtimeReport report = session.apply({.mode = RealtimeMode::off});
    EXPECT_FALSE(report.scheduler_fifo);
    EXPECT_FALSE(report.memory_locked);
    EXPECT_TRUE(report.all_granted());
}

TEST(ServoRealtime, RejectsBadPriorityAndCpu) {
    RealtimeSession session;
    EXPECT_THROW(session.apply({.mode = RealtimeMode::warn, .priority = 0}), std::invalid_argument);
    EXPECT_THROW(session.apply({.mode = RealtimeMode::warn, .priority = 100}),
                 std::invalid_argument);
    EXPECT_THROW(session.apply({.mode = RealtimeMode::warn, .cpu = 100000}), std::invalid_argument);
}

TEST(ServoRealtime, WarnReportsWhatWasGrantedOnTheCallingThread) {
    RealtimeReport report;
    int policy_seen = -1;
    std::thread servo_thread([&] {
        RealtimeSession session;
        report = session.apply({.mode = RealtimeMode::warn,
                                .priority = 10,
                                .cpu = 0,
                                .lock_memory = false,
                                .hold_cpu_dma_latency = false});
        sched_param parameters{};
        pthread_getschedparam(pthread_self(), &policy_seen, &parameters);
    });
    servo_thread.join();
    // Whatever was granted is what the thread really has; what was not is listed.
    EXPECT_EQ(report.scheduler_fifo, policy_seen == SCHED_FIFO);
    EXPECT_EQ(report.all_granted(), report.scheduler_fifo && report.affinity_set);
    EXPECT_NE(report.brief().find("realtime warn"), std::string::npos);
    // The main thread is untouched.
    int main_policy = -1;
    sched_param parameters{};
    pthread_getschedparam(pthread_self(), &main_policy, &parameters);
    EXPECT_EQ(main_policy, SCHED_OTHER);
}

}  // namespace
}  // namespace hapticd::servo
