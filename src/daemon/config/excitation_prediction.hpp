// Before `hapticd --identify` (or `hapticctl identify`) moves anything: what [device.model]
// predicts the planned excitation will do to the handle, through the identification's own
// exact model (tune::predict_open_loop: m, b and, when stated, the Coulomb friction), and
// the refusals that follow (docs/daemon.md, "Identification run"):
//   - a run that would leave the [identify] workspace (it would stop at the edge, with a
//     log too short to identify from);
//   - a run in which friction would hold the handle still after more of the periods than
//     haptic-tune identify accepts (IdentificationOptions::max_stuck_fraction): it barely
//     moves, and the log would be refused after the run.
// Each refusal names the keys to change and the amplitude that would do.
#pragma once

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/servo_settings.hpp"

namespace hapticd::daemon {

/// Fills plan.predicted_excursion_m and plan.predicted_stuck_fraction from [device.model]
/// (nothing without mass and damping) for the planned run: the still wait at zero force,
/// the excitation, then `tail_s` of zero force. Throws ConfigError naming the file, the keys
/// and the allowed amplitude when the run would leave the workspace or stick too long.
void predict_excitation(const Config& config, IdentifyPlan& plan, double tail_s);

}  // namespace hapticd::daemon
