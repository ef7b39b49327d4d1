// The device side of an emulated hidraw node (umockdev_hidraw.hpp): a thread that reads the
// host's 64-byte output reports from the node's pty master, hands each to the reference
// device (DeviceEmulator::handle_hid_report, docs/protocol.md 7) and writes its input reports
// back. The reference device runs in lockstep: each command is one period of its physics.
//
// Tests reach the device through with_device() (its fault knobs, its state), under the lock
// the server thread takes around each report; inject_input_report() writes a report of the
// test's own (a wrong report ID, garbage) ahead of whatever the device answers next.
#pragma once

#include <atomic>
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

    std::uint64_t output_reports() const { return output_reports_.load(); }
    std::uint64_t input_reports() const { return input_reports_.load(); }

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
    std::thread thread_;
};

}  // namespace hapticd::testing
