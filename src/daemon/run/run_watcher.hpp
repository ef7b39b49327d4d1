// The watching thread of a run (docs/architecture.md §6.1): every 10 ms until the servo
// thread ends, from the loop's published status (a seqlock, never waiting for the servo,
// §6.2), it tells systemd READY=1 after the first good tick, STATUS= and WATCHDOG=1 only while
// the ticks advance (service_notifier.hpp), reports what real time refused, gives the control
// socket and the flight recorder their turn, measures the rate, logs fault changes (§7.1), ends
// a real-time --duration, and prints the figures line and the status line; at the end,
// STOPPING=1.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <optional>
#include <string>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/run.hpp"
#include "hapticd/device/device.hpp"
#include "hapticd/servo/realtime.hpp"
#include "hapticd/servo/status.hpp"
#include "outputs/summary_json.hpp"
#include "run/service_notifier.hpp"
#include "run/servo_thread.hpp"

namespace hapticd::daemon {

/// What the watcher reads of the servo loop and its thread, lock-free.
struct WatchedLoop {
    std::function<servo::StatusSnapshot()> status;  ///< LoopInbox::status (the seqlock)
    /// ServoLoop::realtime_report: read once the status says it has ticked.
    std::function<const servo::RealtimeReport&()> realtime_report;
    std::function<bool()> done;  ///< the servo thread has ended (ServoThread::done)
};

/// `loop` and its thread `servo` as the watcher reads them.
template <typename Loop>
WatchedLoop watched_loop(const Loop& loop, const ServoThread<Loop>& servo) {
    return WatchedLoop{.status = [&loop] { return loop.inbox().status(); },
                       .realtime_report = [&loop]() -> const servo::RealtimeReport& {
                           return loop.realtime_report();
                       },
                       .done = [&servo] { return servo.done(); }};
}

class RunWatcher {
  public:
    using Clock = std::chrono::steady_clock;

    /// Starts the run's clock now: made once the servo thread has started. `stop` is set at
    /// the end of a real-time --duration; `measured_rate_hz` is kept for the control socket.
    RunWatcher(WatchedLoop loop, const RunOptions& options, const Config& config,
               const servo::RealtimeRequest& realtime, const device::DeviceInfo& info,
               std::atomic<bool>& stop, std::atomic<double>& measured_rate_hz, std::ostream& log);

    /// Looks every 10 ms until the servo thread has ended; `each_look` runs at each, after
    /// systemd's turn and before the lines.
    void watch(const std::function<void()>& each_look);

    /// The watcher ended a real-time --duration.
    bool duration_ended() const noexcept { return duration_ended_; }
    /// The loop ticked, and what real time granted was reported then.
    bool realtime_reported() const noexcept { return realtime_note_.has_value(); }
    /// Servo time in seconds: from the first tick (from the thread's start if none came).
    double seconds_since_start() const;
    /// STOPPING=1, with the run's exit and what stopped it.
    void stopping(const RunContext& context);

  private:
    void tell_service(Clock::time_point now);
    void measure_rate(Clock::time_point now);
    void start_clock(Clock::time_point now);
    void log_fault_change();
    void end_duration(Clock::time_point now);
    void log_figures(Clock::time_point now);
    void log_status(Clock::time_point now);

    WatchedLoop loop_;
    const RunOptions& options_;
    const Config& config_;
    const servo::RealtimeRequest& realtime_;
    const device::DeviceInfo& info_;
    std::atomic<bool>& stop_;
    std::atomic<double>& measured_rate_hz_;
    std::ostream& log_;

    // --duration counts servo time: from the first tick, not from before the real-time set-up
    // (locking and prefaulting memory can take a tenth of a second).
    Clock::time_point started_;
    bool ticking_ = false;
    std::chrono::duration<double> status_every_;
    Clock::time_point next_status_;
    bool duration_ended_ = false;
    std::uint32_t logged_faults_ = 0;
    // systemd (service_notifier.hpp): READY=1 after the first good tick, STATUS= once a
    // second and on a change of faults, WATCHDOG=1 while the tick counter advances.
    ServiceNotifier notifier_;
    Clock::time_point next_service_status_;
    // The faults the last STATUS= told: its own record, not the journal's (logged_faults_),
    // since the control socket (each look) can clear a fault between the two looks at status.
    std::uint32_t told_faults_ = 0;
    // What real time refused, reported once the servo thread has asked (before its first
    // tick, whose status this thread then sees): a warning with the remedy, and in STATUS=.
    std::optional<std::string> realtime_note_;
    // The run's figures once a minute, for the journal (the status line is per second).
    Clock::duration figures_every_;
    Clock::time_point next_figures_;
    Clock::time_point figures_since_;  ///< when figures_before_ was taken
    servo::StatusSnapshot figures_before_;
    // The rate the control socket reports: ticks over the last second, from the first tick.
    Clock::time_point rate_since_;
    std::uint64_t rate_ticks_before_ = 0;
    bool rate_measured_ = false;  ///< a whole second has been measured (0 Hz is a stall then)
};

}  // namespace hapticd::daemon
