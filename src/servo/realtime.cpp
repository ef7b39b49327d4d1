#include "hapticd/servo/realtime.hpp"

#include <alloca.h>
#include <fcntl.h>
#include <malloc.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "hapticd/input/range.hpp"

namespace hapticd::servo {

namespace {

std::string errno_text(int error) { return std::string(std::strerror(error)); }

// Touches `bytes` of this thread's stack below the caller, so that later growth takes no
// page fault.
__attribute__((noinline)) void prefault_stack(std::size_t bytes) {
    auto* stack = static_cast<volatile unsigned char*>(alloca(bytes));
    for (std::size_t i = 0; i < bytes; i += 4096) stack[i] = 0;
}

// Keeps freed memory in the process (no trim, no mmap'd chunks), then touches `bytes`
// of heap, so the pages stay mapped and locked for whatever allocates outside the tick.
bool prefault_heap(std::size_t bytes) {
    if (mallopt(M_TRIM_THRESHOLD, -1) == 0 || mallopt(M_MMAP_MAX, 0) == 0) return false;
    if (bytes == 0) return true;
    auto* block = static_cast<unsigned char*>(std::malloc(bytes));
    if (block == nullptr) return false;
    const long page = sysconf(_SC_PAGESIZE);
    const std::size_t step = page > 0 ? static_cast<std::size_t>(page) : 4096;
    for (std::size_t i = 0; i < bytes; i += step)
        static_cast<volatile unsigned char*>(block)[i] = 0;
    std::free(block);
    return true;
}

// "0,2-3": the CPUs of `set` as ranges.
std::string cpu_list(const cpu_set_t& set) {
    std::string out;
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
        if (!CPU_ISSET(static_cast<std::size_t>(cpu), &set)) continue;
        int last = cpu;
        while (last + 1 < CPU_SETSIZE && CPU_ISSET(static_cast<std::size_t>(last + 1), &set)) {
            ++last;
        }
        if (!out.empty()) out += ',';
        out += std::to_string(cpu);
        if (last > cpu) out += '-' + std::to_string(last);
        cpu = last;
    }
    return out;
}

}  // namespace

OtherThreadsCpus keep_other_threads_off(int servo_cpu) {
    OtherThreadsCpus result;
    cpu_set_t set;
    CPU_ZERO(&set);
    if (const int error = pthread_getaffinity_np(pthread_self(), sizeof(set), &set); error != 0) {
        result.why_not = "the CPU set could not be read: " + errno_text(error);
        return result;
    }
    result.cpus = cpu_list(set);
    if (servo_cpu < 0) return result;
    const auto servo = static_cast<std::size_t>(servo_cpu);
    if (servo_cpu >= CPU_SETSIZE || !CPU_ISSET(servo, &set)) {
        // Already off it (isolcpus=, the unit's CPUAffinity=): the servo thread may still pin
        // itself there, as far as the cgroup's cpuset allows (RealtimeSession::apply says).
        result.off_servo_cpu = true;
        return result;
    }
    if (CPU_COUNT(&set) == 1) {
        result.why_not = "cpu " + std::to_string(servo_cpu) +
                         " is the only one this process may use: the other threads share it";
        return result;
    }
    CPU_CLR(servo, &set);
    const std::string narrowed = cpu_list(set);
    // This thread first (the threads started after inherit its set), then every thread there
    // is now: the signal watcher, started before the config was read. One that has ended is
    // gone (ESRCH).
    if (const int error = pthread_setaffinity_np(pthread_self(), sizeof(set), &set); error != 0) {
        result.why_not = "narrowing the CPU set to " + narrowed + ": " + errno_text(error);
        return result;
    }
    result.cpus = narrowed;
    std::error_code listing;
    for (const auto& task : std::filesystem::directory_iterator("/proc/self/task", listing)) {
        const auto tid = static_cast<pid_t>(std::atoi(task.path().filename().c_str()));
        if (tid <= 0 || sched_setaffinity(tid, sizeof(set), &set) == 0) continue;
        if (const int error = errno; error != ESRCH) {
            result.why_not = "narrowing thread " + std::to_string(tid) + "'s CPU set to " +
                             narrowed + ": " + errno_text(error);
            return result;
        }
    }
    if (listing) {
        result.why_not = "/proc/self/task could not be read (" + listing.message() +
                         "): only the threads started from now on keep off it";
        return result;
    }
    result.off_servo_cpu = true;
    return result;
}

RealtimeMode parse_realtime_mode(std::string_view text) {
    for (const RealtimeMode mode : kRealtimeModes) {
        if (to_string(mode) == text) return mode;
    }
    throw std::invalid_argument("realtime: expected \"enforce\", \"warn\" or \"off\", got \"" +
                                std::string(text) + "\"");
}

std::string_view to_string(RealtimeMode mode) noexcept {
    switch (mode) {
        case RealtimeMode::enforce:
            return "enforce";
        case RealtimeMode::warn:
            return "warn";
        case RealtimeMode::off:
            return "off";
    }
    return "off";
}

