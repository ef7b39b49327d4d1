// What other threads ask of the servo loop, and the status it answers with: the one place
// where they meet it (docs/architecture.md §3.7). A ServoLoop owns one inbox; the daemon's
// control socket and identify session talk to it, never to the loop.
//
// Any thread: arm(), disarm(), request_fault_reset(), request_coupling(), attach_recording(),
// mark(), offer_environment() and withdraw_environment(), play_open_loop(), and the answers
// offer_taken(), open_loop_idle() and status(). Each is lock-free and never waits for the servo
// thread: an atomic, an atomic pointer, or a seqlock (seqlock.hpp).
//
// The servo thread: take() once, at the start of each tick, returns everything asked since the
// last take as plain data (LoopRequests), which the tick then carries out at one point; as
// ros2_control prepares a controller switch off the loop and performs it at one point of
// update(). recording() and publish_status() are the servo thread's too. The tick never waits
// on another thread: a request it cannot take whole now (gains mid-store) it takes at a later
// tick.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>

#include "hapticd/servo/coupling.hpp"
#include "hapticd/servo/open_loop_source.hpp"
#include "hapticd/servo/seqlock.hpp"
#include "hapticd/servo/status.hpp"
#include "hapticd/servo/telemetry_ring.hpp"

namespace hapticd::servo {

/// What happened to the open-loop source (play_open_loop) at a take.
enum class OpenLoopChange {
    none,   ///< none plays, or one offered waits for an arm
    start,  ///< LoopRequests::open_loop starts playing this tick
    plays,  ///< the one playing goes on
    end,    ///< the one playing is let go: the loop is disarmed
};

/// Everything other threads asked for since the last take, in the order a tick carries it out.
template <typename Environment>
struct LoopRequests {
    bool fault_reset = false;  ///< clear the fault latch (request_fault_reset)
    /// Whether forces may flow this tick: arm()/disarm(); false when an open-loop source ended.
    bool armed = false;
    bool armed_now = false;  ///< armed this tick but not at the last take: restart the soft start
    OpenLoopChange open_loop_change = OpenLoopChange::none;
    OpenLoopSource* open_loop = nullptr;  ///< the source that plays (start, plays)
    /// New coupling gains (request_coupling); never while an open-loop source plays.
    std::optional<CouplingGains> gains;
    /// The environment offered (offer_environment), now the loop's; never while a source plays.
    Environment* environment = nullptr;
    TelemetryRing* recording = nullptr;  ///< attach_recording()'s ring, or null
    std::uint32_t mark = 0;              ///< the latest mark() (the telemetry's `mark`)
};

template <typename Environment>
class LoopInbox {
  public:
    explicit LoopInbox(bool arm_at_start) noexcept
        : armed_(arm_at_start), was_armed_(arm_at_start) {}

    LoopInbox(const LoopInbox&) = delete;
    LoopInbox& operator=(const LoopInbox&) = delete;

    // --- any thread -------------------------------------------------------------------
    /// Forces may flow again (after a still handle and the soft-start ramp).
    void arm() noexcept { armed_.store(true, std::memory_order_release); }
    /// Zero force, enable = false, from the next tick on.
    void disarm() noexcept {
        armed_.store(false, std::memory_order_release);
        disarms_.fetch_add(1, std::memory_order_acq_rel);  // after: see take_open_loop
    }
    /// Clears the fault latch at the start of the next tick; soft start begins again.
    void request_fault_reset() noexcept { reset_requested_.store(true, std::memory_order_release); }

    /// New coupling gains (16) from the start of the next tick, through the soft start: the
    /// force drops to zero, and ramps back once the handle is still, with the coupling
    /// restarted where the handle is. Check them first (daemon: the stability check); one
    /// thread at a time may call this.
    void request_coupling(const CouplingGains& gains) noexcept { pending_gains_.store(gains); }

    /// A second ring that every tick's record also goes to from the next tick on (a control
    /// socket's `record start`), or null to stop. A tick that read the old ring may still push
    /// to it: the caller keeps it alive for the run (src/daemon/socket/recording.hpp).
    void attach_recording(TelemetryRing* ring) noexcept {
        recording_.store(ring, std::memory_order_release);
    }

