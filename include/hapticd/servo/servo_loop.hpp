// The servo loop: one tick exactly as docs/architecture.md §3 describes it (§3.1 sense, §3.2
// couple, §3.3 command, §3.4 record), and the paced loop around it (§3.5).
//
//   sleep to the absolute deadline (LoopPacer), or block in read() when the device paces
//   read the sample; counts -> metres (counts_per_meter)
//   v_d = (x_d[n] - x_d[n-1]) / T                       backward difference, (16)
//   coupling against the environment: (17) impedance, (22) admittance (VirtualCoupling)
//   safety: the stages of SafetySupervisor::filter, in its order (safety.hpp)
//   write the force (the device holds it: ZOH); push one telemetry record (never blocks)
//   link recovery: a latch of link faults only clears once the device is back (LinkRecovery)
//
// run_tick() is that list as four steps, each an inline function: sense (the requests, the
// wake, the sample, x_d and the interval of (16)), couple ((16) with (17) or (22)), command
// (safety and the write) and record (link recovery, statistics, telemetry, status).
//
// It is a template over the device (anything with noexcept read(Sample&) and
// write(const Command&) returning IoResult, e.g. device::Device), the environment (an
// ImpedancePort or an AdmittancePort) and the clock (MonotonicClock; tests inject a virtual
// one and never sleep).
//
// An OpenLoopSource (play_open_loop) may take the place of the coupling and the environment
// for a while: its force goes straight to the handle (§3.6).
//
// Threads: tick() and run() belong to one thread (the servo thread). Other threads talk to
// the loop only through its inbox() (loop_inbox.hpp): their requests, which a tick takes at
// its start, and the status it publishes at its end.
// stats() and summary() are for the servo thread, or for any thread after run() returned.
//
// Real-time: nothing reachable from tick() allocates, locks, logs, throws or makes a system
// call other than the device's I/O and the clock (tests/servo/servo_loop_alloc_test.cpp).
//
// Zero force on every exit: run() writes a disabled zero command when it returns (stop,
// tick limit, fault) and so does the destructor. Destroy the loop before the device.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <glm/geometric.hpp>
#include <stdexcept>
#include <thread>

#include "hapticd/servo/coupling.hpp"
#include "hapticd/servo/environment_port.hpp"
#include "hapticd/servo/faults.hpp"
#include "hapticd/servo/flight_recorder.hpp"
#include "hapticd/servo/io.hpp"
#include "hapticd/servo/link_recovery.hpp"
#include "hapticd/servo/loop_inbox.hpp"
#include "hapticd/servo/open_loop_source.hpp"
#include "hapticd/servo/pacing.hpp"
#include "hapticd/servo/realtime.hpp"
#include "hapticd/servo/safety.hpp"
#include "hapticd/servo/servo_config.hpp"
#include "hapticd/servo/servo_state.hpp"
#include "hapticd/servo/status.hpp"
#include "hapticd/servo/summary.hpp"
#include "hapticd/servo/telemetry.hpp"
#include "hapticd/servo/telemetry_ring.hpp"
#include "hapticd/servo/tick_stats.hpp"

namespace hapticd::servo {

template <typename D>
concept ServoDevice = requires(D& device, Sample& sample, const Command& command) {
    { device.read(sample) }
    noexcept->std::same_as<IoResult>;
    { device.write(command) }
    noexcept->std::same_as<IoResult>;
};

template <typename E>
concept ServoEnvironment = ImpedancePort<E> || AdmittancePort<E>;

/// Why run() returned.
enum class RunExit { stopped, tick_limit, fault };

template <ServoDevice Device, ServoEnvironment Environment, PacingClock Clock = MonotonicClock>
class ServoLoop {
  public:
    /// Validates `config` (std::invalid_argument). `telemetry` may be null (no records); it
    /// must outlive the loop, and its consumer runs on another thread.
    ServoLoop(Device& device, Environment& environment, const ServoConfig& config,
              TelemetryRing* telemetry = nullptr, Clock clock = Clock{})
        : device_(device),
          environment_(&environment),
          inbox_(config.arm_at_start),
          config_(validated(config)),
          period_s_(config.period_s()),
          coupling_(config.coupling, config.solver),
          safety_(config.safety, config.axes),
          link_recovery_(config.link_recovery, config.rate_hz),
          telemetry_(telemetry),
          clock_(clock),
          pacer_(clock_, config.period_ns()),
          rigid_(!config.coupling_enabled) {
        percentiles_every_ = static_cast<std::uint64_t>(std::max(1.0, std::round(config_.rate_hz)));
        // Before the first tick, status() says what the first will start from.
        publish_status(0.0, config.arm_at_start);
    }

