// The servo loop as the control socket sees it (docs/control.md; docs/architecture.md §6.1,
// §6.2): InboxServoControl for the requests that touch the loop itself, and the ports of
// scene_load, record and identify (SocketLoopPorts, run_control.hpp). Every call goes to the
// loop's inbox (servo/loop_inbox.hpp): a seqlock read, an atomic or an atomic pointer that the
// tick takes at its start (recent_status()'s copy and the last gains sit behind mutexes of the
// socket's two threads, never the servo's). A template over the inbox, as the inbox is over its
// environment.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <optional>
#include <type_traits>

#include "hapticd/env/environment.hpp"
#include "hapticd/env/scene.hpp"
#include "hapticd/servo/environment_port.hpp"
#include "hapticd/servo/status.hpp"
#include "run/run_control.hpp"
#include "socket/requests.hpp"

namespace hapticd::daemon {

/// How old a status the control socket may serve: the servo's status crosses to the socket's
/// threads at most 1/kStatusMaxAge times a second, however many clients ask. Each crossing
/// costs the servo's next tick a cache miss on each line of the status it writes (their
/// copies on the reader's core invalidated): a client polling status as fast as it could
/// raised the tick's median compute time by half (docs/benchmarks.md, "The servo under socket
/// abuse"). A 100 Hz stream's rows are 10 ms apart, so each still gets a status of its own,
/// unless an event runs late.
inline constexpr std::chrono::milliseconds kStatusMaxAge{5};

/// The servo loop as the control socket sees it: its inbox's lock-free calls only
/// (loop_inbox.hpp).
template <typename Inbox>
class InboxServoControl final : public control_socket::ServoControl {
  public:
    InboxServoControl(Inbox& inbox, const servo::CouplingGains& gains)
        : inbox_(inbox), gains_(gains) {}
    servo::StatusSnapshot status() const noexcept override { return inbox_.status(); }
    std::string environment_failure() const override {
        if constexpr (requires { inbox_.environment_failure(); }) {
            return inbox_.environment_failure();
        } else {
            return {};  // a test's loop without environments
        }
    }
    servo::StatusSnapshot recent_status() const noexcept override {
        const std::lock_guard lock(status_mutex_);  // the socket's two threads; never the servo's
        const auto now = std::chrono::steady_clock::now();
        if (!status_read_ || now - *status_read_ >= kStatusMaxAge) {
            status_ = inbox_.status();
            status_read_ = now;
        }
        return status_;
    }
    void arm() noexcept override { inbox_.arm(); }
    void mark(std::uint32_t number) noexcept override { inbox_.mark(number); }
    void disarm() noexcept override { inbox_.disarm(); }
    void reset() noexcept override {
        resets_requested_.fetch_add(1, std::memory_order_acq_rel);
        inbox_.request_fault_reset();
    }
    std::uint64_t resets_requested() const noexcept override {
        return resets_requested_.load(std::memory_order_acquire);
    }
    void set_coupling(const servo::CouplingGains& gains) noexcept override {
        const std::lock_guard lock(gains_mutex_);  // two non-real-time threads; never the servo's
        gains_ = gains;
        inbox_.request_coupling(gains);
    }
    servo::CouplingGains coupling() const noexcept override {
        const std::lock_guard lock(gains_mutex_);
        return gains_;
    }

  private:
    Inbox& inbox_;
    std::atomic<std::uint64_t> resets_requested_{0};
    mutable std::mutex gains_mutex_;
    servo::CouplingGains gains_;  // the last accepted: the servo may not have taken it yet
    mutable std::mutex status_mutex_;
    mutable servo::StatusSnapshot status_;  // read from the loop at status_read_
    mutable std::optional<std::chrono::steady_clock::time_point> status_read_;
};

/// The environment of `scene` that a loop over `Environment` renders; null for the other
/// causality.
template <typename Environment>
Environment* environment_of(env::Scene& scene) noexcept {
    if constexpr (std::is_same_v<Environment, env::ImpedanceEnvironment>) {
        return scene.impedance.get();
    } else if constexpr (std::is_same_v<Environment, env::AdmittanceEnvironment>) {
        return scene.admittance.get();
    } else {
        return nullptr;
    }
}

/// The ports of scene_load, record and identify over `inbox`, a loop's over `Environment`, and
/// `control` for the rest.
template <typename Environment, typename Inbox>
SocketLoopPorts socket_loop_ports(Inbox& inbox, control_socket::ServoControl& control) {
    return SocketLoopPorts{
        .control = control,
        .scenes = SceneLoopPort{.offer =
                                    [&inbox](env::Scene& next) {
                                        Environment* const e = environment_of<Environment>(next);
                                        return e != nullptr && inbox.offer_environment(*e);
                                    },
                                .taken = [&inbox] { return inbox.offer_taken(); },
                                .withdraw =
                                    [&inbox](env::Scene& next) {
                                        Environment* const e = environment_of<Environment>(next);
                                        return e != nullptr && inbox.withdraw_environment(*e);
                                    }},
        .attach_recording =
            [&inbox](servo::TelemetryRing* recording_ring) {
                inbox.attach_recording(recording_ring);
            },
        .tick = [&inbox] { return inbox.status().tick; },
        .identify = IdentifyLoopPort{.play =
                                         [&inbox](servo::OpenLoopSource& source) {
                                             return inbox.play_open_loop(source);
                                         },
                                     .idle = [&inbox] { return inbox.open_loop_idle(); },
                                     .disarm = [&inbox] { inbox.disarm(); },
                                     .status = [&inbox] { return inbox.status(); }}};
}

}  // namespace hapticd::daemon
