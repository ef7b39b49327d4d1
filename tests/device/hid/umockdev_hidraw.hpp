// Emulated hidraw nodes for tests through hidapi's real hidraw backend (docs/transport-hid.md,
// "How it is tested"). A umockdev testbed holds, per device, the sysfs tree hidapi's
// enumeration walks through libudev:
//
//   /sys/devices/usbN/N-1               subsystem usb, DEVTYPE=usb_device (idVendor,
//                                        idProduct, manufacturer, product, serial)
//     N-1:1.0                           subsystem usb, DEVTYPE=usb_interface (bInterfaceNumber)
//       0003:VVVV:PPPP.000K             subsystem hid: uevent HID_ID, HID_NAME, HID_UNIQ;
//                                        report_descriptor (binary)
//         hidraw/hidrawK                subsystem hidraw: dev, DEVNAME=/dev/hidrawK; the
//                                        `device` link to its hid parent (hidapi reads
//                                        <hidraw>/device/report_descriptor)
//
// and the node /dev/hidrawK, a symlink to the slave of a pseudo-terminal that this class
// owns (umockdev creates no node for a device added this way). The pty is raw with VMIN = 64,
// so a client's read() and poll() see whole 64-byte reports, as on hidraw; the test side
// reads output reports from and writes input reports to master_fd(). The class keeps the
// slave open itself, flock()ed, while the node is plugged: the master does not hang up
// between clients, and a serial host of another test that reconnects to a stale /dev/pts/N
// which this pty now has backs off instead of reconfiguring and flushing it (plug()). The
// ioctls hidapi needs (HIDIOCGRDESCSIZE in hid_open_path, also HIDIOCGRDESC and
// HIDIOCGRAWINFO) are answered by a umockdev ioctl handler ("handle-ioctl", umockdev >= 0.16)
// on umockdev's own thread; reads and writes go to the pty (each after a round trip to that
// thread, which asks the handler first: hid_device_server.hpp, "Timing").
//
// plug() makes the ioctl handler, then the node, then the sysfs tree, so that a client that
// enumerates meanwhile (a reconnecting plugin) finds either nothing or a node it can open.
// unplug() removes the sysfs tree, then the node, and closes the pty master (the ioctl
// handler stays, for clients that still hold the node): a client's poll() gets POLLHUP and
// its write() EIO, as from a removed hidraw node (whose write() says ENODEV). plug() again
// adds it back, under the same or another hidrawK.
//
// The process that uses the node must run with libumockdev-preload (umockdev-wrapper, or
// LD_PRELOAD=libumockdev-preload.so.0) and the testbed's UMOCKDEV_DIR, which the constructor
// sets in the environment, so that child processes inherit both.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace hapticd::testing {

/// One emulated USB HID device with a single hidraw node.
struct HidrawNodeSpec {
    std::uint16_t vid = 0x1209;
    std::uint16_t pid = 0x4841;
    std::string serial = "EMU-0001";  ///< HID_UNIQ and the USB device's `serial`; "" for none
    std::string manufacturer = "hapticd";
    std::string product = "hapticd emulated device";
    std::vector<std::uint8_t> report_descriptor;  ///< empty: hid::kReportDescriptor
    int hidraw_number = 0;                        ///< /dev/hidraw<number>
};

class UmockdevHidraw {
  public:
    /// A new, empty testbed. Throws std::runtime_error when the process does not run under
    /// libumockdev-preload (the message says how to run it).
    UmockdevHidraw();
    ~UmockdevHidraw();

    UmockdevHidraw(const UmockdevHidraw&) = delete;
    UmockdevHidraw& operator=(const UmockdevHidraw&) = delete;

    /// Adds a device and its node; returns the node's index for the calls below.
    int plug(const HidrawNodeSpec& spec);
    /// Removes the device's sysfs tree and node and hangs its pty up. Idempotent.
    void unplug(int node);

    bool plugged(int node) const;
    std::string devnode(int node) const;  ///< "/dev/hidraw0"
    /// The pty master: read output reports, write input reports. -1 when unplugged.
    int master_fd(int node) const;
    const HidrawNodeSpec& spec(int node) const;
    /// $UMOCKDEV_DIR of the testbed (a child process needs it with the preload library).
    std::string root_dir() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// True when this process runs with libumockdev-preload and a testbed exists.
bool in_umockdev_environment();

}  // namespace hapticd::testing
