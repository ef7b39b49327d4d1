// The control socket's side of one run (docs/control.md; docs/architecture.md §2.8, §6.1):
// what scene_load, record and identify hold for the run, the facts `status` reports, the
// server started once the loop exists and stopped before it goes, and what the socket did
// brought back: its journal lines to the watching thread, its recordings, excitations and
// the scene in force to the summary. Everything it asks of the loop goes through
// SocketLoopPorts (socket/loop_ports.hpp builds them), lock-free (§6.2).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <optional>
#include <string>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/run_notes.hpp"
#include "hapticd/device/device.hpp"
#include "hapticd/env/scene.hpp"
#include "hapticd/servo/environment_port.hpp"
#include "hapticd/servo/telemetry_ring.hpp"
#include "outputs/outputs_directory.hpp"
#include "outputs/summary_json.hpp"
#include "socket/excitation_session.hpp"
#include "socket/recording.hpp"
#include "socket/requests.hpp"
#include "socket/scene_switch.hpp"
#include "socket/server.hpp"

namespace hapticd::daemon {

/// The scene a run renders (`environment` of run_loop is one of its environments), for the
/// control socket's scene_load; an excitation run has none.
struct RunScene {
    const env::Scene* scene = nullptr;
    std::string source;           ///< its file, or "<embedded demo-wall scene>"
    env::SceneOptions options{};  ///< how it was read, and how scenes that replace it are
};

/// The scene a file's preamble names: "NAME (CAUSALITY, SOURCE)" of the scene in force, the
/// last `scenes` loaded or else the run's own; "none (...)" for an excitation run.
std::string scene_in_force(const RunScene& scene, const SceneSwitch* scenes = nullptr);

/// The start-up check of `config` with the coupling `gains` in place of its own, against the
/// scene in force (`scenes`; without, the config's): what a control socket's coupling request
/// must pass ([coupling] check, docs/control.md).
control_socket::CouplingVerdict check_new_coupling(const Config& config, const SceneSwitch* scenes,
                                                   const servo::CouplingGains& gains);

/// What the control socket's requests need of the servo loop.
struct SocketLoopPorts {
    control_socket::ServoControl&
        control;           ///< status, arm, disarm, reset, coupling (InboxServoControl)
    SceneLoopPort scenes;  ///< scene_load's
    std::function<void(servo::TelemetryRing*)> attach_recording;  ///< record's
    std::function<std::uint64_t()> tick;                          ///< record's: the last tick
    IdentifyLoopPort identify;                                    ///< identify's
};

// One per run, on the watching thread: its members stand in the order they must be destroyed
// in (the stopper last, so first), not the order that packs them tightest.
class RunControl {  // NOLINT(clang-analyzer-optin.performance.Padding)
  public:
    /// Without `server` (no --socket), only the measured rate. With one: scene_load for a run
    /// that renders `scene`, record, identify for a run that renders a scene (their files in
    /// `outputs`, the run's outputs directory; null: none), then the server started, and a
    /// line on `log` naming it.
    /// `device` (the run's, open, outliving this): `status` reports its link_quality(), which
    /// the server's thread calls while the servo thread ticks; null: no device counts.
    /// `notes`: the run's (mark, and the notes of coupling and scene_load), outliving this.
    RunControl(const Config& config, const device::DeviceInfo& info, const RunScene& scene,
               const RunContext& context, const SocketLoopPorts& ports,
               control_socket::SocketServer* server, const OutputsDirectory* outputs,
               std::ostream& log, const device::Device* device, RunNotes& notes);
    RunControl(const RunControl&) = delete;
    RunControl& operator=(const RunControl&) = delete;

    /// The ticks per second over the last second, which the watcher measures and `status`
    /// reports.
    std::atomic<double>& measured_rate_hz() noexcept { return measured_rate_hz_; }

    /// Each look of the watching thread: the server's journal lines onto `log`, then the
    /// progress of an identify excitation.
    void poll(std::ostream& log);

    /// After the servo thread has joined: stops the server, writes its last lines, ends a
    /// recording or excitation still running, and puts the recordings, the excitations and
    /// the scene in force at the end in `context`.
    void finish(RunContext& context, std::ostream& log);

  private:
    /// Stops the server when it goes out of scope: before the loop that its handler reaches
    /// is destroyed, on every path.
    struct ControlStopper {
        control_socket::SocketServer* server;
        ~ControlStopper() {
            if (server != nullptr) server->stop();
        }
    };

    void drain_messages(std::ostream& log);
    void finish_recording(RunContext& context, std::ostream& log);
    /// A recording's preamble: the gains, their verdict and the scene in force as it starts.
    std::string recording_preamble(const RunContext& context, const device::DeviceInfo& info,
                                   const RunScene& scene) const;

    const Config& config_;
    control_socket::ServoControl& control_;
    control_socket::SocketServer* server_;
    std::atomic<double> measured_rate_hz_{0.0};
    std::optional<SceneSwitch> scenes_;
    control_socket::RunFacts facts_;
    std::optional<Recording> recording_;
    std::optional<ExcitationSession> identify_;
    ControlStopper stopper_{nullptr};  // last: the server stops before the rest goes
};

}  // namespace hapticd::daemon
