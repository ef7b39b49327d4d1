// What to do about a refused real-time request ([servo] realtime), in the words of the place
// hapticd runs in: a systemd unit (LimitRTPRIO=, LimitMEMLOCK=, DeviceAllow=) or a shell
// (ulimit, /etc/security/limits.d). docs/daemon.md, "Real time in a service".
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "hapticd/servo/realtime.hpp"

namespace hapticd::daemon {

/// Where hapticd runs, as far as the advice goes.
struct RealtimeSurroundings {
    bool in_a_service = false;  ///< started by systemd (INVOCATION_ID is set)
    /// RLIMIT_RTPRIO's soft limit; none: unlimited (or unknown)
    std::optional<std::uint64_t> rtprio_limit;
    bool rt_group_scheduling = false;  ///< the kernel has CONFIG_RT_GROUP_SCHED (cpu.rt_runtime_us)

    /// This process's.
    static RealtimeSurroundings of_this_process();
};

/// Whether the kernel has RT group scheduling: cgroup v1's cpu controller shows
/// cpu.rt_runtime_us under `cgroup_root` (/sys/fs/cgroup or its cpu/), which cgroup v2 never
/// does; then the kernel's build config (`kernel_config`, /boot/config-RELEASE) says
/// CONFIG_RT_GROUP_SCHED=y. Neither readable: false.
bool has_rt_group_scheduling(const std::filesystem::path& cgroup_root,
                             const std::filesystem::path& kernel_config);

/// One sentence per refusal of `report` (empty when all was granted), each saying how to
/// grant it. For SCHED_FIFO it also tells a refusal by the resource limit from one by the
/// kernel (RT group scheduling, or a cgroup without a real-time budget), which no limit fixes.
std::string realtime_advice(
    const servo::RealtimeRequest& request, const servo::RealtimeReport& report,
    const RealtimeSurroundings& surroundings = RealtimeSurroundings::of_this_process());

/// What was refused, in a few words for STATUS= ("realtime refused: SCHED_FIFO, mlockall");
/// empty when all was granted.
std::string realtime_refused_note(const servo::RealtimeRequest& request,
                                  const servo::RealtimeReport& report);

}  // namespace hapticd::daemon
