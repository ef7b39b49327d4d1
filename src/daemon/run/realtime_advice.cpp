#include "run/realtime_advice.hpp"

#include <sys/resource.h>
#include <sys/utsname.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace hapticd::daemon {
namespace {

std::string fifo_advice(const servo::RealtimeRequest& request, const RealtimeSurroundings& where) {
    const auto priority = static_cast<std::uint64_t>(request.priority);
    const std::string fifo = "SCHED_FIFO " + std::to_string(request.priority);
    if (where.rtprio_limit && *where.rtprio_limit < priority) {
        return fifo + " is above this process's RLIMIT_RTPRIO of " +
               std::to_string(*where.rtprio_limit) + ": " +
               (where.in_a_service
                    ? "set LimitRTPRIO=" + std::to_string(request.priority) +
                          " or more in the unit (hapticd@.service has 90), or lower [servo] "
                          "priority"
                    : "raise it (ulimit -r " + std::to_string(request.priority) +
                          ", or an rtprio line in /etc/security/limits.d/ for the user), run "
                          "with CAP_SYS_NICE, or lower [servo] priority") +
               ".";
    }
    // The limit allows it: the kernel refused. With RT group scheduling a task in a cgroup
    // whose cpu.rt_runtime_us is 0 (every service's, by default) may not run SCHED_FIFO.
    const std::string limit =
        where.rtprio_limit ? std::to_string(*where.rtprio_limit) : std::string("unlimited");
    std::string text = fifo + " was refused although RLIMIT_RTPRIO (" + limit + ") allows it: ";
    if (where.rt_group_scheduling) {
        text +=
            "this kernel has RT group scheduling (CONFIG_RT_GROUP_SCHED), which refuses "
            "SCHED_FIFO in a cgroup without a real-time budget: under cgroup v1 give the "
            "service's cgroup one (cpu.rt_runtime_us); under cgroup v2, which has no such "
            "budget, keep the cpu controller off the service's slice (no CPUWeight= or "
            "CPUQuota= on it or its parents); or use a kernel without RT "
            "group scheduling, such as Debian's own";
    } else {
        text +=
            "the kernel refused it (a container or cgroup without a real-time budget, "
            "/proc/sys/kernel/sched_rt_runtime_us, or a security policy); run on the host, "
            "with CAP_SYS_NICE";
    }
    return text + ".";
}

}  // namespace

RealtimeSurroundings RealtimeSurroundings::of_this_process() {
    RealtimeSurroundings where;
    where.in_a_service = std::getenv("INVOCATION_ID") != nullptr;
    if (rlimit rtprio{};
        ::getrlimit(RLIMIT_RTPRIO, &rtprio) == 0 && rtprio.rlim_cur != RLIM_INFINITY) {
        where.rtprio_limit = rtprio.rlim_cur;
    }
    utsname kernel{};
    where.rt_group_scheduling = has_rt_group_scheduling(
        "/sys/fs/cgroup",
        ::uname(&kernel) == 0 ? "/boot/config-" + std::string(kernel.release) : std::string());
    return where;
}

bool has_rt_group_scheduling(const std::filesystem::path& cgroup_root,
                             const std::filesystem::path& kernel_config) {
    std::error_code error;
    if (std::filesystem::exists(cgroup_root / "cpu.rt_runtime_us", error) ||
        std::filesystem::exists(cgroup_root / "cpu" / "cpu.rt_runtime_us", error)) {
        return true;
    }
    if (kernel_config.empty()) return false;
    std::ifstream config(kernel_config);
    for (std::string line; std::getline(config, line);) {
        if (line == "CONFIG_RT_GROUP_SCHED=y") return true;
    }
    return false;
}

std::string realtime_refused_note(const servo::RealtimeRequest& request,
                                  const servo::RealtimeReport& report) {
    if (report.all_granted() || request.mode == servo::RealtimeMode::off) return {};
    std::string names;
    const auto add = [&](const char* name) {
        names += (names.empty() ? "" : ", ") + std::string(name);
    };
    if (!report.scheduler_fifo) add("SCHED_FIFO");
    if (request.lock_memory && !report.memory_locked) add("mlockall");
    if (request.cpu >= 0 && !report.affinity_set) add("affinity");
    if (request.hold_cpu_dma_latency && !report.cpu_dma_latency_held) add("cpu_dma_latency");
    if (names.empty()) add("heap prefault");
    return "realtime refused: " + names;
}

std::string realtime_advice(const servo::RealtimeRequest& request,
                            const servo::RealtimeReport& report,
                            const RealtimeSurroundings& where) {
    if (report.all_granted() || request.mode == servo::RealtimeMode::off) return {};
    std::string advice;
    const auto add = [&](const std::string& sentence) {
        advice += (advice.empty() ? "" : " ") + sentence;
    };
    if (!report.scheduler_fifo) add(fifo_advice(request, where));
    // A heap prefault that failed after mlockall is the same limit: the locked pages ran out.
    if (request.lock_memory && (!report.memory_locked || !report.heap_prefaulted)) {
        add(where.in_a_service ? "mlockall and its heap prefault need LimitMEMLOCK=infinity in "
                                 "the unit (or CAP_IPC_LOCK)."
                               : "mlockall and its heap prefault need an unlimited RLIMIT_MEMLOCK "
                                 "(ulimit -l unlimited, or a memlock line in "
                                 "/etc/security/limits.d/) or CAP_IPC_LOCK.");
    }
    if (request.cpu >= 0 && !report.affinity_set) {
        add("cpu " + std::to_string(request.cpu) +
            " must be one this process may run on (taskset, the unit's CPUAffinity= or "
            "AllowedCPUs=): change [servo] cpu or allow it.");
    }
    if (request.hold_cpu_dma_latency && !report.cpu_dma_latency_held) {
        add(std::string("/dev/cpu_dma_latency must be writable by this user: ") +
            (where.in_a_service ? "the unit allows the node (DeviceAllow=/dev/cpu_dma_latency rw); "
                                  "the cpu_dma_latency line of 70-hapticd.rules gives group "
                                  "hapticd write access (udevadm trigger /dev/cpu_dma_latency "
                                  "after installing it)."
                                : "give the user's group write access (the cpu_dma_latency "
                                  "line of 70-hapticd.rules gives it to group hapticd: adduser "
                                  "USER hapticd), or run as root."));
    }
    return advice;
}

}  // namespace hapticd::daemon
