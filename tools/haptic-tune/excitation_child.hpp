// autotune's excitation child: `hapticd --identify` as a child process (docs/autotune.md).
#pragma once

#include <string>

#include "hapticd/daemon/config.hpp"

namespace hapticd::tools {

/// The hapticd next to this haptic-tune (the build tree's bin/, or the install's bindir),
/// else "hapticd" to be found on PATH.
std::string default_hapticd();

/// The sim plugin on its lockstep clock ([device.sim] clock = "lockstep", read by the sim's
/// own reader, device/sim/sim_config.hpp): the run can go as fast as the CPU (--lockstep).
/// False for a table the sim refuses (hapticd then says why).
bool sim_lockstep(const daemon::Config& config);

/// Runs `hapticd --identify --config CONFIG --log LOG [--lockstep] [--no-status]
/// --parent-lifeline FD` and waits for it. Its standard output goes to our standard error
/// (so that --json output stays clean); its messages show. SIGINT, SIGTERM, SIGHUP and
/// SIGQUIT are passed on to it (it stops at zero force), and autotune reports "interrupted".
/// The lifeline is the read end of a pipe whose write end only this process holds: if
/// autotune dies, even by SIGKILL, the kernel closes it and hapticd stops on its own within
/// one period. `started` is set once hapticd runs (its log is then its own). Throws
/// AutotuneError when it cannot start, was interrupted, or did not exit 0, naming the
/// command and what its exit status means.
void run_identification(const std::string& hapticd, const std::string& config_path,
                        const std::string& log_path, bool lockstep, bool quiet, bool& started);

}  // namespace hapticd::tools