    ~ServoLoop() { write_zero_force(); }

    ServoLoop(const ServoLoop&) = delete;
    ServoLoop& operator=(const ServoLoop&) = delete;

    /// One tick now, without sleeping (lockstep, tests, or a caller that paces itself).
    /// Returns this tick's telemetry record.
    const TelemetryRecord& tick() noexcept {
        const std::int64_t now = clock_.now_ns();
        return run_tick(Wake{.deadline_ns = now, .wake_ns = now}, /*paced=*/false);
    }

    /// Applies the real-time request (throws in enforce mode if refused, after writing zero
    /// force), then ticks at rate_hz until `stop` is set, `max_ticks` ticks have run (0: no
    /// limit), or a fault is latched (see ServoConfig::stop_on_fault; with link recovery, a
    /// latch of link faults only ends the run when link_recovery.timeout_s runs out). Writes
    /// zero force on return. Who paces each tick: tick_paced_by_host, tick_paced_by_device.
    RunExit run(const std::atomic<bool>& stop, std::uint64_t max_ticks = 0) {
        try {
            realtime_.apply(config_.realtime);
        } catch (...) {
            write_zero_force();
            throw;
        }
        pacer_.start();
        RunExit exit = RunExit::stopped;
        DeviceIdle idle;
        for (std::uint64_t ticks_run = 0;; ++ticks_run) {
            if (stop.load(std::memory_order_acquire)) break;
            if (max_ticks != 0 && ticks_run >= max_ticks) {
                exit = RunExit::tick_limit;
                break;
            }
            if (config_.device_paces_loop) {
                tick_paced_by_device(stop, idle);
            } else {
                tick_paced_by_host();
            }
            if (fault_ends_run()) {
                exit = RunExit::fault;
                break;
            }
        }
        write_zero_force();
        return exit;
    }

    /// Any thread: what other threads ask of the loop (arm, disarm, fault reset, gains,
    /// environment, open loop, recording) and the status it answers with (loop_inbox.hpp).
    LoopInbox<Environment>& inbox() noexcept { return inbox_; }
    const LoopInbox<Environment>& inbox() const noexcept { return inbox_; }
    /// The environment the ticks render (the last offer taken); after the servo thread has
    /// stopped, or from it.
    const Environment& environment() const noexcept { return *environment_; }

    /// Every tick's record also goes to `recorder` (may be null; it must outlive the loop),
    /// which the tick that latches a new fault freezes (flight_recorder.hpp). Before run().
    void attach_flight_recorder(FlightRecorder* recorder) noexcept { recorder_ = recorder; }

    // --- servo thread, or after run() returned ----------------------------------------
    const TickStats& stats() const noexcept { return stats_; }
    std::uint32_t faults() const noexcept { return safety_.faults(); }
    /// Every fault latched since construction, even if reset since.
    std::uint32_t faults_seen() const noexcept { return faults_seen_; }
    const SafetySupervisor& safety() const noexcept { return safety_; }
    /// Progress of link-fault recovery; gave_up() after run() returned: the device did not
    /// come back within link_recovery.timeout_s.
    const LinkRecovery& link_recovery() const noexcept { return link_recovery_; }
    const VirtualCoupling& coupling() const noexcept { return coupling_; }
    const RealtimeReport& realtime_report() const noexcept { return realtime_.report(); }
    const ServoConfig& config() const noexcept { return config_; }
    const TelemetryRecord& last_record() const noexcept { return record_; }
    Summary summary() const {
        return make_summary(stats_, config_.rate_hz, faults_seen_,
                            telemetry_ != nullptr ? telemetry_->dropped() : 0,
                            safety_.passivity().energy_j(), config_.overrun);
    }

    /// A disabled zero-force command, now.
    void write_zero_force() noexcept {
        (void)device_.write(Command{});
        held_force_n_ = {};
    }

  private:
    // A gap longer than this between two samples is no interval to difference over.
    static constexpr double kMaxIntervalPeriods = 1e6;

