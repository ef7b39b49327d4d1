// The servo loop on a thread of its own (docs/architecture.md §6.1, §7.2): ServoLoop::run (the
// real-time setup, then the ticks) until the stop flag, which it reads itself at each tick,
// a lockstep run's tick limit or a fault. It is stopped and joined on every path out of the
// run, so that nothing it reaches goes before it and the loop's destructor, which writes zero
// force, never races a tick. A template over the loop, as ServoLoop is over its environment.
#pragma once

#include <atomic>
#include <cmath>
#include <cstdint>
#include <exception>
#include <string>
#include <thread>

#include "hapticd/daemon/run.hpp"
#include "hapticd/device/device.hpp"
#include "hapticd/servo/servo_loop.hpp"

namespace hapticd::daemon {

/// --duration of a lockstep run in ticks of virtual time; 0, no limit, otherwise (a real-time
/// run's duration is the watcher's to end, run_watcher.hpp).
inline std::uint64_t lockstep_tick_limit(const RunOptions& options, const device::DeviceInfo& info,
                                         double rate_hz) {
    if (options.duration_s && info.lockstep) {
        return static_cast<std::uint64_t>(std::llround(*options.duration_s * rate_hz));
    }
    return 0;
}

template <typename Loop>
class ServoThread {
  public:
    /// Starts `loop.run(stop, max_ticks)` on a new thread.
    ServoThread(Loop& loop, std::atomic<bool>& stop, std::uint64_t max_ticks)
        : stop_(stop), thread_([this, &loop, max_ticks] {
              try {
                  run_exit_ = loop.run(stop_, max_ticks);
              } catch (const std::exception& e) {
                  error_ = e.what();
              }
              done_.store(true, std::memory_order_release);
          }) {}

    /// Should anything on the watching thread throw before join(), the servo thread is
    /// stopped and joined (a joinable std::thread's destructor would end the process with the
    /// force held); the loop's destructor then writes zero force.
    ~ServoThread() {
        if (thread_.joinable()) {
            stop_.store(true, std::memory_order_release);
            thread_.join();
        }
    }
    ServoThread(const ServoThread&) = delete;
    ServoThread& operator=(const ServoThread&) = delete;

    /// run() has returned or thrown (any thread).
    bool done() const noexcept { return done_.load(std::memory_order_acquire); }
    void join() { thread_.join(); }

    /// After join(): what run() returned, and what it threw (empty: it returned).
    servo::RunExit run_exit() const noexcept { return run_exit_; }
    const std::string& error() const noexcept { return error_; }

  private:
    std::atomic<bool>& stop_;
    std::atomic<bool> done_{false};
    servo::RunExit run_exit_ = servo::RunExit::stopped;
    std::string error_;
    std::thread thread_;  // last: starts once the rest is set
};

}  // namespace hapticd::daemon
