#include "child_process.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <optional>

extern char** environ;

namespace hapticd::tools {
namespace {

/// Closes a file descriptor once.
class Fd {
  public:
    explicit Fd(int fd = -1) : fd_(fd) {}
    Fd(const Fd&) = delete;
    Fd& operator=(const Fd&) = delete;
    ~Fd() { reset(); }
    int get() const { return fd_; }
    void reset(int fd = -1) {
        if (fd_ >= 0) ::close(fd_);
        fd_ = fd;
    }

  private:
    int fd_;
};

/// A pipe whose both ends are close-on-exec: the child gets only what dup2 gives it.
bool make_pipe(Fd& read_end, Fd& write_end) {
    std::array<int, 2> fds{-1, -1};
    if (::pipe2(fds.data(), O_CLOEXEC) != 0) return false;
    read_end.reset(fds[0]);
    write_end.reset(fds[1]);
    return true;
}

/// Ignores SIGPIPE while it lives, so a child that exits early makes write() fail with
/// EPIPE instead of killing haptic-tune.
class IgnoreSigpipe {
  public:
    IgnoreSigpipe() {
        struct sigaction ignore {};
        ignore.sa_handler = SIG_IGN;
        sigemptyset(&ignore.sa_mask);
        ::sigaction(SIGPIPE, &ignore, &old_);
    }
    IgnoreSigpipe(const IgnoreSigpipe&) = delete;
    IgnoreSigpipe& operator=(const IgnoreSigpipe&) = delete;
    ~IgnoreSigpipe() { ::sigaction(SIGPIPE, &old_, nullptr); }

  private:
    struct sigaction old_ {};
};

constexpr std::array<int, 4> kStopSignals = {SIGINT, SIGTERM, SIGHUP, SIGQUIT};

volatile std::sig_atomic_t g_child_pid = 0;
volatile std::sig_atomic_t g_interrupted = 0;

extern "C" void pass_on_stop_signal(int signal) {
    g_interrupted = signal;
    // Passed on whoever sent it: a terminal's Ctrl-C reaches the whole process group, the
    // child included (a second SIGINT is harmless), but a signal sent to us alone must
    // reach the child too.
    if (g_child_pid > 0) ::kill(static_cast<pid_t>(g_child_pid), signal);
}

/// While it lives: the stop signals are passed on to the child (pass_on_stop_signal).
/// Blocked from construction until started(), so that none is lost before the pid is known.
class StopSignalForwarding {
  public:
    StopSignalForwarding() {
        sigemptyset(&signals_);
        for (const int signal : kStopSignals) sigaddset(&signals_, signal);
        ::pthread_sigmask(SIG_BLOCK, &signals_, &old_mask_);
        struct sigaction pass_on {};
        pass_on.sa_handler = pass_on_stop_signal;
        sigemptyset(&pass_on.sa_mask);
        g_interrupted = 0;
        for (std::size_t i = 0; i < kStopSignals.size(); ++i) {
            ::sigaction(kStopSignals[i], &pass_on, &old_actions_[i]);
        }
    }
    StopSignalForwarding(const StopSignalForwarding&) = delete;
    StopSignalForwarding& operator=(const StopSignalForwarding&) = delete;
    ~StopSignalForwarding() {
        g_child_pid = 0;
        unblock();
        for (std::size_t i = 0; i < kStopSignals.size(); ++i) {
            ::sigaction(kStopSignals[i], &old_actions_[i], nullptr);
        }
    }

    /// What the child starts with: our mask from before, the stop signals at default.
    void configure(posix_spawnattr_t& attributes) const {
        posix_spawnattr_setsigmask(&attributes, &old_mask_);
        posix_spawnattr_setsigdefault(&attributes, &signals_);
        posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
    }
    /// The child runs (pid > 0) or never will (0): a signal that came meanwhile goes now.
    void started(pid_t pid) {
        g_child_pid = pid;
        unblock();
    }
    int interrupted_by() const { return static_cast<int>(g_interrupted); }

