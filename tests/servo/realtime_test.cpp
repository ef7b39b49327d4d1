// Real-time setup: modes and reporting. Runs the requests on a helper thread so that the
// test process's main thread keeps its normal scheduling.
#include "hapticd/servo/realtime.hpp"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <string>
#include <thread>
#include <vector>

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

// The CPUs in the calling thread's set.
std::vector<int> own_cpus() {
    cpu_set_t set;
    CPU_ZERO(&set);
    pthread_getaffinity_np(pthread_self(), sizeof(set), &set);
    std::vector<int> cpus;
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
        if (CPU_ISSET(static_cast<std::size_t>(cpu), &set)) cpus.push_back(cpu);
    }
    return cpus;
}

void pin_to(const std::vector<int>& cpus) {
    cpu_set_t set;
    CPU_ZERO(&set);
    for (const int cpu : cpus) CPU_SET(static_cast<std::size_t>(cpu), &set);
    ASSERT_EQ(pthread_setaffinity_np(pthread_self(), sizeof(set), &set), 0);
}

// Each case runs on a thread of its own, which it may pin as it likes.
template <typename Body>
void on_own_thread(Body body) {
    std::thread thread(body);
    thread.join();
}

TEST(ServoRealtime, OtherThreadsLeaveTheServosCpuThoseThereAndThoseStartedAfter) {
    const std::vector<int> all = own_cpus();
    if (all.size() < 2) GTEST_SKIP() << "needs two CPUs";
    const int servo_cpu = all.back();
    std::vector<int> expected = all;
    expected.pop_back();
    on_own_thread([&] {
        const OtherThreadsCpus result = keep_other_threads_off(servo_cpu);
        EXPECT_TRUE(result.off_servo_cpu);
        EXPECT_EQ(result.why_not, "");
        EXPECT_EQ(own_cpus(), expected);
        // Two CPUs here: the list is the one left; more: it starts with the first.
        EXPECT_EQ(result.cpus.rfind(std::to_string(all.front()), 0), 0U) << result.cpus;
        EXPECT_EQ(result.cpus.find(std::to_string(servo_cpu)), std::string::npos) << result.cpus;
        std::vector<int> child;
        std::thread([&] { child = own_cpus(); }).join();
        EXPECT_EQ(child, expected);
    });
    // The thread that was there already (this one) too; then it gets its CPUs back.
    EXPECT_EQ(own_cpus(), expected);
    pin_to(all);
    EXPECT_EQ(own_cpus(), all);
}

TEST(ServoRealtime, OtherThreadsCpusNamesAContiguousRangeAsARange) {
    const std::vector<int> all = own_cpus();
    if (all.size() < 2) GTEST_SKIP() << "needs two CPUs";
    on_own_thread([&] {
        pin_to({all[0], all[1]});
        // Nothing to keep off: the list of the whole set.
        const OtherThreadsCpus result = keep_other_threads_off(-1);
        EXPECT_FALSE(result.off_servo_cpu);
        EXPECT_EQ(result.why_not, "");
        const std::string expected = all[1] == all[0] + 1
                                         ? std::to_string(all[0]) + "-" + std::to_string(all[1])
                                         : std::to_string(all[0]) + "," + std::to_string(all[1]);
        EXPECT_EQ(result.cpus, expected);
        EXPECT_EQ(own_cpus(), (std::vector<int>{all[0], all[1]}));
    });
}

TEST(ServoRealtime,
     OtherThreadsAreOffTheServosCpuAlreadyWhenItIsNotAmongThemAndCannotBeWhenItIsTheOnlyOne) {
    const std::vector<int> all = own_cpus();
    if (all.size() < 2) GTEST_SKIP() << "needs two CPUs";
    on_own_thread([&] {
        pin_to({all[0]});
        // As isolcpus= or the unit's CPUAffinity= leave it: nothing to do, and done.
        const OtherThreadsCpus outside = keep_other_threads_off(all[1]);
        EXPECT_TRUE(outside.off_servo_cpu);
        EXPECT_EQ(outside.cpus, std::to_string(all[0]));
        EXPECT_EQ(outside.why_not, "");
        const OtherThreadsCpus only = keep_other_threads_off(all[0]);
        EXPECT_FALSE(only.off_servo_cpu);
        EXPECT_NE(only.why_not.find("is the only one"), std::string::npos) << only.why_not;
        EXPECT_EQ(own_cpus(), std::vector<int>{all[0]});
    });
}

}  // namespace
}  // namespace hapticd::servo
