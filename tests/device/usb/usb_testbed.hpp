// A USB device emulated by umockdev, for testing the `usb` plugin through unmodified libusb
// (docs/transport-usb.md, "Testing"). Reusable by any test that needs a hapticd protocol
// device on USB.
//
// How it works. umockdev's testbed (libumockdev) builds a fake sysfs and /dev in a temporary
// directory and exports UMOCKDEV_DIR; a process with libumockdev-preload.so in LD_PRELOAD
// (this test process, and the hapticd processes it starts, which inherit both variables) sees
// that sysfs and /dev instead of the real ones. For each emulated device the fixture adds
//   - a sysfs USB device with busnum, devnum, speed and the binary `descriptors` attribute
//     (device + configuration descriptor: one vendor interface ff/48/01 with an interrupt or
//     bulk endpoint pair 0x01 OUT / 0x81 IN, 64-byte packets, bInterval 1, transport.hpp),
//     which is all libusb's Linux backend reads to enumerate it; and
//   - a live ioctl handler (UMockdevIoctlBase, signal "handle-ioctl") on its usbfs node
//     /dev/bus/usb/BBB/DDD. The preload forwards every ioctl on that node over a socket to
//     umockdev's worker thread in this process, where the handler answers usbdevfs requests:
//     GET_CAPABILITIES, GETDRIVER (none), CLAIM/RELEASEINTERFACE, CLEAR_HALT, SETINTERFACE,
//     SUBMITURB, REAPURB/REAPURBNDELAY, DISCARDURB. The URB and its buffer are read from and
//     written to the client's memory through umockdev's IoctlData (cross-process).
// URBs: a control URB answers GET_DESCRIPTOR (strings, for the serial number); an OUT URB
// hands one frame to the DeviceEmulator (DeviceEmulator::handle) and completes at once; its
// reply frames are queued, one per IN transfer; an IN URB completes with the next queued
// frame, and stays pending while none is queued (as a real interrupt endpoint NAKs). An IN URB
// is never completed inside its own SUBMITURB (umockdev writes the resolved buffer back when
// an ioctl completes; usbfs touches the caller's buffer only at REAPURB), but at the next
// reap or OUT submit.
//
// Limits of the emulation (what a real bus does that this does not): the usbfs node is a
// regular file, so poll() always reports it ready and libusb busy-polls REAPURBNDELAY
// (about 0.1 ms per round trip) instead of sleeping; there is no POLLERR on unplug (the
// fixture completes the URBs in flight with -ENODEV instead, which libusb reports as
// LIBUSB_TRANSFER_NO_DEVICE, as it does on real hardware); there is no bus timing (a reply
// is ready as soon as its command is handled).
//
// Threads: the handler runs on umockdev's worker thread; every member function here may be
// called from any thread (a mutex per device guards the emulator and the URB queues).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "hapticd/device/protocol/device_emulator.hpp"
#include "pen_display_emulator.hpp"  // the device an EmulatedUsbDevice usually runs

namespace hapticd::testing {

struct UsbDeviceSpec {
    device::protocol::EmulatorConfig emulator;  ///< physics, identity, serial number
    std::uint16_t vendor_id = 0x1209;
    std::uint16_t product_id = 0x0001;
    /// iSerialNumber: nullopt: the emulator's serial number; "": the device has none.
    std::optional<std::string> usb_serial;
    std::uint8_t interface_class = 0xFF;
    std::uint8_t interface_subclass = 0x48;
    std::uint8_t interface_protocol = 0x01;
    bool bulk = false;  ///< bulk endpoints instead of interrupt ones
    std::uint16_t max_packet_size = 64;
};

/// URB traffic seen by one device, for assertions.
struct UrbCounts {
    std::uint64_t out_submitted = 0;  ///< OUT URBs (frames to the device)
    std::uint64_t in_submitted = 0;
    std::uint64_t in_completed = 0;  ///< IN URBs completed with data
    std::uint64_t control = 0;       ///< control URBs (descriptor requests)
    std::uint64_t discarded = 0;     ///< DISCARDURB that found its URB
    std::uint64_t clear_halts = 0;
    std::uint64_t claims = 0;
    std::uint64_t releases = 0;
    std::uint64_t busy_claims = 0;  ///< CLAIMINTERFACE refused: another file holds it
    std::uint64_t open_files = 0;   ///< files open on the usbfs node now
};

class UsbTestbed;

class EmulatedUsbDevice {
  public:
    /// Runs f(emulator) under the device's lock: set faults(), read its state.
    template <typename F>
    auto with_emulator(F&& f) {
        std::lock_guard lock(mutex_);
        return f(*emulator_);
    }