  private:
    void unblock() {
        if (blocked_) ::pthread_sigmask(SIG_SETMASK, &old_mask_, nullptr);
        blocked_ = false;
    }
    sigset_t signals_{};
    sigset_t old_mask_{};
    std::array<struct sigaction, kStopSignals.size()> old_actions_{};
    bool blocked_ = true;
};

/// Writes `input` to `to_child` and reads `from_child` until both are done, at once, so
/// that a child that prints before it has read everything cannot deadlock with us.
void exchange(Fd& to_child, Fd& from_child, const std::string& input, std::string& output) {
    IgnoreSigpipe ignore_sigpipe;
    ::fcntl(to_child.get(), F_SETFL, ::fcntl(to_child.get(), F_GETFL) | O_NONBLOCK);
    std::size_t written = 0;
    if (input.empty()) to_child.reset();
    while (to_child.get() >= 0 || from_child.get() >= 0) {
        std::array<pollfd, 2> fds{};
        nfds_t count = 0;
        if (to_child.get() >= 0) fds[count++] = {to_child.get(), POLLOUT, 0};
        if (from_child.get() >= 0) fds[count++] = {from_child.get(), POLLIN, 0};
        if (::poll(fds.data(), count, -1) < 0) {
            if (errno == EINTR) continue;
            break;
        }
        for (nfds_t i = 0; i < count; ++i) {
            if (fds[i].revents == 0) continue;
            if (fds[i].fd == to_child.get()) {
                const ssize_t n =
                    ::write(to_child.get(), input.data() + written, input.size() - written);
                if (n > 0) written += static_cast<std::size_t>(n);
                const bool failed = n < 0 && errno != EAGAIN && errno != EINTR;
                if (failed || written == input.size()) to_child.reset();  // EOF for the child
            } else {
                std::array<char, 4096> buffer{};
                const ssize_t n = ::read(from_child.get(), buffer.data(), buffer.size());
                if (n > 0) {
                    output.append(buffer.data(), static_cast<std::size_t>(n));
                } else if (n == 0 || (errno != EAGAIN && errno != EINTR)) {
                    from_child.reset();
                }
            }
        }
    }
    to_child.reset();  // also on a poll() failure, so that the child cannot wait on us forever
    from_child.reset();
}

}  // namespace

std::string ChildRun::describe_exit() const {
    if (signal != 0) {
        return "was killed by signal " + std::to_string(signal) + " (" + strsignal(signal) + ")";
    }
    return "exited with status " + std::to_string(exit_code);
}

ChildRun run_child(const std::vector<std::string>& argv_strings, const ChildOptions& options) {
    ChildRun run;
    Fd child_in, to_child, from_child, child_out;
    if (options.capture && (!make_pipe(child_in, to_child) || !make_pipe(from_child, child_out))) {
        run.spawn_error = errno;
        return run;
    }
    if (options.inherited_fd >= 0) ::fcntl(options.inherited_fd, F_SETFD, 0);

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    if (options.capture) {
        posix_spawn_file_actions_adddup2(&actions, child_in.get(), STDIN_FILENO);
        posix_spawn_file_actions_adddup2(&actions, child_out.get(), STDOUT_FILENO);
        posix_spawn_file_actions_adddup2(&actions, child_out.get(), STDERR_FILENO);
    } else {
        posix_spawn_file_actions_adddup2(&actions, STDERR_FILENO, STDOUT_FILENO);
    }
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    std::optional<StopSignalForwarding> forwarding;
    if (options.forward_stop_signals) {
        forwarding.emplace();
        forwarding->configure(attributes);
    }
    std::vector<std::string> args = argv_strings;
    std::vector<char*> argv;
    argv.reserve(args.size() + 1);
    for (std::string& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    // posix_spawnp searches PATH when the name has no '/'; glibc reports a failed exec here.
    run.spawn_error = ::posix_spawnp(&pid, argv[0], &actions, &attributes, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attributes);
    if (options.inherited_fd >= 0) ::fcntl(options.inherited_fd, F_SETFD, FD_CLOEXEC);
    if (forwarding) forwarding->started(run.started() ? pid : 0);
    if (!run.started()) return run;

    if (options.capture) {
        child_in.reset();
        child_out.reset();
        exchange(to_child, from_child, options.input, run.output);
    }
    int status = 0;
    pid_t waited = 0;
    while ((waited = ::waitpid(pid, &status, 0)) < 0 && errno == EINTR) {
    }
    if (waited == pid && WIFEXITED(status)) run.exit_code = WEXITSTATUS(status);
    if (waited == pid && WIFSIGNALED(status)) run.signal = WTERMSIG(status);
    if (forwarding) run.interrupted_by = forwarding->interrupted_by();
    return run;
}

}  // namespace hapticd::tools
