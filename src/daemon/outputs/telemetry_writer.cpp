#include "hapticd/daemon/telemetry_writer.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <span>
#include <stdexcept>
#include <string_view>

#include "hapticd/daemon/control_protocol.hpp"
#include "hapticd/servo/telemetry_csv.hpp"

namespace hapticd::daemon {
namespace {

using Clock = std::chrono::steady_clock;

// 256 KiB: well above what kFlushInterval of records fills at 1 kHz (about 10 KiB), so in
// real time it is the timer that writes; in lockstep the buffer fills first.
constexpr std::size_t kBufferBytes = std::size_t{1} << 18;
// An empty ring at 1 kHz fills with one record per millisecond; polling at a quarter of
// that keeps the ring nearly empty without spinning a core.
constexpr auto kIdlePoll = std::chrono::microseconds(250);
// Room for a mark's line ("# mark N: " and a hapticctl mark's text) beside each record.
constexpr std::size_t kMarkLineChars = 32 + control_socket::kMaxMarkTextBytes;

// The record lines in `text`, whole lines: those that begin with a digit (the tick). The
// preamble's and the marks' lines begin with '#', the header row with 't'.
std::uint64_t record_lines(std::string_view text) {
    std::uint64_t records = 0;
    bool line_start = true;
    for (const char c : text) {
        if (line_start && c >= '0' && c <= '9') ++records;
        line_start = c == '\n';
    }
    return records;
}

int create_log(const std::string& path) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) {
        throw std::runtime_error("--log " + path +
                                 ": cannot create the telemetry file: " + std::strerror(errno));
    }
    return fd;
}

}  // namespace

TelemetryWriter::TelemetryWriter(servo::TelemetryRing& ring, const std::string& path, int axes)
    : TelemetryWriter(ring, create_log(path), path, axes) {}

TelemetryWriter::TelemetryWriter(servo::TelemetryRing& ring, int fd, std::string path, int axes,
                                 std::chrono::milliseconds sync_interval, std::string_view preamble,
                                 const RunNotes* notes)
    : ring_(ring),
      path_(std::move(path)),
      axes_(axes),
      fd_(fd),
      sync_interval_(sync_interval),
      buffer_(kBufferBytes),
      notes_(notes) {
    const std::string header = std::string(preamble) + servo::csv_header(axes) + "\n";
    std::memcpy(buffer_.data(), header.data(), header.size());
    used_ = header.size();
    oldest_buffered_ = last_sync_ = Clock::now();
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
    if (write_errno_ == 0 && sync_interval_.count() > 0 && ::fdatasync(fd_) != 0 &&
        errno != EINVAL && errno != EROFS) {
        write_errno_ = errno;
    }
    if (::close(fd_) != 0 && write_errno_ == 0 && errno != EINTR) write_errno_ = errno;
    fd_ = -1;
    if (write_errno_ != 0) throw std::runtime_error("--log " + path_ + ": " + failure());
}

std::string TelemetryWriter::failure() const {
    if (write_errno_ == 0) return {};
    return "writing telemetry failed: " + std::string(std::strerror(write_errno_)) +
           "; the file holds the first " + std::to_string(records_written()) + " of " +
           std::to_string(records_taken()) + " records, each line whole";
}

void TelemetryWriter::run() noexcept {
    while (!producer_done_.load(std::memory_order_acquire)) {
        drain();
        const auto now = Clock::now();
        if (buffered_records_ > 0 && now - oldest_buffered_ >= kFlushInterval) {
            flush_buffer();
            if (write_errno_ == 0 && sync_interval_.count() > 0 &&
                now - last_sync_ >= sync_interval_) {
                (void)::fdatasync(fd_);  // a device that cannot sync (a pipe, /dev/null): fine
                last_sync_ = now;
            }
        }
        std::this_thread::sleep_for(kIdlePoll);
    }
    drain();
}

void TelemetryWriter::drain() noexcept {
    servo::TelemetryRecord record;
    while (ring_.try_pop(record)) {
        if (record.tick < first_tick_) continue;
        if (buffer_.size() - used_ < servo::kMaxCsvLineChars + kMarkLineChars) {
            flush_buffer();
        }
        if (buffered_records_ == 0) oldest_buffered_ = Clock::now();
        write_marks(record.mark);
        used_ += servo::format_csv_record(
            record, axes_, std::span<char>(buffer_.data() + used_, buffer_.size() - used_));
        ++buffered_records_;
        records_taken_.fetch_add(1, std::memory_order_relaxed);
    }
}

// "# mark N: TEXT" before the first record that carries N: for each mark since the last
// record's, and for the first record's own (the trial a recording starts in). A flush makes
// room when the line does not fit beside a record (the writer's thread: it may allocate).
void TelemetryWriter::write_marks(std::uint32_t mark) noexcept {
    if (notes_ == nullptr || (mark == last_mark_ && !first_record_)) return;
    const std::uint32_t first = first_record_ || mark < last_mark_ ? mark : last_mark_ + 1;
    first_record_ = false;
    last_mark_ = mark;
    for (std::uint32_t number = std::max<std::uint32_t>(first, 1); number <= mark; ++number) {
        try {
            const std::string line =
                "# mark " + std::to_string(number) + ": " + notes_->text(number) + "\n";
            if (buffer_.size() - used_ < line.size() + servo::kMaxCsvLineChars) flush_buffer();
            const std::size_t length = std::min(line.size(), buffer_.size() - used_);
            std::memcpy(buffer_.data() + used_, line.data(), length);
            used_ += length;
            buffer_[used_ - 1] = '\n';
        } catch (...) {  // out of memory for a line: the mark's number is still in its column
            return;
        }
    }
}

// Writes the buffer (whole lines) with write(2). A write that fails part way keeps the whole
// lines it got onto the disk, cuts the file back to the last of them, and stops all further
// writes.
void TelemetryWriter::flush_buffer() noexcept {
    if (used_ == 0) return;
    if (write_errno_ == 0) {
        std::size_t done = 0;
        while (done < used_) {
            const ssize_t n = ::write(fd_, buffer_.data() + done, used_ - done);
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) {
                write_errno_ = n < 0 ? errno : EIO;
                break;
            }
            done += static_cast<std::size_t>(n);
        }
        if (write_errno_ == 0) {
            file_bytes_ += used_;
            records_written_.fetch_add(buffered_records_, std::memory_order_relaxed);
        } else if (done > 0) {
            // The whole lines of what was written stay; a cut last line goes (a device such
            // as /dev/full has no length to cut, and kept nothing).
            const std::string_view written(buffer_.data(), done);
            const std::size_t last_newline = written.rfind('\n');
            const std::size_t keep = last_newline == std::string_view::npos ? 0 : last_newline + 1;
            records_written_.fetch_add(record_lines(written.substr(0, keep)),
                                       std::memory_order_relaxed);
            file_bytes_ += keep;
            (void)::ftruncate(fd_, static_cast<off_t>(file_bytes_));
        }
    }
    used_ = 0;
    buffered_records_ = 0;
}

}  // namespace hapticd::daemon
