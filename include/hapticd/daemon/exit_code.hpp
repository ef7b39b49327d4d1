// The exit codes of every hapticd command (hapticd, haptic-tune): 0 success, 1 a negative
// outcome (a fault, a design that is not stable), 2 bad input, 3 an output that is not
// whole. Scripts depend on them (docs/daemon.md, README.md).
#pragma once

#include "hapticd/input/input_error.hpp"

namespace hapticd::daemon {

enum ExitCode : int {
    kExitOk = 0,         ///< hapticd: stopped by a signal or at the end of --duration, no fault;
                         ///< haptic-tune: done, and the design is stable (check, size)
    kExitFault = 1,      ///< hapticd: the run ended on a latched fault, or the loop could not
                         ///< run; --identify: also when the handle left the workspace
    kExitVerdictNo = 1,  ///< haptic-tune: the verdict is no: check finds the design not
                         ///< stable, size's answer fails the exact model, diag's link is
                         ///< not fit, autotune's tuned config fails its start-up check
    kExitBadInput =
        input::InputError::kExitCode,  ///< usage, config, scene or device-table errors; gains
                                       ///< refused; real time refused in enforce mode (before the
                                       ///< first tick); an output path that is empty, an input,
                                       ///< another output, locked by another daemon, or cannot be
                                       ///< created (found before the run)
    kExitOutput = 3,  ///< the run ended without a fault, but an output is not whole: the
                      ///< --log (disk full, a write error, records dropped), --summary, a
                      ///< control socket's recording, or a flight record
};

}  // namespace hapticd::daemon
