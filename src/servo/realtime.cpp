#include "hapticd/servo/realtime.hpp"

#include <alloca.h>
#include <fcntl.h>
#include <malloc.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <stdexcept>

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

}  // namespace

RealtimeMode parse_realtime_mode(std::string_view text) {
    if (text == "enforce") return RealtimeMode::enforce;
    if (text == "warn") return RealtimeMode::warn;
    if (text == "off") return RealtimeMode::off;
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

RealtimeReport RealtimeSession::apply(const RealtimeRequest& request) {
    RealtimeReport report;
    report.mode = request.mode;
    if (request.mode == RealtimeMode::off) {
        report_ = report;
        return report;
    }
    const int min_priority = sched_get_priority_min(SCHED_FIFO);
    const int max_priority = sched_get_priority_max(SCHED_FIFO);
    if (request.priority < min_priority || request.priority > max_priority) {
        throw std::invalid_argument(
            "realtime: priority must be in " + std::to_string(min_priority) + ".." +
            std::to_string(max_priority) + ", got " + std::to_string(request.priority));
    }
    const int cpu_count = static_cast<int>(sysconf(_SC_NPROCESSORS_CONF));
    if (request.cpu < -1 || request.cpu >= cpu_count) {
        throw std::invalid_argument("realtime: cpu must be -1 or in 0.." +
                                    std::to_string(cpu_count - 1) + ", got " +
                                    std::to_string(request.cpu));
    }

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
        if (!prefault_heap(request.prefault_heap_bytes)) {
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