    static const ServoConfig& validated(const ServoConfig& config) {
        config.validate();
        if (!config.coupling_enabled && !ImpedancePort<Environment>) {
            throw std::invalid_argument(
                "servo config: an admittance environment needs the virtual coupling "
                "(coupling_enabled = false is only for impedance environments)");
        }
        return config;
    }

    // The host paces the loop: sleep to the next absolute deadline (LoopPacer), then tick.
    void tick_paced_by_host() noexcept { (void)run_tick(pacer_.wait(), /*paced=*/true); }

    // The last tick had no sample (the device is gone, or timed out at once): it paced nothing.
    struct DeviceIdle {
        bool idle = false;
        std::int64_t deadline_ns = 0;  ///< one period after the start of the tick that had none
    };

    // The device paces the loop (ServoConfig::device_paces_loop, lockstep among them): read()
    // blocks until its next sample, and a tick after one that had none first sleeps to
    // `idle.deadline_ns`, so that a lost device never spins the servo thread.
    void tick_paced_by_device(const std::atomic<bool>& stop, DeviceIdle& idle) noexcept {
        wait_for_telemetry_room(stop);
        if (idle.idle) clock_.sleep_until_ns(idle.deadline_ns);  // at once if it has passed
        idle.deadline_ns = clock_.now_ns() + pacer_.period_ns();
        idle.idle = (tick().flags & kFlagNoSample) != 0u;
    }

    // A fault ends the run: link recovery gave up, or a fault it cannot recover from is
    // latched and the config stops on faults (device_lost always stops).
    bool fault_ends_run() const noexcept {
        if (link_recovery_.gave_up()) return true;
        const std::uint32_t faults = safety_.faults();
        return faults != 0u && !link_recovery_.recoverable(faults) &&
               (config_.stop_on_fault || (faults & kFaultDeviceLost) != 0u);
    }

    // Lockstep only (ServoConfig::telemetry_backpressure): between ticks, wait for the
    // telemetry writer to make room, so that every record of a virtual-time run is logged.
    // A recording's ring (attach_recording) is waited for the same way.
    void wait_for_telemetry_room(const std::atomic<bool>& stop) const noexcept {
        if (!config_.telemetry_backpressure) return;
        const auto full = [](const TelemetryRing* ring) {
            return ring != nullptr && ring->size() + 1 >= ring->capacity();
        };
        while ((full(telemetry_) || full(inbox_.recording())) &&
               !stop.load(std::memory_order_acquire)) {
            std::this_thread::yield();
        }
    }

    Vec3 to_metres(const Sample& sample) const noexcept {
        Vec3 position(0.0);
        for (int axis = 0; axis < config_.axes; ++axis) {
            // A division, not a product with 1/counts_per_meter: the metres are then the
            // double nearest counts/counts_per_meter, which the telemetry prints as a short
            // decimal (3 counts at 1e5/m: 3e-05, not 3.0000000000000004e-05).
            position[axis] =
                static_cast<double>(sample.encoder_counts[axis]) / config_.counts_per_meter;
        }
        return position;
    }

    void account_overrun(const Wake& wake, std::uint32_t& flags) noexcept {
        if (!wake.overrun) {
            consecutive_overruns_ = 0;
            return;
        }
        flags |= kFlagOverrun;
        ++stats_.overruns;
        stats_.missed_periods += static_cast<std::uint64_t>(wake.missed_periods);
        ++consecutive_overruns_;
        if ((consecutive_overruns_ > config_.overrun.max_consecutive_overruns ||
             wake.missed_periods > config_.overrun.max_missed_periods) &&
            (safety_.faults() & kFaultOverrunBudget) == 0u) {
            raise(kFaultOverrunBudget);
            // Late against the first deadline it missed, not the latest one it woke for.
            stats_.budget_overrun_late_ns =
                wake.missed_periods * pacer_.period_ns() + wake.latency_ns;
            stats_.budget_overrun_missed_periods = wake.missed_periods;
            stats_.budget_overrun_consecutive = consecutive_overruns_;
        }
    }

    // Latches `faults` and remembers them as raised in this tick.
    void raise(std::uint32_t faults) noexcept {
        safety_.raise(faults);
        raised_this_tick_ |= faults;
    }

