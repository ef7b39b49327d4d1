// A hapticd running in the background for tests that talk to it while it runs (the control
// socket): started with its arguments, its messages to a file, stopped with SIGTERM. A
// ChildProcess (child_process.hpp), its standard output discarded.
#pragma once

#include <signal.h>
#include <sys/stat.h>

#include <chrono>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "child_process.hpp"

namespace hapticd::testing {

class BackgroundDaemon : public ChildProcess {
  public:
    /// Starts `program` with `arguments`, standard error to `err_file`.
    BackgroundDaemon(std::string program, std::vector<std::string> arguments, std::string err_file)
        : ChildProcess(argv_of(std::move(program), std::move(arguments)), "/dev/null",
                       std::move(err_file)) {}

    /// True once `path` is a socket; false if the daemon exited first or `timeout` passed.
    bool wait_for_socket(const std::string& path,
                         std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
        const auto deadline = std::chrono::steady_clock::now() + timeout;
        while (std::chrono::steady_clock::now() < deadline) {
            struct stat st {};
            if (::lstat(path.c_str(), &st) == 0 && S_ISSOCK(st.st_mode)) return true;
            if (wait(std::chrono::milliseconds(0))) return false;
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
        return false;
    }

    /// SIGTERM, then its exit status (-1 if it did not exit normally).
    int stop() {
        signal(SIGTERM);
        wait();
        return exited() ? exit_code() : -1;
    }

    std::string messages() const { return err(); }

  private:
    static std::vector<std::string> argv_of(std::string program,
                                            std::vector<std::string> arguments) {
        arguments.insert(arguments.begin(), std::move(program));
        return arguments;
    }
};

}  // namespace hapticd::testing
