// Real-time setup of the servo thread ([servo] realtime = "enforce" | "warn" | "off"):
//   - SCHED_FIFO at `priority`, for the calling thread only;
//   - mlockall(MCL_CURRENT | MCL_FUTURE), with malloc told never to return memory to the
//     kernel, then `prefault_stack_bytes` of this thread's stack and `prefault_heap_bytes`
//     of heap touched, so that the tick takes no page faults;
//   - CPU affinity of the calling thread to `cpu` (when >= 0);
//   - /dev/cpu_dma_latency held open with 0 written (no deep C-states while it is open).
// Call it on the servo thread, before the loop. keep_other_threads_off() is its counterpart for
// the rest of the process: called on the main thread before the others start, it keeps them off
// the servo's CPU. In `enforce` mode anything refused is an
// error (std::runtime_error naming each refusal and errno); in `warn` mode the report lists
// it and the caller carries on; `off` does nothing. Everything here runs outside the tick.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace hapticd::servo {

enum class RealtimeMode { enforce, warn, off };
inline constexpr RealtimeMode kRealtimeModes[] = {RealtimeMode::enforce, RealtimeMode::warn,
                                                  RealtimeMode::off};

/// "enforce" | "warn" | "off"; throws std::invalid_argument naming the value otherwise.
RealtimeMode parse_realtime_mode(std::string_view text);
std::string_view to_string(RealtimeMode mode) noexcept;

/// Linux's SCHED_FIFO priorities ([servo] priority), and the highest CPU a cpu_set_t holds.
inline constexpr int kMinPriority = 1;
inline constexpr int kMaxPriority = 99;
inline constexpr int kMaxCpu = 1023;

struct RealtimeRequest {
    RealtimeMode mode = RealtimeMode::warn;
    int priority = 80;  ///< SCHED_FIFO priority, kMinPriority..kMaxPriority
    int cpu = -1;       ///< pin the servo thread to this CPU; -1: leave the affinity alone
    bool lock_memory = true;
    std::size_t prefault_stack_bytes = std::size_t{256} * 1024;
    std::size_t prefault_heap_bytes = std::size_t{8} * 1024 * 1024;
    bool hold_cpu_dma_latency = true;

    /// Ceres-style: false, with the field, its value and the allowed range in `error`, for
    /// a priority outside SCHED_FIFO's or a CPU this machine does not have. Before the
    /// servo thread exists (ServoConfig::is_valid); apply() checks it again.
    bool is_valid(std::string* error) const;
};

/// What was asked for and what was granted.
struct RealtimeReport {
    RealtimeMode mode = RealtimeMode::off;
    bool scheduler_fifo = false;
    int priority = 0;
    bool memory_locked = false;
    bool heap_prefaulted = false;  ///< prefault_heap_bytes touched and kept (lock_memory)
    bool affinity_set = false;
    int cpu = -1;
    bool cpu_dma_latency_held = false;
    std::vector<std::string> refused;  ///< one line per refusal, with the reason

    bool all_granted() const noexcept { return refused.empty(); }
    /// One line for the log, e.g. "realtime warn: SCHED_FIFO 80, mlockall, cpu 2, ...".
    std::string brief() const;
};

/// The CPUs left to hapticd's threads other than the servo's, by keep_other_threads_off().
struct OtherThreadsCpus {
    bool off_servo_cpu = false;  ///< every thread now leaves the servo's CPU (narrowed, or was)
    std::string cpus;            ///< the calling thread's CPUs afterwards, as a list: "0,2-3"
    std::string why_not;         ///< when servo_cpu >= 0 and off_servo_cpu is false: why
};

/// Narrows the CPU set of the calling thread and then of every other thread of the process
/// to the calling thread's less `servo_cpu`, so that they and every thread started afterwards
/// (they inherit the set: the watcher, the control socket's threads, the log writer) leave
/// that core to the servo thread, which pins itself there (RealtimeSession::apply). Nothing
/// changes when servo_cpu < 0; when servo_cpu is not in the calling thread's set (isolcpus=,
/// the unit's CPUAffinity=), nothing needs to, and off_servo_cpu is true; when it is the only
/// CPU in it, nothing can (why_not says so). Outside the tick: call it before the servo thread
/// starts. A later change of the cgroup's cpuset (systemctl set-property AllowedCPUs=) lets
/// the kernel widen the sets again.
OtherThreadsCpus keep_other_threads_off(int servo_cpu);

/// Holds what must stay held for the real-time setup to last (the cpu_dma_latency file).
/// Destroy it after the loop has stopped.
class RealtimeSession {
  public:
    RealtimeSession() = default;
    ~RealtimeSession();
    RealtimeSession(const RealtimeSession&) = delete;
    RealtimeSession& operator=(const RealtimeSession&) = delete;
    RealtimeSession(RealtimeSession&& other) noexcept;
    RealtimeSession& operator=(RealtimeSession&& other) noexcept;

    /// Applies `request` to the calling thread (and the process, for mlockall). Throws
    /// std::invalid_argument on a bad request, std::runtime_error in enforce mode when
    /// anything was refused.
    RealtimeReport apply(const RealtimeRequest& request);

    const RealtimeReport& report() const noexcept { return report_; }

  private:
    int cpu_dma_latency_fd_ = -1;
    RealtimeReport report_{};
};

}  // namespace hapticd::servo
