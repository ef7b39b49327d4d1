// The control socket's `identify` (docs/control.md, "identify"): the excitation run of
// `hapticd --identify` (docs/identification-excitation.md) played on a running daemon that
// is disarmed, of either causality, without stopping it.
//
// start() (the control server's worker) builds the excitation from the config's [identify]
// exactly as `hapticd --identify` does (make_identify_plan), starts a recording to its log
// (recording.hpp: the --log format, lossless), and hands the excitation to the servo loop
// (ServoLoop::play_open_loop), which plays it open loop in place of the coupling and the
// scene: no soft start (the excitation has its own still wait and fade), the passivity
// observer only observing, [safety] max_force and max_speed and every fault applying. The
// loop lets go of it when it is done, at a disarm or at a fault, and is then disarmed.
// poll() (the supervising thread) sees the loop let go, ends the recording and says how the
// excitation ended; it also ends an excitation whose handle was never still. Nothing here
// runs on the servo thread.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/servo_settings.hpp"
#include "hapticd/device/device.hpp"
#include "hapticd/env/excitation_source.hpp"
#include "hapticd/servo/open_loop_source.hpp"
#include "hapticd/servo/status.hpp"
#include "socket/recording.hpp"

namespace hapticd::daemon {

/// The servo loop as the session drives it (ServoLoop's lock-free calls).
struct IdentifyLoopPort {
    std::function<bool(servo::OpenLoopSource&)> play;  ///< play_open_loop
    std::function<bool()> idle;                        ///< open_loop_idle
    std::function<void()> disarm;                      ///< ends a source early
    std::function<servo::StatusSnapshot()> status;
};

/// What a start came to.
struct IdentifyStart {
    bool ok = false;
    std::string message{};      ///< why not, or what was started (for the journal)
    std::string path{};         ///< the log
    double excitation_s = 0.0;  ///< the fades and the periods
    double wait_s = 0.0;        ///< the longest the excitation waits for a still handle
};

/// How an excitation ended: the line that `hapticd --identify` ends with, and its priority.
struct IdentifyOutcome {
    const char* priority = nullptr;  ///< journal.hpp
    std::string text{};              ///< one line, without "hapticd: identify: "
    bool complete = false;           ///< it ran to its end
    bool left_workspace = false;
};

/// `excitation` after its run (its thread has let go of it), the ticks at `rate_hz`; the
/// log named in the lines is `log_path`. `log_ticks`: the log's ticks are the excitation's
/// (`hapticd --identify`: both count from the run's first tick), so the lines name ticks;
/// else times from the excitation's own start. `ended_by`: what stopped an excitation that
/// did not end itself ("" when nothing outside it did).
IdentifyOutcome identify_outcome(const env::ExcitationEnvironment& excitation, double rate_hz,
                                 int axes, const std::string& log_path, bool log_ticks,
                                 const std::string& ended_by = {});

/// The multisine and its schedule in one line, e.g. "multisine, lines per axis 12 (1.6..31.8
/// Hz, crest factor 1.62); period 2.51 s x 4, fade 1.26 s in and out; each axis peaks at
/// 0.5 N; workspace +-15 mm about the start".
std::string describe_excitation(const IdentifyPlan& plan, const env::Multisine& signal);

/// The session's state for `status`.
struct IdentifyProgress {
    bool active = false;  ///< the loop has the excitation (or is about to take it)
    std::string phase{};  ///< env::to_string(Phase)
    std::string path{};   ///< the log
    double played_s = 0.0;
    double excitation_s = 0.0;
    std::string outcome{};  ///< once ended: IdentifyOutcome::text
    bool complete = false;
};

class ExcitationSession {
  public:
    /// The excitation is planned from `config` for `device` at each start; its log is a new
    /// file `recording` makes in the run's outputs directory: the client's name, or
    /// identify-START-N.csv.
    ExcitationSession(const Config& config, device::DeviceInfo device, Recording& recording,
                      IdentifyLoopPort loop, std::string start_name);
    ~ExcitationSession();
    ExcitationSession(const ExcitationSession&) = delete;
    ExcitationSession& operator=(const ExcitationSession&) = delete;

    /// On a disarmed loop without a fault: records to `path` (or the default name) and
    /// hands the excitation to the loop. Refused with the reason otherwise.
    IdentifyStart start(const std::optional<std::string>& path);
    /// The supervising thread, every few milliseconds: once the loop has let go, ends the
    /// recording and writes how the excitation ended to `log`; disarms the loop when the
    /// handle was not still within IdentifyStart::wait_s.
    void poll(std::ostream& log);
    /// After the servo thread has ended: an excitation still playing ended with the run.
    void finish_at_exit(std::ostream& log);
    /// For `status`; nullopt before the first start.
    std::optional<IdentifyProgress> progress() const;
    /// An excitation is offered or playing.
    bool active() const;
    /// Every excitation that ended, in order (the summary's `identify`).
    std::vector<IdentifyProgress> ended() const;

  private:
    /// `servo_ticks`: the servo still runs, so the recording is this session's to stop.
    void end(std::ostream& log, const std::string& ended_by, bool servo_ticks);
    /// progress() of the source there is, under mutex_.
    IdentifyProgress progress_locked() const;

    const Config& config_;
    device::DeviceInfo device_;
    Recording& recording_;
    IdentifyLoopPort loop_;
    std::string start_name_;
    std::uint64_t resets_at_start_ = 0;  // the status's fault_resets_taken at the start

    mutable std::mutex mutex_;  // start(), poll() and progress() come from three threads
    std::unique_ptr<env::ExcitationSource> source_;
    bool active_ = false;
    int runs_ = 0;
    std::string path_;
    std::chrono::steady_clock::time_point started_{};
    double wait_s_ = 0.0;
    bool gave_up_ = false;  ///< poll() disarmed the loop: the handle was not still in time
    std::optional<IdentifyOutcome> outcome_;
    std::vector<IdentifyProgress> ended_;
};

}  // namespace hapticd::daemon
