// The [device.hid] keys (hid_settings.hpp, docs/transport-hid.md).
#include "hapticd/device/hid/hid_settings.hpp"

namespace hapticd::device::hid {

HidSettings read_hid_settings(TableReader& table, const link::LinkContext& context) {
    HidSettings settings;
    settings.source = table.source();
    settings.serial_number = context.settings.serial_number;

    const bool has_vid = table.has("vid");
    const bool has_pid = table.has("pid");
    settings.vid =
        static_cast<std::uint16_t>(table.read(input::Integer{"vid", 0, 0xFFFF, settings.vid}));
    settings.pid =
        static_cast<std::uint16_t>(table.read(input::Integer{"pid", 0, 0xFFFF, settings.pid}));
    settings.ids_given = has_vid && has_pid;
    if (has_vid != has_pid) {
        const char* missing = has_vid ? "pid" : "vid";
        table.fail(missing, std::string("is missing: required with ") + (has_vid ? "vid" : "pid") +
                                ", the device's USB vendor and product id go together, e.g. "
                                "vid = 0x1209, pid = 0x0001 (0 matches any)");
    }

    settings.path =
        table.read(input::Text{"path", "", false,
                               "a hidraw node, e.g. \"/dev/hidraw3\", or none to find the device "
                               "by vid and pid"});
    return settings;
}

}  // namespace hapticd::device::hid
