// [servo] cpu: the servo thread alone on its CPU. hapticd's other threads (the signal
// watcher, started before the config is read; the control socket's two; the watching
// thread) run on the process's other CPUs, as the running process shows them in /proc
// (docs/daemon.md, [servo] cpu; docs/architecture.md §6.4).
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "control_daemon.hpp"
#include "scratch_dir.hpp"
#include "text_file.hpp"

namespace hapticd::testing {
namespace {

using CpuSet = std::set<int>;

// The kernel's list format, "0-2,5".
CpuSet parse_cpu_list(const std::string& list) {
    CpuSet cpus;
    std::istringstream in(list);
    for (std::string item; std::getline(in, item, ',');) {
        const std::size_t dash = item.find('-');
        const int first = std::stoi(item.substr(0, dash));
        const int last = dash == std::string::npos ? first : std::stoi(item.substr(dash + 1));
        for (int cpu = first; cpu <= last; ++cpu) cpus.insert(cpu);
    }
    return cpus;
}

// The CPUs thread `task` (a /proc/PID/task/TID directory) may run on.
CpuSet allowed_cpus(const std::filesystem::path& task) {
    std::ifstream status(task / "status");
    const std::string key = "Cpus_allowed_list:";
    for (std::string line; std::getline(status, line);) {
        if (line.starts_with(key)) return parse_cpu_list(line.substr(key.size()));
    }
    return {};
}

CpuSet own_cpus() {
    cpu_set_t set;
    CPU_ZERO(&set);
    pthread_getaffinity_np(pthread_self(), sizeof(set), &set);
    CpuSet cpus;
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
        if (CPU_ISSET(static_cast<std::size_t>(cpu), &set)) cpus.insert(cpu);
    }
    return cpus;
}

TEST(HilServoCpu, OnlyTheServoThreadMayRunOnItsCpuAndTheSummarySaysWhereTheOthersRun) {
    CpuSet others = own_cpus();
    if (others.size() < 2) GTEST_SKIP() << "needs two CPUs";
    const int servo_cpu = *others.rbegin();
    others.erase(servo_cpu);

    const ScratchDir dir;
    Daemon daemon(dir, "pinned",
                  ConfigText{config_with_room("", "cpu = " + std::to_string(servo_cpu) + "\n")});
    ASSERT_TRUE(daemon.process.wait_for_socket(daemon.socket)) << daemon.process.messages();
    // The servo thread has pinned itself once it ticks.
    const nlohmann::json status = status_when(
        daemon.socket, [](const nlohmann::json& s) { return s["tick"].get<double>() > 100; });
    ASSERT_GT(status["tick"].get<double>(), 100) << status.dump(2);

    int tasks = 0;
    int on_servo_cpu = 0;
    const std::filesystem::path proc = "/proc/" + std::to_string(daemon.process.pid()) + "/task";
    for (const auto& task : std::filesystem::directory_iterator(proc)) {
        ++tasks;
        const CpuSet cpus = allowed_cpus(task.path());
        SCOPED_TRACE("thread " + task.path().filename().string());
        if (cpus == CpuSet{servo_cpu}) {
            ++on_servo_cpu;
            // The servo thread: real time as root (unprivileged, warn mode runs without).
            const int policy = sched_getscheduler(std::atoi(task.path().filename().c_str()));
            if (::geteuid() == 0) {
                EXPECT_EQ(policy, SCHED_FIFO);
            }
        } else {
            EXPECT_EQ(cpus, others);
        }
    }
    // Main, signal watcher, servo, control server and its worker at least.
    EXPECT_GE(tasks, 5);
    EXPECT_EQ(on_servo_cpu, 1);

    ASSERT_EQ(daemon.process.stop(), 0) << daemon.process.messages();
    const nlohmann::json summary = nlohmann::json::parse(read_file(daemon.summary));
    EXPECT_EQ(parse_cpu_list(summary["realtime"]["other_threads_cpus"].get<std::string>()), others);
    EXPECT_EQ(summary["realtime"]["cpu"], servo_cpu);
    EXPECT_EQ(summary["realtime"]["other_threads_not_off"], "");
    EXPECT_NE(daemon.process.messages().find("other threads on cpus"), std::string::npos)
        << daemon.process.messages();
}

// Without a cpu, or with real time off (the servo then pins itself nowhere), every thread
// keeps the process's CPUs.
TEST(HilServoCpu, WithoutACpuOrWithRealTimeOffNothingIsNarrowed) {
    const CpuSet all = own_cpus();
    std::string real_time_off =
        config_with_room("", "cpu = " + std::to_string(*all.rbegin()) + "\n");
    const std::string warn = "realtime = \"warn\"";
    ASSERT_NE(real_time_off.find(warn), std::string::npos);
    real_time_off.replace(real_time_off.find(warn), warn.size(), "realtime = \"off\"");
    for (const std::string& config : {config_with_room(""), real_time_off}) {
        SCOPED_TRACE(config.substr(0, config.find("[device]")));
        const ScratchDir dir;
        Daemon daemon(dir, "unpinned", ConfigText{config});
        ASSERT_TRUE(daemon.process.wait_for_socket(daemon.socket)) << daemon.process.messages();
        status_when(daemon.socket,
                    [](const nlohmann::json& s) { return s["tick"].get<double>() > 100; });
        for (const auto& task : std::filesystem::directory_iterator(
                 "/proc/" + std::to_string(daemon.process.pid()) + "/task")) {
            EXPECT_EQ(allowed_cpus(task.path()), all) << task.path();
        }
        ASSERT_EQ(daemon.process.stop(), 0) << daemon.process.messages();
        const nlohmann::json summary = nlohmann::json::parse(read_file(daemon.summary));
        EXPECT_EQ(summary["realtime"]["other_threads_cpus"], "");
        EXPECT_EQ(summary["realtime"]["other_threads_not_off"], "");
    }
}

}  // namespace
}  // namespace hapticd::testing