    /// Every record from the next tick on carries `number` in its `mark` column (a trial
    /// marker or a change of gains or scene: the daemon keeps their text, run_notes.hpp).
    void mark(std::uint32_t number) noexcept { mark_.store(number, std::memory_order_release); }

    /// Render `next` in place of the environment from the start of a coming tick, through the
    /// soft start (as new gains are: zero force, then the ramp once the handle is still), with
    /// `next` reset where the handle is. False when an offer is already waiting. The caller
    /// owns every environment: the one replaced is the servo's no more once offer_taken() (a
    /// daemon's `scene load`: src/daemon/socket/scene_switch.hpp).
    bool offer_environment(Environment& next) noexcept {
        Environment* none = nullptr;
        return offered_environment_.compare_exchange_strong(none, &next, std::memory_order_acq_rel);
    }
    /// The offer is no longer waiting. Every tick after the one that took it renders it; the
    /// environment it replaced is not touched again.
    bool offer_taken() const noexcept {
        return offered_environment_.load(std::memory_order_acquire) == nullptr;
    }
    /// Takes back `next` if no tick has taken it (true), else false: it was taken.
    bool withdraw_environment(Environment& next) noexcept {
        Environment* offered = &next;
        return offered_environment_.compare_exchange_strong(offered, nullptr,
                                                            std::memory_order_acq_rel);
    }

    /// Play `source` on the handle open loop, in place of the coupling and the environment,
    /// from the first tick that finds the loop armed: this call arms it. The source brings its
    /// own still wait and fade-in, so there is no soft start, and it is active by design, so
    /// the passivity controller leaves it alone (the observer counts from zero); the velocity
    /// limit, the saturation and every fault apply. While it plays, offers and new gains wait.
    /// It ends at the start of the tick after source.done(), at a disarm() or at a fault: the
    /// loop lets go of it disarmed, with the coupling and the environment to restart where the
    /// handle is (through the soft start once armed again). A disarm() before a tick took it
    /// withdraws it unplayed. False when a source is already offered or playing. One caller at
    /// a time (the daemon's ExcitationSession); the caller owns `source` and keeps it until
    /// open_loop_idle().
    bool play_open_loop(OpenLoopSource& source) noexcept {
        // The disarms so far go with the offer (take_open_loop), so they are stored first;
        // an offer refused puts back the count of the one that stays.
        const std::uint64_t kept = disarms_at_offer_.exchange(
            disarms_.load(std::memory_order_acquire), std::memory_order_acq_rel);
        OpenLoopSource* none = nullptr;
        if (!open_loop_.compare_exchange_strong(none, &source, std::memory_order_acq_rel)) {
            disarms_at_offer_.store(kept, std::memory_order_release);
            return false;
        }
        arm();  // after the offer: a tick that sees it armed sees the source
        return true;
    }
    /// No source is offered or playing; the last one is the caller's again.
    bool open_loop_idle() const noexcept {
        return open_loop_.load(std::memory_order_acquire) == nullptr;
    }

    /// The latest tick's state.
    StatusSnapshot status() const noexcept { return status_.load(); }

    // --- servo thread -----------------------------------------------------------------
    /// Everything asked since the last take. `faulted`: a fault is latched (a fault reset
    /// taken in this call clears it), which ends an open-loop source.
    LoopRequests<Environment> take(bool faulted) noexcept {
        LoopRequests<Environment> requests;
        requests.recording = recording();
        requests.mark = mark_.load(std::memory_order_acquire);
        requests.fault_reset = reset_requested_.exchange(false, std::memory_order_acq_rel);
        if (requests.fault_reset) faulted = false;
        requests.armed = armed_.load(std::memory_order_acquire);
        take_open_loop(requests, faulted);
        if (requests.open_loop != nullptr) {  // offers and gains wait: a reset would end its run
            was_armed_ = true;
            return requests;
        }
        // New gains: taken only when the writer is not mid-store (Seqlock::try_load), else at
        // a later tick; the tick never waits for the control socket's thread.
        CouplingGains gains;
        std::uint64_t version = 0;
        if (pending_gains_.version() != gains_version_ && pending_gains_.try_load(gains, version) &&
            version != gains_version_) {
            gains_version_ = version;
            requests.gains = gains;
        }
        // The exchange releases the environment replaced to its owner (offer_taken()).
        if (offered_environment_.load(std::memory_order_relaxed) != nullptr) {
            requests.environment =
                offered_environment_.exchange(nullptr, std::memory_order_acq_rel);
        }
        requests.armed_now = requests.armed && !was_armed_;
        was_armed_ = requests.armed;
        return requests;
    }