std::string RealtimeReport::brief() const {
    std::ostringstream out;
    out << "realtime " << to_string(mode) << ":";
    if (mode == RealtimeMode::off) return out.str() + " not requested";
    out << (scheduler_fifo ? " SCHED_FIFO " + std::to_string(priority)
                           : std::string(" no SCHED_FIFO"));
    out << (memory_locked ? ", mlockall" : ", memory not locked");
    if (cpu >= 0) out << (affinity_set ? ", cpu " : ", not pinned to cpu ") << cpu;
    out << (cpu_dma_latency_held ? ", cpu_dma_latency 0" : ", no cpu_dma_latency");
    for (const std::string& refusal : refused) out << "; refused: " << refusal;
    return out.str();
}

RealtimeSession::~RealtimeSession() {
    if (cpu_dma_latency_fd_ >= 0) ::close(cpu_dma_latency_fd_);
}

RealtimeSession::RealtimeSession(RealtimeSession&& other) noexcept
    : cpu_dma_latency_fd_(other.cpu_dma_latency_fd_), report_(std::move(other.report_)) {
    other.cpu_dma_latency_fd_ = -1;
}

RealtimeSession& RealtimeSession::operator=(RealtimeSession&& other) noexcept {
    if (this != &other) {
        if (cpu_dma_latency_fd_ >= 0) ::close(cpu_dma_latency_fd_);
        cpu_dma_latency_fd_ = other.cpu_dma_latency_fd_;
        report_ = std::move(other.report_);
        other.cpu_dma_latency_fd_ = -1;
    }
    return *this;
}

bool RealtimeRequest::is_valid(std::string* error) const {
    if (mode == RealtimeMode::off) return true;  // nothing is asked of the system
    const int min_priority = std::max(kMinPriority, sched_get_priority_min(SCHED_FIFO));
    const int max_priority = std::min(kMaxPriority, sched_get_priority_max(SCHED_FIFO));
    if (priority < min_priority || priority > max_priority) {
        return input::invalid(
            error, input::out_of_range("realtime.priority", priority,
                                       std::to_string(min_priority) + ".." +
                                           std::to_string(max_priority) + " (SCHED_FIFO)"));
    }
    const int cpu_count = std::min(static_cast<int>(sysconf(_SC_NPROCESSORS_CONF)), kMaxCpu + 1);
    if (cpu < -1 || cpu >= cpu_count) {
        return input::invalid(
            error, input::out_of_range("realtime.cpu", cpu,
                                       "-1 (none) or 0.." + std::to_string(cpu_count - 1) +
                                           " (this machine's CPUs)"));
    }
    return true;
}

RealtimeReport RealtimeSession::apply(const RealtimeRequest& request) {
    RealtimeReport report;
    report.mode = request.mode;
    if (request.mode == RealtimeMode::off) {
        report_ = report;
        return report;
    }
    if (std::string error; !request.is_valid(&error)) throw std::invalid_argument(error);

    sched_param parameters{};
    parameters.sched_priority = request.priority;
    if (const int error = pthread_setschedparam(pthread_self(), SCHED_FIFO, &parameters);
        error == 0) {
        report.scheduler_fifo = true;
        report.priority = request.priority;
    } else {
        report.refused.push_back("SCHED_FIFO " + std::to_string(request.priority) + ": " +
                                 errno_text(error));
    }

    if (request.lock_memory) {
        if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
            report.memory_locked = true;
        } else {
            report.refused.push_back("mlockall: " + errno_text(errno));
        }
        report.heap_prefaulted = prefault_heap(request.prefault_heap_bytes);
        if (!report.heap_prefaulted) {
            report.refused.push_back("heap prefault of " +
                                     std::to_string(request.prefault_heap_bytes) + " bytes failed");
        }
        prefault_stack(request.prefault_stack_bytes);
    }

    report.cpu = request.cpu;
    if (request.cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET(static_cast<std::size_t>(request.cpu), &set);
        if (const int error = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
            error == 0) {
            report.affinity_set = true;
        } else {
            report.refused.push_back("affinity to cpu " + std::to_string(request.cpu) + ": " +
                                     errno_text(error));
        }
    }

    if (request.hold_cpu_dma_latency && cpu_dma_latency_fd_ < 0) {
        const int fd = ::open("/dev/cpu_dma_latency", O_WRONLY | O_CLOEXEC);
        const std::int32_t zero_us = 0;
        if (fd < 0) {
            report.refused.push_back("/dev/cpu_dma_latency: " + errno_text(errno));
        } else if (::write(fd, &zero_us, sizeof(zero_us)) != sizeof(zero_us)) {
            report.refused.push_back("/dev/cpu_dma_latency write: " + errno_text(errno));
            ::close(fd);
        } else {
            cpu_dma_latency_fd_ = fd;
        }
    }
    report.cpu_dma_latency_held = cpu_dma_latency_fd_ >= 0;

    report_ = report;
    if (request.mode == RealtimeMode::enforce && !report.all_granted()) {
        throw std::runtime_error(report.brief());
    }
    return report;
}

}  // namespace hapticd::servo