    // Reads one sample; false when there is none this tick. Raises the faults it implies
    // (judge_read). A read that failed the link does not also count towards read_timeout,
    // which is for timeouts and dropped samples.
    bool read_sample(Sample& sample, std::uint32_t& flags) noexcept {
        const IoResult result = device_.read(sample);
        const ReadVerdict verdict = judge_read(result, sample.status);
        if (verdict.faults != 0u) raise(verdict.faults);
        const bool have_sample = verdict.have_sample;
        if (have_sample) {
            consecutive_timeouts_ = 0;
        } else {
            flags |= kFlagNoSample;
            ++stats_.read_timeouts;
            const bool link_failed =
                (raised_this_tick_ & (kFaultDeviceLost | kFaultDeviceIo)) != 0u;
            if (!link_failed && ++consecutive_timeouts_ > config_.safety.read_timeouts_allowed) {
                raise(kFaultReadTimeout);
            }
        }
        return have_sample;
    }

    // What request_fault_reset() does, at the start of a tick; also what LinkRecovery does
    // at the end of the tick that completed the settle. The next sample re-initialises the
    // coupling and the environment where the handle is; the soft start waits for a still
    // handle again.
    void clear_fault_latch() noexcept {
        if ((safety_.faults() & kFaultEnvironment) != 0u) inbox_.publish_environment_failure({});
        safety_.reset();
        link_recovery_.reset();
        initialised_ = false;
        consecutive_overruns_ = 0;
        consecutive_timeouts_ = 0;
    }

    // The time since the previous sample used, in whole periods times T: the backward
    // difference must span the time between the two samples, not the period the loop meant
    // to keep (a host stalled for 55 ms between its wake and the read would otherwise see
    // the handle move 55 periods' worth in one). The device's clock says when it latched
    // each sample, rounded to periods (the models' T; jitter within half a period is
    // ignored, as the pacer's schedule ignores it). So even when the device paces the loop:
    // its sequence numbers count the samples it produced, not the periods between them (a
    // protocol device answers a poll after a lost reply one period on but two numbers on,
    // and a hung one answers with the next number however long it hung). 0 when unknown:
    // the device's clock stood still, went backwards or is not a number although a new
    // sample came (the caller then restarts the history at this sample, with no
    // velocity-based force in this tick).
    double sample_interval_s(const Sample& sample) noexcept {
        double periods = 0.0;
        const double elapsed_s = sample.device_time_s - last_device_time_s_;
        if (elapsed_s > 0.0 && elapsed_s < kMaxIntervalPeriods * period_s_) {
            periods = std::max(1.0, std::round(elapsed_s / period_s_));
        }
        start_history(sample);
        return periods * period_s_;
    }

    // Starts the velocity history at `sample` (no interval is needed for the first one).
    void start_history(const Sample& sample) noexcept {
        last_device_time_s_ = sample.device_time_s;
    }

    // What sense() found: whether the loop is armed, the sample's fate, the handle's position
    // and the interval that its velocity spans.
    struct Sensed {
        bool armed = false;             ///< armed_, as this tick read it
        bool open_loop = false;         ///< an OpenLoopSource plays (open_loop_source_)
        bool have_sample = false;       ///< a sample came, neither dropped nor disconnected
        bool interval_unknown = false;  ///< nothing velocity-based may act this tick
        double interval_s = 0.0;        ///< what the backward difference spans, s
        Vec3 x_d{0.0};                  ///< device position, m
    };

    // What couple() found: the velocity, the tool and the coupling's force on the handle.
    struct Coupled {
        Vec3 v_d{0.0};             ///< device velocity, m/s
        Vec3 x_e{0.0};             ///< tool position (the environment's side), m
        Vec3 handle_force_n{0.0};  ///< before safety, N
    };

    // One tick, the steps of the list at the top of this file. The steps are always inlined:
    // the tick is one function, as it was when it was written as one (bench/servo).
    const TelemetryRecord& run_tick(const Wake& wake, bool paced) noexcept {
        std::uint32_t flags = 0;  // TelemetryRecord::flags
        Sample sample;            // its status is recorded even when it is not a sample
        const Sensed sensed = sense(wake, sample, flags);
        const Coupled coupled = couple(sensed, flags);
        const SafeForce safe = command(sensed, coupled, flags);
        record(wake, paced, sample, sensed, coupled, safe, flags);
        return record_;
    }

