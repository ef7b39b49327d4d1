// HID report wrapping (docs/protocol.md section 6.2).
#include "hapticd/device/protocol/transport.hpp"

#include <algorithm>

namespace hapticd::device::protocol::hid {

Encoded wrap_report(std::uint8_t report_id, std::span<const std::byte> frame,
                    std::span<std::byte> out) noexcept {
    if (frame.size() > kReportDataSize) return {0, Error::bad_length};
    if (out.size() < kReportSize) return {0, Error::no_space};
    out[0] = std::byte{report_id};
    std::copy(frame.begin(), frame.end(), out.begin() + 1);
    std::fill(out.begin() + 1 + static_cast<std::ptrdiff_t>(frame.size()),
              out.begin() + static_cast<std::ptrdiff_t>(kReportSize), std::byte{0});
    return {kReportSize, Error::none};
}

Error unwrap_report(std::uint8_t expected_id, std::span<const std::byte> report,
                    std::span<const std::byte>& frame) noexcept {
    if (report.empty()) return Error::truncated;
    if (report[0] != std::byte{expected_id}) return Error::bad_report_id;
    const std::span<const std::byte> data = report.subspan(1);
    const std::size_t size = frame_size(data);
    frame = (size == 0 || size > data.size()) ? data : data.first(size);
    return Error::none;
}

}  // namespace hapticd::device::protocol::hid
