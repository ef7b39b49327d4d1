#include "hapticd/daemon/telemetry_writer.hpp"

#include <cerrno>
#include <chrono>
#include <cstring>
#include <span>
#include <stdexcept>

#include "hapticd/servo/telemetry_csv.hpp"

namespace hapticd::daemon {
namespace {

constexpr std::size_t kBufferBytes = std::size_t{1} << 20;
// An empty ring at 1 kHz fills with one record per millisecond; polling at a quarter of
// that keeps the ring nearly empty without spinning a core.
constexpr auto kIdlePoll = std::chrono::microseconds(250);

}  // namespace

TelemetryWriter::TelemetryWriter(servo::TelemetryRing& ring, const std::string& path, int axes)
    : ring_(ring), path_(path), axes_(axes), buffer_(kBufferBytes) {
    file_ = std::fopen(path.c_str(), "w");
    if (file_ == nullptr) {
        throw std::runtime_error("--log " + path +
                                 ": cannot create the telemetry file: " + std::strerror(errno));
    }
    const std::string header = servo::csv_header(axes) + "\n";
    std::memcpy(buffer_.data(), header.data(), header.size());
    used_ = header.size();
}

TelemetryWriter::~TelemetryWriter() {
    try {
        finish();
    } catch (...) {  // NOLINT(bugprone-empty-catch): the error was reported by finish() users
    }
}

void TelemetryWriter::start() {
    thread_ = std::thread([this] { run(); });
}

void TelemetryWriter::finish() {
    if (finished_) return;
    finished_ = true;
    producer_done_.store(true, std::memory_order_release);
    if (thread_.joinable()) thread_.join();
    drain();  // in case start() was never called
    flush_buffer();
    if (std::fclose(file_) != 0 && write_errno_ == 0) write_errno_ = errno;
    file_ = nullptr;
    if (write_errno_ != 0) {
        throw std::runtime_error("--log " + path_ +
                                 ": writing telemetry failed: " + std::strerror(write_errno_));
    }
}

void TelemetryWriter::run() noexcept {
    while (!producer_done_.load(std::memory_order_acquire)) {
        drain();
        std::this_thread::sleep_for(kIdlePoll);
    }
    drain();
}

void TelemetryWriter::drain() noexcept {
    servo::TelemetryRecord record;
    while (ring_.try_pop(record)) {
        if (buffer_.size() - used_ < servo::kMaxCsvLineChars) flush_buffer();
        used_ += servo::format_csv_record(
            record, axes_, std::span<char>(buffer_.data() + used_, buffer_.size() - used_));
        records_written_.fetch_add(1, std::memory_order_relaxed);
    }
}

void TelemetryWriter::flush_buffer() noexcept {
    if (used_ == 0) return;
    if (std::fwrite(buffer_.data(), 1, used_, file_) != used_ && write_errno_ == 0) {
        write_errno_ = errno != 0 ? errno : EIO;
    }
    used_ = 0;
}

}  // namespace hapticd::daemon
