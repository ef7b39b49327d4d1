// What each control request does to a running servo loop (docs/control.md, "Requests").
// The server (socket/server.hpp) parses; this answers. It runs on the server's thread (a
// coupling's stability check on the server's worker), and nothing it asks of the loop waits
// for the servo thread: status() reads a seqlock (recent_status() a copy of it at most 5 ms
// old, behind a mutex of the socket's threads), arm(), disarm() and reset() set atomics, and
// new gains go through a seqlock, all taken by the servo thread at the start of its next
// tick; the device's link counts (Device::link_quality) are relaxed atomics.
#pragma once

#include <atomic>
#include <functional>
#include <string>

#include "hapticd/daemon/run_notes.hpp"
#include "hapticd/device/device.hpp"
#include "hapticd/servo/environment_port.hpp"
#include "hapticd/servo/status.hpp"
#include "socket/excitation_session.hpp"
#include "socket/recording.hpp"
#include "socket/scene_switch.hpp"
#include "socket/server.hpp"

namespace hapticd::daemon::control_socket {

/// The servo loop as the control socket sees it (socket/loop_ports.hpp adapts ServoLoop; tests
/// use their own).
class ServoControl {
  public:
    virtual ~ServoControl() = default;
    /// The loop's status as of its latest tick: for what a request decides (arm's refusal of
    /// a latched fault, a coupling's check).
    virtual servo::StatusSnapshot status() const noexcept = 0;
    /// A status at most a few ms old, read from the loop at most once per that time: for
    /// `status` replies and telemetry events, which any client may ask for as fast as it
    /// likes (socket/loop_ports.hpp, kStatusMaxAge).
    virtual servo::StatusSnapshot recent_status() const noexcept = 0;
    /// Why the environment failed, "" when it has not (LoopInbox::environment_failure).
    virtual std::string environment_failure() const { return {}; }
    virtual void arm() noexcept = 0;
    virtual void disarm() noexcept = 0;
    virtual void reset() noexcept = 0;
    /// How many reset()s were asked for so far (the status's fault_resets_taken catches up
    /// once the servo has taken them and published a status).
    virtual std::uint64_t resets_requested() const noexcept = 0;
    /// From the control server's worker thread (one at a time).
    virtual void set_coupling(const servo::CouplingGains& gains) noexcept = 0;
    /// The gains last set (or the config's): what a coupling request without damping keeps.
    /// From the server's thread while the worker may set them.
    virtual servo::CouplingGains coupling() const noexcept = 0;
    /// Every record from the next tick on carries `number` in its `mark` column
    /// (LoopInbox::mark; the text is the run's, RunNotes).
    virtual void mark(std::uint32_t number) noexcept = 0;
};

/// What the stability check made of new coupling gains.
struct CouplingVerdict {
    bool accepted = false;
    std::string verdict;  ///< the check's one line (StartupCheck::describe()), or why not
};

/// What does not change during a run, for `status`.
struct RunFacts {
    std::string name;  ///< [servo] name
    int axes = 1;
    double rate_hz = 1000.0;  ///< [servo] rate_hz
    std::string device;       ///< the device line ("sim device, 3 axes, lockstep clock")
    std::string config_path;  ///< absolute; "(embedded default)" without --config
    /// The ticks per second over the last second, kept by the supervising thread.
    const std::atomic<double>* measured_rate_hz = nullptr;
    double velocity_filter_hz = 0.0;  ///< [coupling] velocity_filter: a coupling request keeps it
    bool coupling_enabled = true;     ///< [coupling] enabled
    /// The start-up check on the config with these gains ([coupling] check; docs/control.md).
    std::function<CouplingVerdict(const servo::CouplingGains&)> check_coupling{};
    /// record_start and record_stop's; null: this run cannot record.
    Recording* recording = nullptr;
    /// scene_load's; null: this run renders no scene (an excitation run).
    SceneSwitch* scenes = nullptr;
    /// identify's; null: this run cannot play the excitation (an excitation run).
    ExcitationSession* identify = nullptr;
    /// The device, for `status`'s link counts: only its link_quality(), which any thread may
    /// call while the servo thread reads and writes it (device.hpp). Null: no counts
    /// (`counted` false).
    const device::Device* link_source = nullptr;
    /// The run's notes: mark's, and a note for each coupling and scene_load taken; null: this
    /// run cannot mark.
    RunNotes* notes = nullptr;
};

/// The status reply's body: state, tick, rates, forces, positions and faults.
nlohmann::json status_body(const servo::StatusSnapshot& s, const RunFacts& facts);

/// A subscriber's event (docs/control.md, "subscribe"): tick, t_s, state, x_m, xe_m, f_n and
/// faults, from the servo's last status.
std::string telemetry_event(const servo::StatusSnapshot& s, const RunFacts& facts);

/// Answers one request.
Answer answer(const Request& request, const Peer& peer, ServoControl& loop, const RunFacts& facts);

}  // namespace hapticd::daemon::control_socket
