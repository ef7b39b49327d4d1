#include "run/run_watcher.hpp"

#include <ostream>
#include <thread>
#include <utility>

#include "hapticd/daemon/journal.hpp"
#include "run/run_messages.hpp"

namespace hapticd::daemon {

RunWatcher::RunWatcher(WatchedLoop loop, const RunOptions& options, const Config& config,
                       const servo::RealtimeRequest& realtime, const device::DeviceInfo& info,
                       std::atomic<bool>& stop, std::atomic<double>& measured_rate_hz,
                       std::ostream& log)
    : loop_(std::move(loop)),
      options_(options),
      config_(config),
      realtime_(realtime),
      info_(info),
      stop_(stop),
      measured_rate_hz_(measured_rate_hz),
      log_(log),
      started_(Clock::now()),
      status_every_(options.status_interval_s),
      next_status_(started_ + std::chrono::duration_cast<Clock::duration>(status_every_)),
      notifier_(),
      next_service_status_(started_),
      figures_every_(std::chrono::duration_cast<Clock::duration>(
          std::chrono::duration<double>(options.figures_interval_s))),
      next_figures_(started_ + figures_every_),
      figures_since_(started_),
      rate_since_(started_) {}

void RunWatcher::watch(const std::function<void()>& each_look) {
    while (!loop_.done()) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        const Clock::time_point now = Clock::now();
        tell_service(now);
        each_look();
        measure_rate(now);
        if (!ticking_ && loop_.status().tick >= 1) start_clock(now);
        log_fault_change();
        end_duration(now);
        log_figures(now);
        log_status(now);
    }
}

double RunWatcher::seconds_since_start() const {
    return std::chrono::duration<double>(Clock::now() - started_).count();
}

void RunWatcher::stopping(const RunContext& context) {
    notifier_.stopping("stopping: " + context.exit +
                       (context.stopped_by.empty() ? "" : " (" + context.stopped_by + ")"));
}

void RunWatcher::tell_service(Clock::time_point now) {
    const servo::StatusSnapshot status = loop_.status();
    if (status.tick < 1) return;
    if (!realtime_note_) realtime_note_ = report_realtime(realtime_, loop_.realtime_report(), log_);
    const std::string service_line = service_status(
        status, config_.servo.rate_hz,
        rate_measured_ && !info_.lockstep ? std::optional<double>(measured_rate_hz_.load())
                                          : std::nullopt,
        *realtime_note_);
    if (status.faults == 0u) notifier_.ready(service_line);
    notifier_.watch(status.tick, now);
    if (now >= next_service_status_ || status.faults != told_faults_) {
        notifier_.status(service_line);
        next_service_status_ = now + std::chrono::seconds(1);
        told_faults_ = status.faults;
    }
}

void RunWatcher::measure_rate(Clock::time_point now) {
    if (ticking_ && now - rate_since_ >= std::chrono::seconds(1)) {
        const std::uint64_t ticks = loop_.status().tick;
        measured_rate_hz_.store(static_cast<double>(ticks - rate_ticks_before_) /
                                std::chrono::duration<double>(now - rate_since_).count());
        rate_ticks_before_ = ticks;
        rate_since_ = now;
        rate_measured_ = true;
    }
}

// The first tick: the run's clock, the status line, the figures and the rate start from it.
void RunWatcher::start_clock(Clock::time_point now) {
    ticking_ = true;
    started_ = now - std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                         static_cast<double>(loop_.status().tick) / config_.servo.rate_hz));
    next_status_ = started_ + std::chrono::duration_cast<Clock::duration>(status_every_);
    next_figures_ = started_ + figures_every_;
    figures_since_ = started_;
    // The rate's first second starts here, not before the real-time set-up.
    rate_since_ = now;
    rate_ticks_before_ = loop_.status().tick;
}

void RunWatcher::log_fault_change() {
    const servo::StatusSnapshot status = loop_.status();
    if (status.faults == logged_faults_) return;
    if ((status.faults & ~logged_faults_) != 0u || status.faults == 0u) {
        log_ << ((status.faults & ~logged_faults_) != 0u ? priority::warning : priority::notice)
             << fault_change_line(logged_faults_, status, config_) << "\n"
             << std::flush;
    }
    logged_faults_ = status.faults;
}

void RunWatcher::end_duration(Clock::time_point now) {
    if (options_.duration_s && !info_.lockstep &&
        now - started_ >= std::chrono::duration<double>(*options_.duration_s)) {
        duration_ended_ = true;
        stop_.store(true, std::memory_order_release);
    }
}

void RunWatcher::log_figures(Clock::time_point now) {
    if (options_.figures_interval_s <= 0.0 || now < next_figures_) return;
    const servo::StatusSnapshot status = loop_.status();
    log_ << priority::info
         << figures_line(status, figures_before_,
                         std::chrono::duration<double>(now - figures_since_).count())
         << "\n"
         << std::flush;
    figures_before_ = status;
    figures_since_ = now;
    // A late look (a slow start, a stalled host) gives one line over the time since the last,
    // not a burst of lines, one per interval it missed, all of the same moment.
    while (next_figures_ <= now) next_figures_ += figures_every_;
}

void RunWatcher::log_status(Clock::time_point now) {
    if (options_.status_interval_s > 0.0 && now >= next_status_) {
        log_ << status_line(loop_.status(), info_.axes) << "\n" << std::flush;
        next_status_ += std::chrono::duration_cast<Clock::duration>(status_every_);
    }
}

}  // namespace hapticd::daemon
