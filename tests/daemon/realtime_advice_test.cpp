// What hapticd says to do about a refused real-time request (realtime_advice.hpp): in a
// unit's words inside a service, in a shell's outside, and a kernel's refusal told apart from
// a resource limit's.
#include "run/realtime_advice.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <string>

#include "scratch_dir.hpp"

namespace hapticd::daemon {
namespace {

using servo::RealtimeMode;
using servo::RealtimeReport;
using servo::RealtimeRequest;

RealtimeReport everything_refused() {
    RealtimeReport report;
    report.mode = RealtimeMode::warn;
    report.refused = {"SCHED_FIFO 80: Operation not permitted", "mlockall: Cannot allocate memory",
                      "affinity to cpu 1: Invalid argument",
                      "/dev/cpu_dma_latency: Permission denied"};
    return report;
}

RealtimeRequest pinned_request() {
    RealtimeRequest request;
    request.cpu = 1;
    return request;
}

RealtimeSurroundings service(std::optional<std::uint64_t> rtprio, bool rt_groups = false) {
    return {.in_a_service = true, .rtprio_limit = rtprio, .rt_group_scheduling = rt_groups};
}

TEST(RealtimeAdvice, InAServiceItNamesTheUnitsSettings) {
    const std::string advice = realtime_advice(pinned_request(), everything_refused(), service(0));
    EXPECT_NE(advice.find("SCHED_FIFO 80 is above this process's RLIMIT_RTPRIO of 0: set "
                          "LimitRTPRIO=80 or more in the unit"),
              std::string::npos)
        << advice;
    EXPECT_NE(advice.find("LimitMEMLOCK=infinity in the unit"), std::string::npos) << advice;
    EXPECT_NE(advice.find("cpu 1 must be one this process may run on"), std::string::npos);
    EXPECT_NE(advice.find("DeviceAllow=/dev/cpu_dma_latency rw"), std::string::npos) << advice;
    EXPECT_EQ(realtime_refused_note(pinned_request(), everything_refused()),
              "realtime refused: SCHED_FIFO, mlockall, affinity, cpu_dma_latency");
}

TEST(RealtimeAdvice, InAShellItNamesUlimitAndLimitsD) {
    const std::string advice = realtime_advice(pinned_request(), everything_refused(),
                                               {.in_a_service = false, .rtprio_limit = 10});
    EXPECT_NE(advice.find("RLIMIT_RTPRIO of 10: raise it (ulimit -r 80"), std::string::npos)
        << advice;
    EXPECT_NE(advice.find("ulimit -l unlimited"), std::string::npos) << advice;
    EXPECT_EQ(advice.find("LimitRTPRIO"), std::string::npos) << advice;
}

TEST(RealtimeAdvice, ALimitThatAllowsThePriorityMeansTheKernelRefused) {
    for (const std::optional<std::uint64_t> limit :
         {std::optional<std::uint64_t>(99), std::optional<std::uint64_t>(80),
          std::optional<std::uint64_t>()}) {
        const std::string advice =
            realtime_advice(pinned_request(), everything_refused(), service(limit));
        const std::string shown = limit ? std::to_string(*limit) : "unlimited";
        EXPECT_NE(advice.find("SCHED_FIFO 80 was refused although RLIMIT_RTPRIO (" + shown +
                              ") allows it: the kernel refused it"),
                  std::string::npos)
            << advice;
        EXPECT_EQ(advice.find("LimitRTPRIO="), std::string::npos) << advice;
    }
    const std::string groups =
        realtime_advice(pinned_request(), everything_refused(), service(90, true));
    EXPECT_NE(groups.find("RT group scheduling (CONFIG_RT_GROUP_SCHED)"), std::string::npos)
        << groups;
    EXPECT_NE(groups.find("cpu.rt_runtime_us"), std::string::npos) << groups;
    EXPECT_NE(groups.find("under cgroup v2, which has no such budget, keep the cpu controller "
                          "off the service's slice"),
              std::string::npos)
        << groups;
}

TEST(RealtimeAdvice, NothingRefusedOrNothingAskedIsNothingToSay) {
    RealtimeReport granted;
    granted.mode = RealtimeMode::warn;
    granted.scheduler_fifo = granted.memory_locked = granted.cpu_dma_latency_held = true;
    EXPECT_EQ(realtime_advice(RealtimeRequest{}, granted), "");
    EXPECT_EQ(realtime_refused_note(RealtimeRequest{}, granted), "");
    RealtimeRequest off;
    off.mode = RealtimeMode::off;
    EXPECT_EQ(realtime_advice(off, everything_refused()), "");
    // Only what was refused is named: SCHED_FIFO granted, the rest refused.
    RealtimeReport partial = everything_refused();
    partial.scheduler_fifo = true;
    const std::string advice = realtime_advice(RealtimeRequest{}, partial);
    EXPECT_EQ(advice.find("SCHED_FIFO"), std::string::npos) << advice;
    EXPECT_EQ(advice.find("cpu 1"), std::string::npos) << advice;  // no cpu was asked for
    EXPECT_NE(advice.find("mlockall"), std::string::npos) << advice;
}

// mlockall granted, but its heap prefault failed (the locked pages ran out under the limit,
// or an allocator that is not glibc's, as under ASan): the remedy is the memlock limit.
TEST(RealtimeAdvice, AFailedHeapPrefaultIsTheMemlockLimitsToo) {
    RealtimeReport report;
    report.mode = RealtimeMode::warn;
    report.scheduler_fifo = report.memory_locked = report.cpu_dma_latency_held = true;
    report.heap_prefaulted = false;
    report.refused = {"heap prefault of 8388608 bytes failed"};
    const std::string advice = realtime_advice(RealtimeRequest{}, report, service(0));
    EXPECT_NE(advice.find("mlockall and its heap prefault need LimitMEMLOCK=infinity"),
              std::string::npos)
        << advice;
    EXPECT_EQ(realtime_refused_note(RealtimeRequest{}, report), "realtime refused: heap prefault");
}

// RT group scheduling: cgroup v1 shows cpu.rt_runtime_us; cgroup v2 never does, so there the
// kernel's build config says it. A kernel without either, or nothing readable: none.
TEST(RealtimeAdvice, RtGroupSchedulingIsFoundInTheCgroupV1TreeOrTheKernelsConfig) {
    const testing::ScratchDir dir;
    std::filesystem::create_directories(dir.file("v1/cpu"));
    dir.write("v1/cpu/cpu.rt_runtime_us", "0\n");
    std::filesystem::create_directories(dir.file("v2"));
    dir.write("v2/cgroup.controllers", "cpu io memory\n");
    const std::string with = dir.write("config-with", "CONFIG_SMP=y\nCONFIG_RT_GROUP_SCHED=y\n");
    const std::string without =
        dir.write("config-without", "CONFIG_SMP=y\n# CONFIG_RT_GROUP_SCHED is not set\n");
    EXPECT_TRUE(has_rt_group_scheduling(dir.file("v1"), ""));
    EXPECT_TRUE(has_rt_group_scheduling(dir.file("v2"), with));
    EXPECT_FALSE(has_rt_group_scheduling(dir.file("v2"), without));
    EXPECT_FALSE(has_rt_group_scheduling(dir.file("v2"), dir.file("no-such-config")));
    EXPECT_FALSE(has_rt_group_scheduling(dir.file("v2"), ""));
}

}  // namespace
}  // namespace hapticd::daemon
