// A hapticd running in the background for tests that talk to it while it runs (the control
// socket): started with its arguments, its messages to a file, stopped with SIGTERM.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "text_file.hpp"

namespace hapticd::testing {

class BackgroundDaemon {
  public:
    /// Starts `program` with `arguments`, standard error to `err_file`.
    BackgroundDaemon(std::string program, std::vector<std::string> arguments, std::string err_file)
        : program_(std::move(program)),
          arguments_(std::move(arguments)),
          err_file_(std::move(err_file)) {
        std::vector<char*> argv;
        argv.push_back(program_.data());
        for (std::string& a : arguments_) argv.push_back(a.data());
        argv.push_back(nullptr);
        pid_ = ::fork();
        if (pid_ < 0) throw std::runtime_error("fork failed");
        if (pid_ == 0) {
            // Only async-signal-safe calls between fork and exec (the test has threads).
            const int err = ::open(err_file_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
            const int null = ::open("/dev/null", O_WRONLY);
            if (err < 0 || null < 0 || ::dup2(err, 2) < 0 || ::dup2(null, 1) < 0) ::_exit(127);
            ::execv(program_.c_str(), argv.data());
            ::_exit(127);
        }
    }
    ~BackgroundDaemon() {
        if (pid_ > 0) {
            ::kill(pid_, SIGKILL);
            ::waitpid(pid_, nullptr, 0);
        }
    }
    BackgroundDaemon(const BackgroundDaemon&) = delete;
    BackgroundDaemon& operator=(const BackgroundDaemon&) = delete;

    /// True once `path` is a socket; false if the daemon exited first or `timeout` passed.
    bool wait_for_socket(const std::string& path,
                         std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
        const auto deadline = std::chrono::steady_clock::now() + timeout;
        while (std::chrono::steady_clock::now() < deadline) {
            struct stat st {};
            if (::lstat(path.c_str(), &st) == 0 && S_ISSOCK(st.st_mode)) return true;
            if (pid_ > 0 && ::waitpid(pid_, &status_, WNOHANG) == pid_) {
                pid_ = -1;
                return false;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
        return false;
    }

    /// SIGTERM, then its exit status (-1 if it did not exit normally).
    int stop() {
        if (pid_ > 0) {
            ::kill(pid_, SIGTERM);
            ::waitpid(pid_, &status_, 0);
            pid_ = -1;
        }
        return WIFEXITED(status_) ? WEXITSTATUS(status_) : -1;
    }

    std::string messages() const { return read_file(err_file_); }

  private:
    std::string program_;
    std::vector<std::string> arguments_;
    std::string err_file_;
    pid_t pid_ = -1;
    int status_ = 0;
};

}  // namespace hapticd::testing
