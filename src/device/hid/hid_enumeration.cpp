// hidapi's enumeration as values, and the choice of a device (hid_enumeration.hpp,
// docs/transport-hid.md "Selecting the device").
#include "hapticd/device/hid/hid_enumeration.hpp"

#include <hidapi.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <system_error>
#include <type_traits>

namespace hapticd::device::hid {
namespace {

constexpr std::size_t kMaxListed = 16;  ///< devices named in a message before "and N more"

std::string quoted(const std::string& text) { return "\"" + text + "\""; }

std::string hex4(unsigned value) {
    char text[8];
    std::snprintf(text, sizeof text, "%04x", value & 0xFFFFu);
    return text;
}

std::string usage_text(std::uint32_t usage) {
    return hex4(usage >> 16) + ":" + hex4(usage & 0xFFFFu);
}

bool ids_match(const HidDeviceEntry& entry, const HidSettings& settings) {
    return (settings.vid == 0 || entry.vid == settings.vid) &&
           (settings.pid == 0 || entry.pid == settings.pid);
}

/// "  /dev/hidraw0 ...\n  /dev/hidraw1 ...": at most kMaxListed lines.
std::string listing(const std::vector<HidDeviceEntry>& entries) {
    std::string text;
    for (std::size_t i = 0; i < entries.size() && i < kMaxListed; ++i) {
        text += "\n  " + entries[i].describe();
    }
    if (entries.size() > kMaxListed) {
        text += "\n  and " + std::to_string(entries.size() - kMaxListed) + " more";
    }
    return text;
}

std::string wanted(const HidSettings& settings) {
    std::string text = "HID device " + hex_ids(settings.vid, settings.pid);
    if (!settings.serial_number.empty())
        text += " with serial number " + quoted(settings.serial_number);
    return text;
}

/// The same file: equal paths, or both resolve to the same node through symlinks.
bool same_node(const std::string& a, const std::string& b) {
    if (a == b) return true;
    std::error_code error;
    return std::filesystem::equivalent(a, b, error) && !error;
}

/// hidapi's library state, from the first enumeration until the plugin is unloaded: hid_exit
/// frees hidapi's static data. Without it LeakSanitizer found 144 bytes of hidapi's lost each
/// time the plugin was unloaded after an enumeration that found no device.
struct HidapiLifetime {
    HidapiLifetime() { (void)hid_init(); }
    ~HidapiLifetime() { (void)hid_exit(); }
    HidapiLifetime(const HidapiLifetime&) = delete;
    HidapiLifetime& operator=(const HidapiLifetime&) = delete;
};

}  // namespace

bool HidDeviceEntry::may_speak_protocol() const {
    if (usages.empty()) return true;
    const std::uint32_t ours = (std::uint32_t{kProtocolUsagePage} << 16) | kProtocolUsage;
    return std::find(usages.begin(), usages.end(), ours) != usages.end();
}

std::string HidDeviceEntry::describe() const {
    std::string text = path + " " + hex_ids(vid, pid);
    if (!product.empty()) text += " " + quoted(product);
    text += " serial " + (serial.empty() ? std::string("(none)") : quoted(serial));
    if (usages.empty()) {
        text += " usage (descriptor unreadable)";
    } else {
        text += " usage";
        for (const std::uint32_t usage : usages) text += " " + usage_text(usage);
    }
    return text;
}

std::string hex_ids(std::uint16_t vid, std::uint16_t pid) {
    return (vid == 0 ? std::string("any") : hex4(vid)) + ":" +
           (pid == 0 ? std::string("any") : hex4(pid));
}

std::string utf8_from_wide(const wchar_t* text) {
    std::string out;
    if (text == nullptr) return out;
    for (; *text != L'\0'; ++text) {
        // A code point (wchar_t is UTF-32 on Linux), as unsigned before it widens.
        const auto c =
            static_cast<std::uint32_t>(static_cast<std::make_unsigned_t<wchar_t>>(*text));
        if (c < 0x80) {
            out += static_cast<char>(c);
        } else if (c < 0x800) {
            out += static_cast<char>(0xC0 | (c >> 6));
            out += static_cast<char>(0x80 | (c & 0x3F));
        } else if (c < 0x10000) {
            out += static_cast<char>(0xE0 | (c >> 12));
            out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
            out += static_cast<char>(0x80 | (c & 0x3F));
        } else if (c < 0x110000) {
            out += static_cast<char>(0xF0 | (c >> 18));
            out += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
            out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
            out += static_cast<char>(0x80 | (c & 0x3F));
        } else {
            out += '?';
        }
    }
    return out;
}

std::vector<HidDeviceEntry> enumerate_hid_devices() {
    static const HidapiLifetime hidapi;  // thread-safe first use; destroyed at unload

    std::vector<HidDeviceEntry> entries;
    hid_device_info* const list = hid_enumerate(0, 0);
    // hidapi lists a node once per top-level collection (usage pair), all with one path.
    for (const hid_device_info* info = list; info != nullptr; info = info->next) {
        const std::string path = info->path != nullptr ? info->path : "";
        auto entry = std::find_if(entries.begin(), entries.end(),
                                  [&](const HidDeviceEntry& e) { return e.path == path; });
        if (entry == entries.end()) {
            HidDeviceEntry e;
            e.path = path;
            e.vid = info->vendor_id;
            e.pid = info->product_id;
            e.serial = utf8_from_wide(info->serial_number);
            e.manufacturer = utf8_from_wide(info->manufacturer_string);
            e.product = utf8_from_wide(info->product_string);
            e.interface_number = info->interface_number;
            entries.push_back(std::move(e));
            entry = entries.end() - 1;
        }
        if (info->usage_page != 0 || info->usage != 0) {
            entry->usages.push_back((std::uint32_t{info->usage_page} << 16) | info->usage);
        }
    }
    hid_free_enumeration(list);
    return entries;
}

HidDeviceEntry select_hid_device(const std::vector<HidDeviceEntry>& seen,
                                 const HidSettings& settings) {
    if (seen.empty()) {
        throw std::runtime_error(
            "hid: no " + wanted(settings) +
            ": there are no hidraw devices at all. Is it plugged in, and does its firmware "
            "enumerate as a HID device? (`ls /dev/hidraw*`, `dmesg | tail`; "
            "docs/transport-hid.md)");
    }
    std::vector<HidDeviceEntry> by_ids;
    for (const HidDeviceEntry& entry : seen) {
        if (ids_match(entry, settings)) by_ids.push_back(entry);
    }
    if (by_ids.empty()) {
        throw std::runtime_error(
            "hid: no " + wanted(settings) + " (" + settings.source +
            ": device.hid.vid, device.hid.pid); the hidraw devices are:" + listing(seen));
    }
    std::vector<HidDeviceEntry> by_usage;
    for (const HidDeviceEntry& entry : by_ids) {
        if (entry.may_speak_protocol()) by_usage.push_back(entry);
    }
    if (by_usage.empty()) {
        throw std::runtime_error(
            "hid: no " + wanted(settings) + " declares the protocol's collection (usage page " +
            hex4(kProtocolUsagePage) + ", usage " + hex4(kProtocolUsage) +
            ", docs/protocol.md 6.2); these have the ids but other collections:" + listing(by_ids));
    }
    std::vector<HidDeviceEntry> chosen;
    if (settings.serial_number.empty()) {
        chosen = by_usage;
    } else {
        for (const HidDeviceEntry& entry : by_usage) {
            if (entry.serial == settings.serial_number) chosen.push_back(entry);
        }
        if (chosen.empty()) {  // devices that report no HID serial may still be it
            for (const HidDeviceEntry& entry : by_usage) {
                if (entry.serial.empty()) chosen.push_back(entry);
            }
        }
        if (chosen.empty()) {
            throw std::runtime_error("hid: no " + wanted(settings) + " (" + settings.source +
                                     ": device.hid.serial_number); these have other serial "
                                     "numbers:" +
                                     listing(by_usage));
        }
    }
    if (chosen.size() > 1) {
        throw std::runtime_error(
            "hid: " + std::to_string(chosen.size()) + " devices match " + wanted(settings) +
            "; say which one with " + settings.source +
            ": device.hid.serial_number or device.hid.path:" + listing(chosen));
    }
    return chosen.front();
}

std::optional<HidDeviceEntry> check_configured_path(const std::vector<HidDeviceEntry>& seen,
                                                    const HidSettings& settings) {
    std::optional<HidDeviceEntry> found;
    for (const HidDeviceEntry& entry : seen) {
        if (entry.path == settings.path) found = entry;
    }
    if (!found) {
        for (const HidDeviceEntry& entry : seen) {
            if (same_node(entry.path, settings.path)) found = entry;
        }
    }
    if (!settings.ids_given) return found;
    if (!found) {
        throw std::runtime_error(
            "hid: " + settings.source + ": device.hid.path = " + quoted(settings.path) +
            " is not a hidraw device that hidapi lists, so it cannot be "
            "checked against device.hid.vid, device.hid.pid = " +
            hex_ids(settings.vid, settings.pid) + "; the hidraw devices are:" + listing(seen));
    }
    if (!ids_match(*found, settings)) {
        throw std::runtime_error(
            "hid: " + settings.source + ": device.hid.path = " + quoted(settings.path) + " is " +
            found->describe() +
            ", not device.hid.vid, device.hid.pid = " + hex_ids(settings.vid, settings.pid) +
            " (hidraw numbers change when devices are replugged: a udev "
            "SYMLINK is stable, docs/transport-hid.md)");
    }
    return found;
}

}  // namespace hapticd::device::hid
