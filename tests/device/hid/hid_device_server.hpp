// The device side of an emulated hidraw node (umockdev_hidraw.hpp): a thread that reads the
// host's 64-byte output reports from the node's pty master, hands each to the reference
// device (DeviceEmulator::handle_hid_report, docs/protocol.md 7) and writes its input reports
// back. The reference device runs in lockstep: each command is one period of its physics.
//
// Tests reach the device through with_device() (its fault knobs, its state), under the lock
// the server thread takes around each report; inject_input_report() writes a report of the
// test's own (a wrong report ID, garbage) ahead of whatever the device answers next.
//
// Timing: every read() and write() of the node makes a round trip through umockdev's ioctl
// thread, and each report crosses the pty's flip-buffer worker and this thread, so one
// request and its answer take about a dozen thread hand-offs. On an idle machine that is a
// fraction of a millisecond; on a loaded 2-core one it is several milliseconds, and now and
// then well over a second. A test whose outcome must not depend on that waits for
// await_answered() before it reads the answer: once it returns, the answer is in the node,
// and a read() finds it at once, whatever its deadline.
//
// Unlike a hidraw node, the node (a pty) has one input queue for all its clients: input
// reports nobody read stay for the next client to open it (hidraw starts each open with an
// empty queue; ProtocolDevice discards what is there before its handshake), and two clients
// open at once would each take some of the reports (hidraw gives every client a copy). The
// tests open one client at a time.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <thread>

#include "hapticd/device/protocol/device_emulator.hpp"

namespace hapticd::testing {

class HidDeviceServer {
  public:
    /// Serves `master_fd` (not owned) with a new DeviceEmulator of `config`.
    HidDeviceServer(int master_fd, const device::protocol::EmulatorConfig& config);
    ~HidDeviceServer();  ///< stop()

    HidDeviceServer(const HidDeviceServer&) = delete;
    HidDeviceServer& operator=(const HidDeviceServer&) = delete;

    /// Ends the thread (before the master fd is closed). Idempotent.
    void stop();

    template <typename F>
    decltype(auto) with_device(F&& f) {
        std::lock_guard lock(mutex_);
        return f(*device_);
    }

    /// Writes one input report as is (any size, any ID).
    void inject_input_report(std::span<const std::byte> report);

    /// Output reports read from the node (counted before the device handles them).
    std::uint64_t output_reports() const { return output_reports_.load(); }
    /// Input reports written to the node (counted before each is written, so a client never
    /// holds a report this does not count yet).
    std::uint64_t input_reports() const { return input_reports_.load(); }

    /// Waits until the device has handled `output_reports` output reports in all and every
    /// input report it answered them with is in the node; false after `timeout`. Taking
    /// output_reports() before sending gives the count to wait for: output_reports() + the
    /// reports sent. Allocates nothing (the HidDevice test waits under an AllocationGuard).
    bool await_answered(std::uint64_t output_reports, std::chrono::nanoseconds timeout);

  private:
    void run();
    void write_all(std::span<const std::byte> bytes);

    int master_;
    int wake_ = -1;           ///< eventfd: stop()
    std::mutex mutex_;        ///< the device
    std::mutex write_mutex_;  ///< whole reports on the master, in order
    std::unique_ptr<device::protocol::DeviceEmulator> device_;
    std::atomic<std::uint64_t> output_reports_{0};
    std::atomic<std::uint64_t> input_reports_{0};
    std::mutex answered_mutex_;
    std::condition_variable answered_changed_;
    std::uint64_t answered_ = 0;  ///< output reports handled and answered (answered_mutex_)
    std::thread thread_;
};

}  // namespace hapticd::testing
