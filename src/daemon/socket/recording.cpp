#include "socket/recording.hpp"

#include <unistd.h>

#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "outputs/outputs_directory.hpp"

namespace hapticd::daemon {
namespace {

// 65 s of records at 1 kHz, as the --log's ring: a disk that stalls for a minute loses nothing.
constexpr std::size_t kRecordingRingRecords = std::size_t{1} << 16;

}  // namespace

Recording::Recording(std::function<void(servo::TelemetryRing*)> attach,
                     std::function<std::uint64_t()> tick, int axes, bool lockstep,
                     const OutputsDirectory* directory, std::function<std::string()> preamble,
                     const RunNotes* notes)
    : ring_(kRecordingRingRecords),
      attach_(std::move(attach)),
      tick_(std::move(tick)),
      axes_(axes),
      lockstep_(lockstep),
      directory_(directory),
      preamble_(std::move(preamble)),
      notes_(notes) {}

Recording::~Recording() { attach_(nullptr); }

RecordingResult Recording::start(const std::string& requested) {
    const std::lock_guard lock(mutex_);
    if (writer_) {
        return {.ok = false,
                .message = "already recording to " + writer_->path() + " (record stop first)",
                .path = writer_->path()};
    }
    if (directory_ == nullptr) {
        return {.ok = false, .message = kNoOutputsDirectory, .path = requested};
    }
    const OutputsDirectory::ClientFile file = directory_->client_file(requested);
    if (file.name.empty()) return {.ok = false, .message = file.refusal, .path = requested};
    const OutputsDirectory::NewFile created = directory_->create(file.name);
    const std::string& path = created.path;
    if (created.fd < 0) {
        return {
            .ok = false, .message = "cannot create " + path + ": " + created.error, .path = path};
    }
    const int fd = created.fd;
    servo::TelemetryRecord stale;
    while (ring_.try_pop(stale)) {
    }  // a tick that pushed after the last stop's wait gave up
    dropped_before_ = ring_.dropped();
    // Attached first, then the first tick the file holds: the tick after the next one to be
    // published cannot have read the ring pointer before the attach. The writer skips
    // anything earlier (a tick that was already under way).
    std::string preamble;
    try {
        if (preamble_) preamble = preamble_();
    } catch (const std::exception& e) {
        (void)::close(fd);
        (void)directory_->remove(file.name);
        return {.ok = false, .message = std::string("cannot record: ") + e.what(), .path = path};
    }
    attach_(&ring_);
    const std::uint64_t first_tick = tick_() + 2;
    try {
        writer_ = std::make_unique<TelemetryWriter>(
            ring_, fd, path, axes_,
            lockstep_ ? std::chrono::milliseconds{0} : std::chrono::milliseconds{1000}, preamble,
            notes_);
        writer_->skip_ticks_before(first_tick);
        writer_->start();
    } catch (const std::exception& e) {
        attach_(nullptr);
        writer_.reset();
        (void)directory_->remove(file.name);
        return {.ok = false, .message = std::string("cannot record: ") + e.what(), .path = path};
    }
    {
        const std::lock_guard path_lock(path_mutex_);
        active_path_ = path;
    }
    return {.ok = true,
            .message = "recording to " + path + " from tick " + std::to_string(first_tick),
            .path = path,
            .first_tick = first_tick};
}

RecordingResult Recording::stop() {
    const std::lock_guard lock(mutex_);
    if (!writer_) return {.ok = false, .message = "not recording (record start FILE first)"};
    return end(/*servo_stopped=*/false);
}

std::optional<RecordingResult> Recording::finish_at_exit() {
    const std::lock_guard lock(mutex_);
    if (!writer_) return std::nullopt;
    return end(/*servo_stopped=*/true);
}

// The servo stops pushing; once two more ticks have been published, the tick that may have
// read the ring before the detach has recorded, and the writer drains the rest and closes.
RecordingResult Recording::end(bool servo_stopped) {
    attach_(nullptr);
    if (!servo_stopped) {
        const std::uint64_t detached_at = tick_();
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
        while (tick_() < detached_at + 2 && std::chrono::steady_clock::now() < deadline) {
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }
    }
    RecordingResult result{.ok = true, .path = writer_->path()};
    try {
        writer_->finish();
    } catch (const std::exception&) {  // failure() says it
    }
    result.records = writer_->records_written();
    result.dropped = ring_.dropped() - dropped_before_;
    result.failure = writer_->failure();
    if (result.failure.empty() && result.dropped > 0) {
        result.failure = std::to_string(result.dropped) + " records lost: the disk did not keep up";
    }
    result.complete = result.failure.empty();
    result.message =
        "recording " + result.path + " closed: " + std::to_string(result.records) + " records" +
        (result.complete ? std::string(", none lost") : ", INCOMPLETE: " + result.failure);
    const std::lock_guard path_lock(path_mutex_);
    writer_.reset();
    active_path_.reset();
    closed_.push_back(result);
    return result;
}

std::optional<bool> Recording::active_whole() const {
    const std::lock_guard lock(path_mutex_);
    if (!active_path_) return std::nullopt;
    return writer_->complete();
}

std::optional<std::string> Recording::active_path() const {
    const std::lock_guard lock(path_mutex_);
    return active_path_;
}

std::vector<RecordingResult> Recording::closed() const {
    const std::lock_guard lock(path_mutex_);
    return closed_;
}

}  // namespace hapticd::daemon