    // Sense: what the other threads asked for, how late the tick woke, and the sample: the
    // device position x_d and the interval that its backward difference (16) spans. Where
    // the position history breaks (the first sample, a gap under a link fault, an unknown
    // interval) it starts again at x_d; a step no handle makes raises encoder_jump.
    [[gnu::always_inline]] Sensed sense(const Wake& wake, Sample& sample,
                                        std::uint32_t& flags) noexcept {
        raised_this_tick_ = 0;
        Sensed sensed;
        sensed.armed = take_requests(sensed.open_loop);
        account_overrun(wake, flags);
        scheduled_periods_ += 1 + static_cast<std::uint64_t>(wake.missed_periods);
        sensed.have_sample = read_sample(sample, flags);
        // A gap in the samples under a link fault breaks the position history: a device that
        // comes back may have moved or restarted its encoder, so its first sample starts the
        // history again (no jump check against the last position before the gap).
        if (!sensed.have_sample && (safety_.faults() & kLinkFaults) != 0u) initialised_ = false;
        sensed.x_d =
            sensed.have_sample ? to_metres(sample) : coupling_.previous_device_position_m();
        sensed.interval_s = period_s_;
        if (sensed.have_sample && initialised_) measure_interval(sample, sensed, flags);
        if (sensed.have_sample) continue_history(sample, sensed);
        return sensed;
    }

    // Couple: the virtual coupling (16), F = k_c (x_d - x_e) + b_c (v_d - v_e), in series
    // with an impedance environment (17) or driving an admittance environment (22); without
    // the coupling (coupling_enabled = false) the environment acts on the handle directly, as
    // an open-loop source always does.
    // Only when armed, unfaulted and with a sample over a known interval; otherwise there is
    // no force and the tool follows the handle.
    [[gnu::always_inline]] Coupled couple(const Sensed& sensed, std::uint32_t& flags) noexcept {
        Coupled coupled{.x_e = coupling_.previous_tool_position_m()};
        if (sensed.have_sample && sensed.armed && !safety_.faulted() && !sensed.interval_unknown) {
            const CouplingStep step = coupling_step(sensed, sensed.x_d, sensed.interval_s);
            if (!step.finite) raise(kFaultNonFinite);
            if (step.finite && !step.converged) {
                flags |= kFlagSolverNotConverged;
                ++stats_.solver_not_converged;
            }
            coupled.handle_force_n = step.handle_force_n;
            coupled.v_d = step.device_velocity_mps;
            coupled.x_e = step.tool_position_m;
        } else if (sensed.have_sample) {
            coupled.v_d = coupling_.device_velocity_mps(sensed.x_d, sensed.interval_s);
            coupling_.track_device(sensed.x_d);
            coupled.x_e = sensed.x_d;
        }
        // A world that failed in this tick (its reset, or the step's calls) or before: a
        // failed world gives no force, and the fault zeroes the command (command()).
        if (!sensed.open_loop && environment_failed()) {
            if ((safety_.faults() & kFaultEnvironment) == 0u) {
                inbox_.publish_environment_failure(environment_failure());
            }
            raise(kFaultEnvironment);
        }
        return coupled;
    }

    // Command: safety (SafetySupervisor::filter, its stages in the order safety.hpp lists), then
    // the write; the device holds the force until the next one (the ZOH of (13)). A fault
    // zeroes the force in the tick that raised it. Without a sample (and without a fault)
    // nothing is written: the device holds the last force for at most read_timeouts_allowed.
    [[gnu::always_inline]] SafeForce command(const Sensed& sensed, const Coupled& coupled,
                                             std::uint32_t& flags) noexcept {
        Command force_command;
        SafeForce safe;
        bool write = true;
        if (!sensed.armed) {
            flags |= kFlagDisarmed;
        } else if (sensed.have_sample && !safety_.faulted()) {
            safe =
                safety_.filter(coupled.handle_force_n, coupled.v_d, sensed.interval_s,
                               sensed.open_loop ? ForceOrigin::open_loop : ForceOrigin::coupling);
            for (int axis = 0; axis < config_.axes; ++axis) {
                force_command.force_n[static_cast<std::size_t>(axis)] = safe.handle_force_n[axis];
            }
            force_command.enable = safe.enable;
        } else if (!safety_.faulted()) {
            write = false;
        }
        if (safety_.faulted()) force_command = Command{};  // zero force in the tick that faulted
        if (write) {
            // A write that failed tried zero force once more: that is what the tick commanded.
            held_force_n_ = write_command(force_command) ? force_command.force_n
                                                         : std::array<double, kMaxAxes>{};
        }
        if (sensed.open_loop) flags |= kFlagOpenLoop;
        flag_safety_actions(safe, force_command.enable, flags);
        faults_seen_ |= safety_.faults();
        return safe;
    }

