#include "socket/excitation_session.hpp"

#include <filesystem>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "hapticd/daemon/journal.hpp"
#include "hapticd/servo/faults.hpp"
#include "hapticd/servo/servo_state.hpp"
#include "run/run_messages.hpp"

namespace hapticd::daemon {
namespace {

// How long the excitation may wait for a still handle before the session gives up: long
// enough to let go of the handle after asking, short enough that a handle held on purpose
// does not leave a daemon waiting to push on it.
constexpr double kStillWaitS = 10.0;

using Phase = env::ExcitationEnvironment::Phase;

std::string seconds(double s) {
    std::ostringstream out;
    out << std::defaultfloat << std::setprecision(6) << s;
    return out.str();
}

}  // namespace

IdentifyOutcome identify_outcome(const env::ExcitationEnvironment& e, double rate_hz, int axes,
                                 const std::string& log_path, bool log_ticks,
                                 const std::string& ended_by) {
    const double start_s = static_cast<double>(e.start_tick()) / rate_hz;
    const double played_s = static_cast<double>(e.samples_played()) / rate_hz;
    const double whole_s = static_cast<double>(e.samples()) / rate_hz;
    const std::string stopped_by = ended_by.empty() ? std::string() : ", stopped by " + ended_by;
    std::ostringstream text;
    text << std::defaultfloat;
    IdentifyOutcome outcome;
    switch (e.phase()) {
        case Phase::finished:
            outcome.priority = priority::info;
            outcome.complete = true;
            text << "the excitation ran to its end: " << whole_s << " s ";
            if (log_ticks) {
                text << "from tick " << e.start_tick() << " (t = " << start_s << " s)";
            } else {
                text << "from " << start_s << " s after the start";
            }
            text << "; the log is " << log_path;
            break;
        case Phase::left_workspace:
            outcome.priority = priority::err;
            outcome.left_workspace = true;
            text << "the handle left the workspace at ";
            if (log_ticks) {
                text << "tick " << e.start_tick() + e.samples_played()
                     << " (t = " << start_s + played_s << " s)";
            } else {
                text << start_s + played_s << " s after the start";
            }
            text << ": x = " << millimetres(e.exit_position_m(), axes) << " mm, outside +-"
                 << 1e3 * e.settings().workspace_half_width_m << " mm about "
                 << millimetres(e.center_m(), axes) << " mm; force zero from that tick on, after "
                 << played_s << " of " << whole_s
                 << " s of excitation (lower [identify] force_amplitude, raise band_low or widen "
                    "workspace)";
            break;
        case Phase::waiting_for_still:
            outcome.priority = priority::warning;
            text << "WARNING: the handle was never still (|v| < " << e.settings().still_speed_mps
                 << " m/s for " << e.settings().still_time_s << " s), so no excitation ran"
                 << stopped_by;
            break;
        case Phase::running:
        case Phase::interrupted:
            outcome.priority = priority::warning;
            text << "WARNING: the run ended " << played_s << " s into the " << whole_s
                 << " s excitation (from t = " << start_s << " s"
                 << (log_ticks ? "" : " after the start") << ")" << stopped_by << "; the log is "
                 << log_path;
            break;
    }
    outcome.text = text.str();
    return outcome;
}

std::string describe_excitation(const IdentifyPlan& plan, const env::Multisine& signal) {
    const env::ExcitationSettings& s = plan.excitation;
    std::ostringstream out;
    out << "multisine, lines per axis";
    for (int axis = 0; axis < signal.axes(); ++axis) {
        out << (axis == 0 ? " " : ", ") << signal.lines(axis).size() << " ("
            << signal.lines(axis).front().frequency_hz << ".."
            << signal.lines(axis).back().frequency_hz << " Hz, crest factor "
            << std::setprecision(3) << signal.crest_factor(axis) << std::setprecision(6) << ")";
    }
    out << "; period " << signal.period_s() << " s x " << s.periods << ", fade " << s.fade_s
        << " s in and out; each axis peaks at " << s.signal.peak_force_n << " N; workspace +-"
        << 1e3 * s.workspace_half_width_m << " mm about the start";
    if (plan.predicted_excursion_m) {
        out << "; [device.model] predicts a swing of +-" << 1e3 * *plan.predicted_excursion_m
            << " mm";
    }
    if (plan.predicted_stuck_fraction) {
        out << " and the handle held still by friction after "
            << 100.0 * *plan.predicted_stuck_fraction << " % of the periods";
    }
    return out.str();
}

ExcitationSession::ExcitationSession(const Config& config, device::DeviceInfo device,
                                     Recording& recording, IdentifyLoopPort loop,
                                     std::string start_name)
    : config_(config),
      device_(std::move(device)),
      recording_(recording),
      loop_(std::move(loop)),
      start_name_(std::move(start_name)) {}

ExcitationSession::~ExcitationSession() = default;

IdentifyStart ExcitationSession::start(const std::optional<std::string>& path) {
    const std::lock_guard lock(mutex_);
    const auto refused = [](std::string why) {
        return IdentifyStart{.ok = false, .message = std::move(why)};
    };
    if (active_) {
        return refused("an excitation is playing already (the log is " + path_ +
                       "): wait for its end, or stop it with hapticctl disarm");
    }
    const servo::StatusSnapshot now = loop_.status();
    if (now.faults != 0u) {
        return refused("a fault is latched (" + fault_names(now.faults) +
                       "): reset it first (hapticctl reset)");
    }
    if (now.state != servo::ServoState::disabled) {
        return refused("identify starts on a disarmed daemon, and this one is " +
                       std::string(servo::servo_state_name(now.state)) +
                       ": hapticd disarm first (hapticctl disarm), with nobody holding the handle");
    }
    IdentifyPlan plan;
    std::unique_ptr<env::ExcitationSource> source;
    try {
        plan = make_identify_plan(config_, device_);
        source = std::make_unique<env::ExcitationSource>(plan.excitation);
    } catch (const std::invalid_argument& e) {
        return refused(config_.source + ": [identify]: " + e.what());
    } catch (const std::exception& e) {  // ConfigError: the message names the key
        return refused(e.what());
    }
    const std::string log_path =
        path.value_or("identify-" + start_name_ + "-" + std::to_string(runs_ + 1) + ".csv");
    const RecordingResult recording = recording_.start(log_path);
    if (!recording.ok) return refused(recording.message);
    if (!loop_.play(*source)) {  // only one session plays, so only a bug gets here
        (void)recording_.stop();
        return refused("the servo loop has an open-loop source already");
    }
    source_ = std::move(source);
    active_ = true;
    resets_at_start_ = now.fault_resets_taken;
    ++runs_;
    path_ = recording.path;
    started_ = std::chrono::steady_clock::now();
    wait_s_ = kStillWaitS;
    outcome_.reset();
    gave_up_ = false;
    const double rate_hz = config_.servo.rate_hz;
    const double excitation_s = static_cast<double>(source_->excitation().samples()) / rate_hz;
    return {.ok = true,
            .message =
                "playing the excitation open loop (no coupling, no scene, the soft start "
                "its own; max_force " +
                seconds(plan.excitation.force_limit_n) + " N and max_speed " +
                seconds(config_.safety.max_speed_mps) +
                " m/s apply): " + describe_excitation(plan, source_->excitation().signal()) + "; " +
                seconds(excitation_s) + " s once the handle is still; the log is " + path_,
            .path = path_,
            .excitation_s = excitation_s,
            .wait_s = wait_s_};
}

void ExcitationSession::poll(std::ostream& log) {
    const std::lock_guard lock(mutex_);
    if (!active_) return;
    if (loop_.idle()) {
        // Why it ended, for an excitation that did not run to its end (identify_outcome()
        // names it then). A reset makes the source interrupted (done), so it is asked first.
        std::string ended_by;
        const servo::StatusSnapshot now = loop_.status();
        if (now.faults != 0u) {
            ended_by = "the fault " + fault_names(now.faults);
        } else if (now.fault_resets_taken != resets_at_start_) {
            ended_by = "a reset (hapticctl reset ends an excitation as a disarm does)";
        } else if (!source_->done()) {
            ended_by = gave_up_ ? "no still handle within " + seconds(wait_s_) + " s"
                                : std::string("a disarm");
        }
        end(log, ended_by, /*servo_ticks=*/true);
        return;
    }
    if (!gave_up_ && source_->phase() == Phase::waiting_for_still &&
        std::chrono::steady_clock::now() - started_ >= std::chrono::duration<double>(wait_s_)) {
        gave_up_ = true;
        loop_.disarm();  // the tick lets go of it; a later poll ends the session
    }
}

void ExcitationSession::finish_at_exit(std::ostream& log) {
    const std::lock_guard lock(mutex_);
    if (active_) end(log, "the end of the run", /*servo_ticks=*/false);
}

void ExcitationSession::end(std::ostream& log, const std::string& ended_by, bool servo_ticks) {
    // The loop has let go (or its thread has ended): the excitation is this thread's now.
    // The recording ends after the tick that let go, so the log ends at zero force; once the
    // servo has stopped, the run's own finish ends it (run_loop).
    std::optional<RecordingResult> log_closed;
    if (servo_ticks) log_closed = recording_.stop();
    IdentifyOutcome outcome = identify_outcome(source_->excitation(), config_.servo.rate_hz,
                                               device_.axes, path_, /*log_ticks=*/false, ended_by);
    if (log_closed && !log_closed->complete) {  // a full disk: the excitation's log is not whole
        outcome.text += "; the log is INCOMPLETE: " + log_closed->failure;
        outcome.complete = false;
        outcome.priority = priority::err;
    }
    log << outcome.priority << "hapticd: identify: " << outcome.text << "\n" << std::flush;
    outcome_ = std::move(outcome);
    active_ = false;
    ended_.push_back(progress_locked());
}

std::optional<IdentifyProgress> ExcitationSession::progress() const {
    const std::lock_guard lock(mutex_);
    if (!source_) return std::nullopt;
    return progress_locked();
}

std::vector<IdentifyProgress> ExcitationSession::ended() const {
    const std::lock_guard lock(mutex_);
    return ended_;
}

IdentifyProgress ExcitationSession::progress_locked() const {
    const double rate_hz = config_.servo.rate_hz;
    IdentifyProgress p;
    p.active = active_;
    // An excitation let go of mid-run was interrupted, though nothing told it so.
    const Phase phase = source_->phase();
    p.phase = env::to_string(!active_ && phase == Phase::running ? Phase::interrupted : phase);
    p.path = path_;
    p.played_s = static_cast<double>(source_->samples_played()) / rate_hz;
    p.excitation_s = static_cast<double>(source_->excitation().samples()) / rate_hz;
    if (outcome_) {
        p.outcome = outcome_->text;
        p.complete = outcome_->complete;
    }
    return p;
}

bool ExcitationSession::active() const {
    const std::lock_guard lock(mutex_);
    return active_;
}

}  // namespace hapticd::daemon
