// The `usb` plugin's MakeLink (protocol_device.hpp): reads [device.usb]'s own keys and
// returns the unopened UsbLink. The plugin is ProtocolDevice("usb", make_usb_link).
#pragma once

#include <memory>

#include "hapticd/device/link/protocol_device.hpp"

namespace hapticd::device::usb {

std::unique_ptr<link::FrameLink> make_usb_link(TableReader& table,
                                               const link::LinkContext& context);

}  // namespace hapticd::device::usb