    /// The ring attach_recording() gave, or null.
    TelemetryRing* recording() const noexcept { return recording_.load(std::memory_order_acquire); }

    /// The servo thread's latest state, for status().
    void publish_status(const StatusSnapshot& snapshot) noexcept { status_.store(snapshot); }

    /// Why the environment failed, as the tick that latched the fault `environment` read it
    /// from the environment (a plugin's world: env/plugin_environment.hpp), cut to fit; ""
    /// before, and again once a fault reset is taken. The servo thread publishes it only when
    /// it changes; any thread reads it.
    using FailureText = std::array<char, 192>;
    void publish_environment_failure(std::string_view why) noexcept {
        FailureText text{};
        const std::size_t n = std::min(why.size(), text.size() - 1);
        if (n > 0) std::memcpy(text.data(), why.data(), n);
        environment_failure_.store(text);
    }
    std::string environment_failure() const {
        const FailureText text = environment_failure_.load();
        return std::string(text.data());
    }

  private:
    // The open-loop source: taken by a take that finds the loop armed (the acquire of armed_
    // sees the offer made before the arm); let go at the take after it is done, at a disarm
    // or with a fault latched: disarmed. A disarm() after the offer and before any take took
    // it withdraws the offer, so that no later arm() plays it: disarm() counts itself after
    // clearing armed_, and an offer made before that count moved is let go untaken. An offer
    // whose arm() is not yet seen (and no disarm came) waits for it.
    void take_open_loop(LoopRequests<Environment>& requests, bool faulted) noexcept {
        if (playing_ == nullptr) {
            OpenLoopSource* const offered = open_loop_.load(std::memory_order_acquire);
            if (offered == nullptr) return;
            if (disarms_.load(std::memory_order_acquire) !=
                disarms_at_offer_.load(std::memory_order_acquire)) {
                open_loop_.store(nullptr, std::memory_order_release);  // withdrawn, unplayed
                requests.armed = armed_.load(std::memory_order_acquire);
                return;
            }
            if (!requests.armed) return;
            playing_ = offered;
            requests.open_loop_change = OpenLoopChange::start;
        } else {
            requests.open_loop_change = OpenLoopChange::plays;
        }
        if (requests.armed && !faulted && !playing_->done()) {
            requests.open_loop = playing_;
            return;
        }
        playing_ = nullptr;
        requests.open_loop_change = OpenLoopChange::end;
        requests.armed = false;
        armed_.store(false, std::memory_order_release);
        open_loop_.store(nullptr, std::memory_order_release);  // the caller's again
    }

    std::atomic<bool> armed_;
    std::atomic<std::uint64_t> disarms_{0};                   ///< disarm() calls
    std::atomic<bool> reset_requested_{false};                ///< request_fault_reset()'s
    Seqlock<CouplingGains> pending_gains_;                    ///< request_coupling()'s
    std::atomic<TelemetryRing*> recording_{nullptr};          ///< attach_recording()'s
    std::atomic<std::uint32_t> mark_{0};                      ///< mark()'s
    std::atomic<Environment*> offered_environment_{nullptr};  ///< offer_environment()'s
    std::atomic<OpenLoopSource*> open_loop_{nullptr};         ///< play_open_loop()'s, until let go
    std::atomic<std::uint64_t> disarms_at_offer_{0};          ///< disarms_ before the offer
    Seqlock<StatusSnapshot> status_;                          ///< publish_status()'s
    Seqlock<FailureText> environment_failure_;                ///< publish_environment_failure()'s
    // The servo thread's own.
    bool was_armed_;                     ///< armed at the last take
    std::uint64_t gains_version_ = 0;    ///< pending_gains_.version() last taken
    OpenLoopSource* playing_ = nullptr;  ///< the source playing
};

}  // namespace hapticd::servo
