// How a frame travels on each transport (docs/protocol.md section 6). The serial byte stream
// has its own file (stream_framer.hpp); USB and HID need only the constants below and, for
// HID, a report ID in front of the frame and zero padding behind it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "hapticd/device/protocol/frame.hpp"

namespace hapticd::device::protocol {

/// The VID:PID the usb and hid plugins look for by default: pid.codes (https://pid.codes),
/// the open-source vendor ID, and its test PID 0x0001 — free for development and testing,
/// never for a shipped product (a lab that ships firmware asks pid.codes for its own PID and
/// sets device.usb.pid / device.hid.pid).
inline constexpr std::uint16_t kDevelopmentVendorId = 0x1209;
inline constexpr std::uint16_t kDevelopmentProductId = 0x0001;

/// 6.1 USB: a vendor-specific interface with one interrupt (or bulk) endpoint each way; one
/// frame per transfer, always a short packet (kMaxFrameSize < 64), so no zero-length packet.
namespace usb {
inline constexpr std::uint8_t kInterfaceClass = 0xFF;     ///< vendor-specific
inline constexpr std::uint8_t kInterfaceSubClass = 0x48;  ///< 'H'
inline constexpr std::uint8_t kInterfaceProtocol = 0x01;  ///< this protocol, any version
inline constexpr std::uint8_t kEndpointOut = 0x01;        ///< recommended address, host -> device
inline constexpr std::uint8_t kEndpointIn = 0x81;         ///< recommended address, device -> host
inline constexpr std::size_t kMaxPacketSize = 64;         ///< full speed
inline constexpr std::uint8_t kInterval = 1;              ///< bInterval, frames (1 ms)
static_assert(kMaxFrameSize < kMaxPacketSize, "a frame must be one short packet");
}  // namespace usb

/// 6.2 HID: 64-byte reports = report ID + 63 data bytes holding the frame, zero-padded.
namespace hid {
inline constexpr std::uint8_t kOutputReportId = 0x01;  ///< host -> device (output report)
inline constexpr std::uint8_t kInputReportId = 0x02;   ///< device -> host (input report)
inline constexpr std::size_t kReportDataSize = 63;
inline constexpr std::size_t kReportSize = 1 + kReportDataSize;  ///< as hidapi/hidraw see it
static_assert(kMaxFrameSize <= kReportDataSize);

/// The device's HID report descriptor: vendor page 0xFF00, usage 0x01; output report 1 and
/// input report 2 of 63 bytes each.
inline constexpr auto kReportDescriptor = std::to_array<std::uint8_t>({
    0x06, 0x00, 0xFF,  // Usage Page (Vendor Defined 0xFF00)
    0x09, 0x01,        // Usage (0x01)
    0xA1, 0x01,        // Collection (Application)
    0x15, 0x00,        //   Logical Minimum (0)
    0x26, 0xFF, 0x00,  //   Logical Maximum (255)
    0x75, 0x08,        //   Report Size (8)
    0x85, 0x01,        //   Report ID (1)
    0x95, 0x3F,        //   Report Count (63)
    0x09, 0x01,        //   Usage (0x01)
    0x91, 0x02,        //   Output (Data, Variable, Absolute)
    0x85, 0x02,        //   Report ID (2)
    0x95, 0x3F,        //   Report Count (63)
    0x09, 0x02,        //   Usage (0x02)
    0x81, 0x02,        //   Input (Data, Variable, Absolute)
    0xC0,              // End Collection
});

/// Writes [report_id, frame..., zeros] (kReportSize bytes) into `out`. no_space if `out` is
/// smaller than kReportSize, bad_length if the frame is larger than kReportDataSize.
Encoded wrap_report(std::uint8_t report_id, std::span<const std::byte> frame,
                    std::span<std::byte> out) noexcept;

/// The frame inside a report that starts with its report ID: checks the ID (bad_report_id;
/// truncated if the report is empty) and cuts the padding off using the frame's header
/// (frame_size()). When the header is unreadable, `frame` is all the data bytes, for
/// decode() to report what is wrong.
Error unwrap_report(std::uint8_t expected_id, std::span<const std::byte> report,
                    std::span<const std::byte>& frame) noexcept;
}  // namespace hid

}  // namespace hapticd::device::protocol
