// The Device interface (docs/architecture.md §4.1): what the servo loop reads and writes each
// tick.
//
// Units: encoder counts are integers, converted to metres with DeviceInfo::counts_per_meter;
// Command::force_n is the force the device applies to the handle along each +axis, in
// newtons. Every device plugin (sim, usb, hid, serial) implements this class and is loaded
// through the versioned C factory of plugin_abi.hpp.
//
// Real-time contract: read() and write() are called from the servo tick. They must not
// allocate, lock, log or throw; errors are returned as IoResult and status bits.
// link_quality() is the one function another thread may call while the tick runs.
#pragma once

#include <cstdint>
#include <string>

#include "hapticd/servo/io.hpp"
#include "hapticd/servo/rate.hpp"

namespace hapticd::device {

using servo::Command;
using servo::IoResult;
using servo::kMaxAxes;
using servo::Sample;

/// What a device says about itself; read once after open(), outside the tick.
struct DeviceInfo {
    int axes = 1;                   ///< 1..kMaxAxes Cartesian axes
    double counts_per_meter = 0.0;  ///< encoder resolution, counts/m, > 0
    double force_limit_n = 0.0;     ///< largest |force| per axis the device accepts, N
    /// True when read() itself paces the loop: it blocks until the device's next period
    /// (or, on a lockstep clock, returns the next virtual-time sample at once), so the loop
    /// must not also sleep to a deadline.
    bool paces_loop = false;
    bool lockstep = false;  ///< virtual time: sample times are exact multiples of T
    /// When the sample is taken. true: when read() is called (the sim): a loop that reads at
    /// the start of its tick computes each command from a fresh sample. false: when the
    /// device answers a command (the open protocol latches right after the command, or at
    /// its next period boundary), and read() returns it later.
    bool samples_at_read = false;
    /// The open protocol's version this session speaks (docs/protocol.md 3.2); 0 for a
    /// device that is not on the open protocol.
    int protocol_version = 0;
    std::string name;    ///< e.g. "sim", "usb"
    std::string serial;  ///< device serial number, if it has one
};

/// What the daemon passes to Device::open.
struct DeviceConfig {
    int axes = 1;                            ///< [device] axes
    double rate_hz = servo::kDefaultRateHz;  ///< [servo] rate_hz
    bool lockstep = false;  ///< hapticd --lockstep: virtual time, as fast as the CPU goes
    /// The plugin's own table, [device.<plugin>]: a TOML document (the daemon hands over the
    /// config file's own text, so that the plugin's messages carry its lines) and the
    /// table's dotted path in it ("device.sim"; empty: the document is the table). The plugin
    /// reads it with device::PluginTable, rejects unknown keys, and names `source` (the
    /// config file), the line and the key.
    std::string plugin_table_toml;
    std::string plugin_table_path;
    std::string source = "<config>";
};

/// How the link to the device is doing: counts since open(), for the operator (the control
/// socket's `status`, docs/control.md). Plain data of fixed size: it crosses the plugin ABI
/// (plugin_abi.hpp records its layout). A device that keeps no such counts (the sim) returns
/// it with counted = false and every count 0.
struct LinkQuality {
    bool counted = false;               ///< the device keeps these counts
    std::uint64_t frames_sent = 0;      ///< frames the transport sent (commands, polls)
    std::uint64_t frames_received = 0;  ///< whole frames the transport delimited
    std::uint64_t bad_frames = 0;       ///< frames that failed to decode (CRC, size, version,
                                        ///< field) plus the transport's framing errors
    std::uint64_t transfer_errors = 0;  ///< the transport's failed sends and receives
    std::uint64_t reply_timeouts = 0;   ///< reads that ended without a valid reply
    std::uint64_t missed_samples = 0;   ///< gaps in the device's sample sequence, summed
    std::uint64_t late = 0;             ///< replies to an earlier request, dropped
    std::uint64_t duplicate = 0;        ///< replies seen before, dropped
    std::uint64_t device_errors = 0;    ///< error reports from the device
    std::uint64_t disconnects = 0;      ///< times the device was lost
    std::uint64_t reconnects = 0;       ///< times it came back (a new session)
    std::uint64_t wrong_session = 0;    ///< replies of another session (stale, or another
                                        ///< device's), dropped
    std::uint64_t unexpected = 0;       ///< replies to no request outstanding, dropped
    std::uint64_t out_of_step = 0;      ///< sessions ended because the device's samples all
                                        ///< came from behind ours
};

class Device {
  public:
    virtual ~Device() = default;
    /// Outside the tick. Throws std::runtime_error naming the file, key, value and allowed
    /// range on bad configuration, or saying why the device could not be opened.
    virtual void open(const DeviceConfig& config) = 0;
    virtual DeviceInfo info() const = 0;
    /// Tick: the next sample. No allocation, lock, log or throw.
    virtual IoResult read(Sample& sample) noexcept = 0;
    /// Tick: the force to hold until the next write. No allocation, lock, log or throw.
    virtual IoResult write(const Command& command) noexcept = 0;
    /// Leaves the device at zero force and releases it. Safe to call more than once and
    /// after a failed open().
    virtual void close() noexcept = 0;
    /// Any thread, also while the servo thread is in read() or write(), from open()'s return
    /// until the device is opened again or destroyed: the link's counts, which may be a tick
    /// old (each count is read on its own, so they need not be of the same instant). Must not
    /// block the tick: no lock the tick takes. The default: counted = false.
    virtual LinkQuality link_quality() const noexcept { return {}; }
};

}  // namespace hapticd::device
