// The reference device behind a pseudo-terminal: the test rig of the serial transport
// (docs/transport-serial.md, "Testing"). The host side opens slave_path() (or the stable
// symlink) exactly as it would open /dev/ttyACM0; a thread on the master side feeds every
// byte to DeviceEmulator::handle_stream() and writes the COBS-encoded replies back.
//
//   PtyPair    posix_openpt / grantpt / unlockpt / ptsname_r, the line raw (no echo), and a
//              slave descriptor kept open so that the master never sees the slave closed
//              (a master reads EIO while no slave is open) between the host's reopens.
//   PtyDevice  the emulator served on a PtyPair in its own thread. Tests reach the emulator
//              (fault knobs, inspection) through with_emulator(), serialised with the
//              serving thread; a request hook runs before each request (deterministic fault
//              injection at the n-th command); a line tap sees (and may change) the bytes
//              of each request before the emulator and of its answer before the line
//              (faults on the wire); the device can go silent, send raw bytes (garbage),
//              hang up (close the master: the host sees POLLHUP/EIO, as when a USB adapter
//              is unplugged) and be plugged in again on a new pty.
//
// A pty's slave path cannot outlive its master: /dev/pts/N is gone when the master closes,
// and a new pair may get another number. So a device that "comes back" is served on a new
// pair, and the path the host opens is a symlink that plug_in() re-points, which is what
// /dev/serial/by-id/... does for a real USB serial device that is replugged.
//
// Reusable by any test that needs a protocol device on a serial port (link diagnostics, the
// daemon against the serial plugin): link hapticd_test_pty_device.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "hapticd/device/protocol/device_emulator.hpp"

namespace hapticd::testing {

class PtyPair {
  public:
    /// Throws std::runtime_error (with errno's text) if the system has no ptys to give.
    PtyPair();
    ~PtyPair();
    PtyPair(const PtyPair&) = delete;
    PtyPair& operator=(const PtyPair&) = delete;

    int master() const noexcept { return master_; }
    /// The slave's own descriptor, kept open by the pair (to inspect its termios).
    int slave() const noexcept { return slave_; }
    const std::string& slave_path() const noexcept { return slave_path_; }
    /// Closes the master: every slave descriptor hangs up. Idempotent.
    void close_master() noexcept;

  private:
    int master_ = -1;
    int slave_ = -1;
    std::string slave_path_;
};

/// Points the symlink `link` at `target`, atomically (a new link renamed over the old one).
void point_symlink(const std::string& link, const std::string& target);

class PtyDevice {
  public:
    /// Called under the lock before the bytes that end with a delimiter (a request, or an
    /// empty frame) are handled: `requests` is the emulator's count of requests so far.
    using RequestHook =
        std::function<void(device::protocol::DeviceEmulator& emulator, std::uint64_t requests)>;

    /// Serves a new emulator on a new pty pair. With `stable_path` the host should open that
    /// symlink (it points at the current slave; plug_in() re-points it).
    explicit PtyDevice(const device::protocol::EmulatorConfig& config,
                       std::string stable_path = "");
    ~PtyDevice();
    PtyDevice(const PtyDevice&) = delete;
    PtyDevice& operator=(const PtyDevice&) = delete;

    /// What the host opens: the symlink if there is one, else the slave path.
    std::string port() const;
    std::string slave_path() const;
    /// The current pair (to look at the slave's termios); null while unplugged.
    const PtyPair* pair() const noexcept { return pair_.get(); }

    /// Runs `f(emulator)` with the serving thread held off.
    template <typename F>
    decltype(auto) with_emulator(F&& f) {
        std::lock_guard<std::mutex> lock(mutex_);
        return f(emulator_);
    }

    /// The wire between the host and the emulator, both ways (a fault injector). Called
    /// under the lock, in order: to_device with the bytes of one request as they came off
    /// the line (up to and including its delimiter; a request split across reads comes in
    /// pieces), before the emulator sees them; then to_host with the emulator's answer to
    /// them (COBS frames with their delimiters; empty when it answered nothing), before they
    /// are written. Each may change its bytes in any way. Either may be empty.
    struct LineTap {
        std::function<void(std::vector<std::byte>& bytes)> to_device;
        std::function<void(std::vector<std::byte>& bytes)> to_host;
    };

    void set_request_hook(RequestHook hook);
    void set_line_tap(LineTap tap);
    /// false: read and drop every byte the host sends, answer nothing (a silent device on a
    /// live line). true (the default): answer.
    void set_answering(bool answering);
    /// Bytes onto the line from the device's side, as one write (between replies).
    void write_raw(std::span<const std::byte> bytes);

    /// Stops serving and closes the master: the host's descriptor hangs up.
    void hang_up();
    /// Serves the same emulator (same serial number, physics continuing) on a new pair and
    /// re-points the symlink. The host reconnects by reopening port().
    void plug_in();

    /// Bytes received from the host so far; requests (frames) the emulator handled so far.
    std::uint64_t bytes_received() const noexcept { return bytes_received_.load(); }
    std::uint64_t requests() const noexcept { return requests_.load(); }
    /// Waits until requests() >= n, at most `timeout_ms`; false on timeout.
    bool wait_for_requests(std::uint64_t n, int timeout_ms);

  private:
    void start();
    void stop();
    void serve();
    /// One request's bytes (up to and including its delimiter) through the emulator.
    void handle(std::span<const std::byte> bytes);
    void write_all(std::span<const std::byte> bytes);

    device::protocol::DeviceEmulator emulator_;
    std::string stable_path_;
    std::unique_ptr<PtyPair> pair_;
    int wake_read_ = -1;
    int wake_write_ = -1;
    std::thread thread_;
    std::atomic<bool> stop_{false};

    std::mutex mutex_;  // emulator_, hook_, answering_, writes to the master
    std::condition_variable served_;
    RequestHook hook_;
    LineTap tap_;
    bool answering_ = true;
    std::atomic<std::uint64_t> bytes_received_{0};
    std::atomic<std::uint64_t> requests_{0};
    std::vector<std::byte> reply_;
    std::vector<std::byte> tapped_;  // the bytes a line tap passes on
};

}  // namespace hapticd::testing
