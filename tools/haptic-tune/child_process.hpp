// Running another program from haptic-tune and waiting for it: `hapticd --identify` for
// autotune, the chart script's python for plot and zwidth. One posix_spawn path for both,
// so that the child's file descriptors, signals and exit status are handled one way.
#pragma once

#include <string>
#include <vector>

namespace hapticd::tools {

struct ChildOptions {
    /// false: the child inherits our standard input and standard error, and its standard
    /// output goes to our standard error (so that our own --json output stays clean).
    /// true: `input` is written to its standard input, which is then closed, and what it
    /// prints on standard output and standard error is captured, together, in
    /// ChildRun::output. A child that stops reading early does not kill us (SIGPIPE).
    bool capture = false;
    std::string input;
    /// SIGINT, SIGTERM, SIGHUP and SIGQUIT are passed on to the child while it runs, and
    /// ChildRun::interrupted_by says which came. The child starts with them at their default
    /// actions. They are blocked from before the spawn until the child's pid is known, so
    /// that none is lost in between.
    bool forward_stop_signals = false;
    /// A file descriptor of ours that the child inherits across its exec (-1: none); the
    /// others are close-on-exec, as every descriptor haptic-tune opens is.
    int inherited_fd = -1;
};

struct ChildRun {
    int spawn_error = 0;     ///< errno when the child could not be started; then nothing ran
    int exit_code = -1;      ///< its exit status when it exited
    int signal = 0;          ///< the signal that killed it, 0 when it exited
    int interrupted_by = 0;  ///< forward_stop_signals: the signal passed on to it, 0: none
    std::string output;      ///< capture: what it printed

    bool started() const noexcept { return spawn_error == 0; }
    bool succeeded() const noexcept { return started() && signal == 0 && exit_code == 0; }
    /// "was killed by signal 9 (Killed)" or "exited with status 3".
    std::string describe_exit() const;
};

/// Runs argv (argv[0] is searched on PATH when it has no '/') and waits for it. Never
/// throws for the child's sake: a child that cannot start gives spawn_error.
ChildRun run_child(const std::vector<std::string>& argv, const ChildOptions& options);

}  // namespace hapticd::tools