    /// The IN endpoint stalls: the IN URB pending now (or the next one) completes with -EPIPE,
    /// and so does every IN URB until the host clears the halt (USBDEVFS_CLEAR_HALT).
    void stall_in();
    /// The next OUT URB completes with -EPIPE (its frame is lost) and the OUT endpoint stays
    /// halted until the host clears it.
    void stall_out();
    /// The next IN completion carries `status` (a negative errno, e.g. -EPROTO) and no data.
    void fail_next_in(int status);
    /// Queues raw bytes as the next IN transfer's data (not a frame of the emulator's).
    void inject_in(std::vector<std::byte> bytes);
    /// The cable comes out right after the device has taken its `n`-th command (counting
    /// from the emulator's start), before it answers: deterministic against a running host.
    /// The device is then gone for every file (as UsbTestbed::unplug() says) but still in
    /// sysfs until the test calls UsbTestbed::unplug() (wait for plugged() to turn false).
    void unplug_at_command(std::uint64_t n);

    UrbCounts counts() const;
    bool in_halted() const;
    bool out_halted() const;
    bool plugged() const;
    int bus() const;
    int address() const;
    std::string devnode() const;  ///< /dev/bus/usb/BBB/DDD
    std::string syspath() const;  ///< /sys/devices/...
    const UsbDeviceSpec& spec() const { return spec_; }

  private:
    friend class UsbTestbed;
    struct Client;
    struct Handler;

    EmulatedUsbDevice(UsbDeviceSpec spec, int port);

    UsbDeviceSpec spec_;
    int port_;
    mutable std::mutex mutex_;
    std::unique_ptr<device::protocol::DeviceEmulator> emulator_;
    std::shared_ptr<Handler> handler_;
    int address_ = 0;
    bool plugged_ = false;
};

class UsbTestbed {
  public:
    /// Creates the testbed. Throws std::runtime_error if libumockdev-preload is not in
    /// LD_PRELOAD (run the test through ctest, or umockdev-wrapper).
    UsbTestbed();
    ~UsbTestbed();
    UsbTestbed(const UsbTestbed&) = delete;
    UsbTestbed& operator=(const UsbTestbed&) = delete;

    /// Plugs in a new device (bus 1, the next free address).
    EmulatedUsbDevice& add(UsbDeviceSpec spec = {});
    /// The cable comes out: URBs in flight complete with -ENODEV, every later ioctl on a file
    /// opened before answers ENODEV, and the device leaves sysfs (enumeration loses it). After
    /// unplug_at_command() has fired, only the last part is left to do.
    void unplug(EmulatedUsbDevice& device);
    /// Back in, at a new device address (as the kernel assigns one), with a new emulator from
    /// the spec (a USB reset: no session, zero force) unless `fresh_emulator` is false.
    void replug(EmulatedUsbDevice& device, bool fresh_emulator = true);
    /// Lets other users use the testbed (it is private to its creator by default), so that a
    /// process running as `nobody` meets the device node's permissions (root's, 0644): EACCES
    /// on open, as on a machine without the udev rule.
    void open_to_other_users();

    const std::string& root_dir() const { return root_dir_; }
    static bool preload_active();

  private:
    friend class EmulatedUsbDevice;
    void add_to_sysfs(EmulatedUsbDevice& device);

    struct Impl;
    std::unique_ptr<Impl> impl_;
    std::string root_dir_;
    std::vector<std::unique_ptr<EmulatedUsbDevice>> devices_;
    int next_address_ = 2;  ///< 1 is the root hub
};

}  // namespace hapticd::testing
