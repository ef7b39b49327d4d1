// A child process for the tests that run the executables: started with posix_spawn (none of
// the test's code runs between fork and exec, so it is safe beside the test's threads), its
// standard output and error each to a file or both to pipes; signalled, waited for (with a
// timeout or to its end), and its exit status. Destroyed while it runs, it is killed
// (SIGKILL) and reaped. run_command.hpp (a shell command, its output captured) and
// background_daemon.hpp (a hapticd serving its control socket) are built on it.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "text_file.hpp"

extern char** environ;

namespace hapticd::testing {

class ChildProcess {
  public:
    /// Runs `argv` (argv[0] is the program's path, not searched for in PATH) in the test's
    /// environment, its standard output and error to the files `out_file` and `err_file`
    /// (created or truncated; "/dev/null" discards). Throws when it cannot be started.
    ChildProcess(std::vector<std::string> argv, std::string out_file, std::string err_file)
        : out_file_(std::move(out_file)), err_file_(std::move(err_file)) {
        start(std::move(argv));
    }
    /// The same with its standard output and error to pipes: read them with read_output().
    explicit ChildProcess(std::vector<std::string> argv) { start(std::move(argv)); }
    ~ChildProcess() {
        if (!reaped_) {
            ::kill(pid_, SIGKILL);
            wait();
        }
        close_pipes();
    }
    ChildProcess(const ChildProcess&) = delete;
    ChildProcess& operator=(const ChildProcess&) = delete;

    pid_t pid() const { return pid_; }
    /// Sends it `number` (nothing once it has been reaped: its pid may be another's by then).
    void signal(int number) const {
        if (!reaped_) ::kill(pid_, number);
    }
    /// Waits up to `timeout` (0: only looks); true when it has ended (exit_code()).
    bool wait(std::chrono::milliseconds timeout) {
        const auto until = std::chrono::steady_clock::now() + timeout;
        while (!reap(WNOHANG) && std::chrono::steady_clock::now() <= until) {
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }
        return reaped_;
    }
    /// Waits until it ends.
    void wait() {
        while (!reaped_) reap(0);
    }
    /// Once it ended: whether it exited (rather than a signal ending it).
    bool exited() const { return WIFEXITED(status_); }
    /// Once it ended: its exit status, or -signal when a signal ended it.
    int exit_code() const { return WIFEXITED(status_) ? WEXITSTATUS(status_) : -WTERMSIG(status_); }
    /// What it has written to its output and error files so far ("" with pipes).
    std::string out() const { return read_file(out_file_); }
    std::string err() const { return read_file(err_file_); }

    struct Output {
        std::string out;  ///< standard output
        std::string err;  ///< standard error
    };
    /// With pipes: its standard output and error, read until both are closed (when it, and
    /// whatever it started and left them to, has ended).
    Output read_output() {
        Output output;
        std::array<pollfd, 2> pipes{{{out_pipe_, POLLIN, 0}, {err_pipe_, POLLIN, 0}}};
        const std::array<std::string*, 2> into{&output.out, &output.err};
        std::array<char, 4096> buffer{};
        while (pipes[0].fd >= 0 || pipes[1].fd >= 0) {
            if (::poll(pipes.data(), pipes.size(), -1) < 0) {
                if (errno == EINTR) continue;
                throw std::runtime_error(std::string("poll: ") + std::strerror(errno));
            }
            for (std::size_t i = 0; i < pipes.size(); ++i) {
                if (pipes[i].fd < 0 || pipes[i].revents == 0) continue;
                const ssize_t n = ::read(pipes[i].fd, buffer.data(), buffer.size());
                if (n > 0) {
                    into[i]->append(buffer.data(), static_cast<std::size_t>(n));
                } else if (n == 0 || errno != EINTR) {
                    ::close(pipes[i].fd);
                    pipes[i].fd = -1;
                }
            }
        }
        out_pipe_ = err_pipe_ = -1;
        return output;
    }

  private:
    void start(std::vector<std::string> argv) {
        if (argv.empty()) throw std::invalid_argument("ChildProcess: no program to run");
        posix_spawn_file_actions_t actions;
        posix_spawn_file_actions_init(&actions);
        std::array<int, 2> out{-1, -1};
        std::array<int, 2> err{-1, -1};
        const bool piped = out_file_.empty() && err_file_.empty();
        if (piped) {
            if (::pipe2(out.data(), O_CLOEXEC) != 0 || ::pipe2(err.data(), O_CLOEXEC) != 0) {
                const int error = errno;
                for (const int fd : {out[0], out[1], err[0], err[1]}) {
                    if (fd >= 0) ::close(fd);
                }
                posix_spawn_file_actions_destroy(&actions);
                throw std::runtime_error(std::string("pipe2: ") + std::strerror(error));
            }
            // dup2 clears close-on-exec on 1 and 2 only: the child keeps no other end.
            posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
            posix_spawn_file_actions_adddup2(&actions, err[1], STDERR_FILENO);
        } else {
            posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out_file_.c_str(),
                                             O_WRONLY | O_CREAT | O_TRUNC, 0644);
            posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_file_.c_str(),
                                             O_WRONLY | O_CREAT | O_TRUNC, 0644);
        }
        std::vector<char*> pointers;
        pointers.reserve(argv.size() + 1);
        for (std::string& arg : argv) pointers.push_back(arg.data());
        pointers.push_back(nullptr);
        const int error =
            ::posix_spawn(&pid_, pointers[0], &actions, nullptr, pointers.data(), environ);
        posix_spawn_file_actions_destroy(&actions);
        if (piped) {
            ::close(out[1]);
            ::close(err[1]);
            out_pipe_ = out[0];
            err_pipe_ = err[0];
        }
        if (error != 0) {
            close_pipes();
            throw std::runtime_error("cannot run " + argv[0] + ": " + std::strerror(error));
        }
        reaped_ = false;
    }

    /// waitpid with `options`; true once it has been reaped.
    bool reap(int options) {
        if (reaped_) return true;
        const pid_t r = ::waitpid(pid_, &status_, options);
        if (r == pid_) reaped_ = true;
        if (r < 0 && errno != EINTR) {  // not ours to wait for: neither exited nor signalled
            status_ = -1;
            reaped_ = true;
        }
        return reaped_;
    }

    void close_pipes() noexcept {
        for (int* fd : {&out_pipe_, &err_pipe_}) {
            if (*fd >= 0) ::close(*fd);
            *fd = -1;
        }
    }

    std::string out_file_;
    std::string err_file_;
    pid_t pid_ = -1;
    int status_ = 0;
    bool reaped_ = true;  ///< until it has started: nothing to kill or wait for
    int out_pipe_ = -1;
    int err_pipe_ = -1;
};

}  // namespace hapticd::testing