    // Record: link recovery counts the tick, then the statistics, the telemetry record
    // (never blocks), the flight recorder (frozen by a new fault) and the status snapshot. A
    // link-fault latch that this tick's settle completes clears after its record, which still
    // carries the faults that held the force at zero.
    [[gnu::always_inline]] void record(const Wake& wake, bool paced, const Sample& sample,
                                       const Sensed& sensed, const Coupled& coupled,
                                       const SafeForce& safe, std::uint32_t flags) noexcept {
        const bool good_tick = sensed.have_sample && (raised_this_tick_ & kLinkFaults) == 0u;
        const LinkAction link_action = link_recovery_.update(
            safety_.faults(), good_tick, 1 + static_cast<std::uint64_t>(wake.missed_periods));
        if (link_action == LinkAction::recover) flags |= kFlagLinkRecovered;
        // Compute time: from the wake to the command written.
        const std::int64_t compute_ns = clock_.now_ns() - wake.wake_ns;
        count_tick(wake, paced, compute_ns);
        fill_record(wake, paced, sample, sensed, coupled, flags, compute_ns);
        if (telemetry_ != nullptr) telemetry_->try_push(record_);
        if (recording_ != nullptr) recording_->try_push(record_);
        if (recorder_ != nullptr) {
            // A fault new to the records kept freezes them; one that came while they were
            // frozen freezes them at the first tick kept after the thaw.
            if (recorder_->record(record_)) {
                if ((record_.faults & ~recorded_faults_) != 0u) recorder_->freeze();
                recorded_faults_ = record_.faults;
            }
        }
        ++stats_.ticks;
        if (link_action == LinkAction::recover) {
            clear_fault_latch();
            ++stats_.link_recoveries;
        }
        if (stats_.ticks % percentiles_every_ == 0) {  // a walk of the histograms' low buckets
            wake_latency_us_ = wake_latency_summary(stats_.wake_latency);
            tick_compute_us_ = tick_compute_summary(stats_.compute);
        }
        publish_status(safe.soft_start_scale, sensed.armed);
    }

    // ---- the steps' parts ----

    // What other threads asked for (LoopInbox::take), carried out at the start of a tick: a
    // fault reset, the open-loop source starting or let go, new gains, a new environment, and
    // arming (for the last three the soft start begins again, and the coupling and the
    // environment restart where the handle is). Returns whether the loop is armed;
    // `open_loop`: whether a source plays this tick.
    bool take_requests(bool& open_loop) noexcept {
        const LoopRequests<Environment> requests = inbox_.take(safety_.faulted());
        recording_ = requests.recording;
        mark_ = requests.mark;
        if (requests.fault_reset) {
            clear_fault_latch();
            ++fault_resets_taken_;
        }
        switch (requests.open_loop_change) {
            case OpenLoopChange::start:  // it starts where the handle is, observed from zero
                initialised_ = false;
                safety_.restart_passivity_observer();
                break;
            case OpenLoopChange::end:  // disarmed; the coupling restarts where the handle is
                initialised_ = false;
                safety_.restart_soft_start();
                safety_.restart_passivity_observer();
                break;
            case OpenLoopChange::none:
            case OpenLoopChange::plays:
                break;
        }
        open_loop_source_ = requests.open_loop;
        open_loop = open_loop_source_ != nullptr;
        if (requests.gains) coupling_.set_gains(*requests.gains);
        if (requests.environment != nullptr) environment_ = requests.environment;
        if (requests.gains || requests.environment != nullptr || requests.armed_now) {
            safety_.restart_soft_start();
            initialised_ = false;  // the coupling and the environment restart where the handle is
        }
        return requests.armed;
    }

    // The interval since the previous sample (sample_interval_s). When it is unknown,
    // nothing velocity-based may act on this tick: zero force now, and the history (and the
    // soft start) starts again here.
    void measure_interval(const Sample& sample, Sensed& sensed, std::uint32_t& flags) noexcept {
        sensed.interval_s = sample_interval_s(sample);
        sensed.interval_unknown = sensed.interval_s == 0.0;
        if (!sensed.interval_unknown) return;
        flags |= kFlagIntervalUnknown;
        ++stats_.intervals_unknown;
        initialised_ = false;
        safety_.restart_soft_start();
        sensed.interval_s = period_s_;
    }

