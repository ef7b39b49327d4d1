// The `usb` plugin's link factory (make_usb_link.hpp).
#include "hapticd/device/usb/make_usb_link.hpp"

#include "hapticd/device/usb/usb_link.hpp"
#include "hapticd/device/usb/usb_settings.hpp"

namespace hapticd::device::usb {

std::unique_ptr<link::FrameLink> make_usb_link(TableReader& table,
                                               const link::LinkContext& context) {
    return std::make_unique<UsbLink>(read_usb_settings(table, context.settings.serial_number));
}

}  // namespace hapticd::device::usb
