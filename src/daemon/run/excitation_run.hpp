// `hapticd --identify`: the excitation ([identify], env/excitation.hpp) instead of the
// scene, open loop, logged for haptic-tune identify (docs/identification.md).
#pragma once

#include <atomic>
#include <iosfwd>

#include "hapticd/daemon/run.hpp"
#include "run/run_stamp.hpp"

namespace hapticd::daemon {

/// The excitation run (hapticd --identify), as run_daemon runs a scene: set up, supervised,
/// summarised. Throws BadInput, ConfigError or OutputError before the device moves (run_daemon maps
/// them to exit 2); returns the exit code once it ran.
int run_excitation(const RunOptions& options, const RunStamp& stamp, std::atomic<bool>& stop,
                   std::ostream& out, std::ostream& log);

}  // namespace hapticd::daemon