    // A new sample either starts the history (the coupling, the environment and the velocity
    // history restart at x_d) or continues it, checked for an encoder jump.
    void continue_history(const Sample& sample, const Sensed& sensed) noexcept {
        if (!initialised_) {
            coupling_.reset(sensed.x_d);
            if (sensed.open_loop) {
                open_loop_source_->reset(sensed.x_d);
            } else {
                environment_->reset(sensed.x_d);
            }
            start_history(sample);
            initialised_ = true;
        } else if (config_.safety.encoder_jump_m > 0.0 &&
                   max_abs(sensed.x_d - coupling_.previous_device_position_m()) >
                       config_.safety.encoder_jump_m * (sensed.interval_s / period_s_)) {
            // A step per period: a sample that comes 55 periods after the last may have
            // moved 55 times as far.
            raise(kFaultEncoderJump);
        }
    }

    // Whether the environment failed (a plugin's world: env/plugin_environment.hpp); the
    // servo's own test environments have no failed() and never fail.
    bool environment_failed() const noexcept {
        if constexpr (requires(const Environment& e) {
                          { e.failed() } -> std::same_as<bool>;
                      }) {
            return environment_->failed();
        } else {
            return false;
        }
    }

    // Why it failed ("" for the servo's own test environments).
    std::string_view environment_failure() const noexcept {
        if constexpr (requires(const Environment& e) {
                          { e.failure() } -> std::same_as<std::string_view>;
                      }) {
            return environment_->failure();
        } else {
            return {};
        }
    }

    CouplingStep coupling_step(const Sensed& sensed, const Vec3& x_d, double interval_s) noexcept {
        if (sensed.open_loop) return coupling_.step_rigid(*open_loop_source_, x_d, interval_s);
        if constexpr (ImpedancePort<Environment>) {
            if (rigid_) return coupling_.step_rigid(*environment_, x_d, interval_s);
        }
        return coupling_.step(*environment_, x_d, interval_s);
    }

    // The flags and counts of what safety did to this tick's force.
    void flag_safety_actions(const SafeForce& safe, bool enabled, std::uint32_t& flags) noexcept {
        if (safe.saturated) {
            flags |= kFlagSaturated;
            ++stats_.saturated_ticks;
        }
        if (safe.overspeed) {
            flags |= kFlagOverspeed;
            ++stats_.overspeed_ticks;
        }
        if (enabled && safe.soft_start_scale < 1.0) flags |= kFlagSoftStart;
        if (safe.passivity_damping_n_s_per_m > 0.0) {
            flags |= kFlagPassivityControl;
            ++stats_.passivity_control_ticks;
        }
    }

    // The tick's statistics: compute time, wake latency, and the largest force held.
    void count_tick(const Wake& wake, bool paced, std::int64_t compute_ns) noexcept {
        stats_.compute.record(compute_ns);
        if (paced) stats_.wake_latency.record(wake.latency_ns);
        // The force the device holds from this tick on (ZOH): this tick's command, or the
        // last one when nothing was written. The telemetry's f{i}_n is this force.
        const Vec3 commanded(held_force_n_[0], held_force_n_[1], held_force_n_[2]);
        stats_.max_force_n = std::max(stats_.max_force_n, glm::length(commanded));
    }

    void fill_record(const Wake& wake, bool paced, const Sample& sample, const Sensed& sensed,
                     const Coupled& coupled, std::uint32_t flags,
                     std::int64_t compute_ns) noexcept {
        record_.tick = stats_.ticks;
        // Divisions for the same reason as in to_metres(): tick 9 at 1 kHz is 0.009 s.
        record_.t_s = config_.device_paces_loop && sensed.have_sample
                          ? sample.device_time_s
                          : static_cast<double>(scheduled_periods_ - 1) / config_.rate_hz;
        record_.unix_time_s = static_cast<double>(unix_now_us()) / 1e6;
        for (int axis = 0; axis < kMaxAxes; ++axis) {
            const auto i = static_cast<std::size_t>(axis);
            record_.x_m[i] = sensed.x_d[axis];
            record_.v_mps[i] = coupled.v_d[axis];
            record_.xe_m[i] = coupled.x_e[axis];
            record_.f_n[i] = held_force_n_[i];
        }
        record_.status = sample.status;
        record_.flags = flags;
        record_.faults = safety_.faults();
        record_.state = static_cast<std::uint32_t>(
            servo_state(sensed.armed, record_.faults, soft_start_scale_for_state()));
        record_.wake_latency_us = paced ? static_cast<double>(wake.latency_ns) / 1e3 : 0.0;
        record_.compute_us = static_cast<double>(compute_ns) / 1e3;
        record_.mark = mark_;
        record_.energy_j = safety_.passivity().energy_j();
    }

