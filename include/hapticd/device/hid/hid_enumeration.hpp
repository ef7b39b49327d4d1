// Which hidraw node to open (docs/transport-hid.md, "Selecting the device"): hidapi's
// enumeration turned into plain values, and the choice among them by the [device.hid] keys.
// Outside the tick only: everything here allocates and throws.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hapticd/device/hid/hid_settings.hpp"

namespace hapticd::device::hid {

/// The top-level collection a hapticd protocol device declares (docs/protocol.md 6.2).
inline constexpr std::uint16_t kProtocolUsagePage = 0xFF00;
inline constexpr std::uint16_t kProtocolUsage = 0x01;

/// One hidraw node as hidapi's hidraw backend sees it (udev: the hidraw device's parent
/// "hid" device's HID_ID, HID_NAME, HID_UNIQ; the usages from its sysfs report_descriptor).
struct HidDeviceEntry {
    std::string path;  ///< "/dev/hidraw3"
    std::uint16_t vid = 0;
    std::uint16_t pid = 0;
    std::string serial;  ///< HID_UNIQ (UTF-8); empty when the device reports none
    std::string manufacturer;
    std::string product;
    int interface_number = -1;  ///< USB interface, -1 when not USB
    /// The usage pairs of its top-level collections, (page << 16) | usage, in descriptor
    /// order; empty when hidapi could not read the report descriptor.
    std::vector<std::uint32_t> usages;

    /// Declares the protocol's collection, or does not say (its descriptor was unreadable).
    bool may_speak_protocol() const;
    /// "/dev/hidraw3 1209:4841 "hapticd paddle" serial "HX-0001" usage ff00:0001".
    std::string describe() const;
};

/// Every hidraw node, one entry per path (hid_enumerate(0, 0)). Calls hid_init() first.
std::vector<HidDeviceEntry> enumerate_hid_devices();

/// The device the settings select among `seen` (settings.path must be empty): vid and pid
/// (0 matches any), then the protocol's collection where the descriptor says, then the
/// serial number where the device reports one (an exact match wins over a device that
/// reports none). Throws std::runtime_error: nothing matches (the message lists what was
/// seen and why each candidate was passed over), or several do (it lists them and asks for
/// serial_number or path).
HidDeviceEntry select_hid_device(const std::vector<HidDeviceEntry>& seen,
                                 const HidSettings& settings);

/// With settings.path: the entry of that node (compared by path, then through symlinks),
/// or nullopt when hidapi does not list it. Throws std::runtime_error when vid/pid were
/// given too and the node is another device, or is not listed (so cannot be checked).
std::optional<HidDeviceEntry> check_configured_path(const std::vector<HidDeviceEntry>& seen,
                                                    const HidSettings& settings);

/// "1209:4841" (lower-case hex, 4 digits each); 0 prints as "any".
std::string hex_ids(std::uint16_t vid, std::uint16_t pid);

/// A wide string from hidapi as UTF-8 ("" for null).
std::string utf8_from_wide(const wchar_t* text);

}  // namespace hapticd::device::hid