    // False when the write failed: the fault is raised and zero force tried once more.
    bool write_command(const Command& command) noexcept {
        const IoResult result = device_.write(command);
        if (result == IoResult::ok) return true;
        raise(result == IoResult::disconnected ? kFaultDeviceLost : kFaultDeviceIo);
        if (command.enable) (void)device_.write(Command{});  // one more try at zero force
        return false;
    }

    // The soft start's scale as the safety state reads it: an open-loop source has none, and
    // runs at full scale.
    double soft_start_scale_for_state() const noexcept {
        return open_loop_source_ != nullptr ? 1.0 : safety_.soft_start().scale();
    }

    void publish_status(double soft_start_scale, bool armed) noexcept {
        StatusSnapshot snapshot;
        snapshot.wake_latency_us = wake_latency_us_;
        snapshot.tick_compute_us = tick_compute_us_;
        snapshot.tick = record_.tick;
        snapshot.t_s = record_.t_s;
        snapshot.x_m = record_.x_m;
        snapshot.xe_m = record_.xe_m;
        snapshot.f_n = record_.f_n;
        snapshot.faults = record_.faults;
        snapshot.flags = record_.flags;
        snapshot.fault_resets_taken = fault_resets_taken_;
        snapshot.overruns = stats_.overruns;
        snapshot.solver_not_converged = stats_.solver_not_converged;
        snapshot.energy_j = record_.energy_j;
        snapshot.soft_start_scale = soft_start_scale;
        snapshot.armed = armed;
        snapshot.stiffness_n_per_m = coupling_.gains().stiffness_n_per_m;
        snapshot.damping_n_s_per_m = coupling_.gains().damping_n_s_per_m;
        snapshot.read_timeouts = stats_.read_timeouts;
        snapshot.link_recoveries = stats_.link_recoveries;
        if constexpr (requires(const Environment& e) {
                          { e.port_report() } -> std::same_as<EnvironmentPortReport>;
                      }) {
            snapshot.environment = environment_->port_report();
        }
        // The soft start's own scale: a tick without a sample filters nothing, and must not
        // make a running loop look as if it were arming again.
        snapshot.state = servo_state(armed, record_.faults, soft_start_scale_for_state());
        inbox_.publish_status(snapshot);
    }

    Device& device_;
    Environment* environment_;  ///< the one the ticks render
    LoopInbox<Environment> inbox_;
    OpenLoopSource* open_loop_source_ = nullptr;  ///< the one playing (servo thread)
    ServoConfig config_;
    double period_s_;
    VirtualCoupling coupling_;
    SafetySupervisor safety_;
    LinkRecovery link_recovery_;
    TelemetryRing* telemetry_;
    TelemetryRing* recording_ = nullptr;  ///< the inbox's recording ring, as this tick took it
    FlightRecorder* recorder_ = nullptr;
    std::uint32_t recorded_faults_ = 0;       ///< the faults of the last record the recorder kept
    WakeLatencySummaryUs wake_latency_us_{};  ///< for status(), once a second
    TickComputeSummaryUs tick_compute_us_{};
    std::uint64_t percentiles_every_ = 1;  ///< ticks between refreshes: one second's
    Clock clock_;
    LoopPacer<Clock> pacer_;
    bool rigid_;  ///< no virtual coupling (ServoConfig::coupling_enabled = false)
    RealtimeSession realtime_;
    TickStats stats_;
    TelemetryRecord record_;
    std::uint64_t fault_resets_taken_ = 0;  ///< servo thread only; published in the status
    std::uint32_t mark_ = 0;                ///< the latest LoopInbox::mark() taken
    bool initialised_ = false;
    int consecutive_overruns_ = 0;
    int consecutive_timeouts_ = 0;
    std::uint64_t scheduled_periods_ = 0;
    double last_device_time_s_ = 0.0;
    std::uint32_t faults_seen_ = 0;
    std::uint32_t raised_this_tick_ = 0;           ///< Fault bits raised in the current tick
    std::array<double, kMaxAxes> held_force_n_{};  ///< what the device holds (last written)
};

}  // namespace hapticd::servo
