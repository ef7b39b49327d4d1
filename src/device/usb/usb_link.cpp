// The `usb` transport: protocol frames over libusb (usb_link.hpp, docs/transport-usb.md,
// docs/protocol.md 6.1).
#include "hapticd/device/usb/usb_link.hpp"

#include <sys/time.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <new>
#include <stdexcept>
#include <utility>

#include "hapticd/device/usb/usb_discovery.hpp"

namespace hapticd::device::usb {
namespace {

using link::LinkResult;

std::string error_text(int code) { return libusb_strerror(code); }

std::string endpoint_text(std::uint8_t address) {
    std::array<char, 16> text{};
    std::snprintf(text.data(), text.size(), "endpoint 0x%02x", address);
    return text.data();
}

void fill_transfer(libusb_transfer* transfer, libusb_device_handle* handle,
                   const UsbEndpoint& endpoint, unsigned char* buffer, int length,
                   libusb_transfer_cb_fn callback, void* user_data, unsigned timeout_ms) {
    libusb_fill_bulk_transfer(transfer, handle, endpoint.address, buffer, length, callback,
                              user_data, timeout_ms);
    transfer->type = endpoint.transfer_type;  // bulk or interrupt: the same fields
}

}  // namespace

UsbLink::UsbLink(UsbSettings settings) : settings_(std::move(settings)) {}

UsbLink::~UsbLink() { close(); }

void UsbLink::open() {
    close();
    try {
        open_device();
        allocate_transfers();
        if (!submit_in()) {
            throw std::runtime_error(describe() + ": cannot submit a transfer on " +
                                     endpoint_text(endpoints_.in.address));
        }
    } catch (...) {
        release();
        throw;
    }
    if (opened_before_) count(counts_.reopens);
    opened_before_ = true;
}

void UsbLink::open_device() {
    // A context of our own per open(): a fresh enumeration on every reconnect attempt,
    // whether or not libusb's hotplug monitor saw the device come back.
    int result = libusb_init(&context_);
    if (result != LIBUSB_SUCCESS) {
        context_ = nullptr;
        throw std::runtime_error("usb: libusb_init failed: " + error_text(result));
    }
    FoundDevice found = find_device(context_, settings_);
    handle_ = found.handle;
    bus_ = found.bus;
    address_ = found.address;
    usb_serial_ = found.usb_serial;

    libusb_config_descriptor* config = nullptr;
    result = libusb_get_active_config_descriptor(libusb_get_device(handle_), &config);
    if (result != LIBUSB_SUCCESS) {
        throw std::runtime_error(
            describe() + ": cannot read its configuration descriptor: " + error_text(result));
    }
    try {
        endpoints_ = select_endpoints(*config, settings_, describe());
    } catch (...) {
        libusb_free_config_descriptor(config);
        throw;
    }
    libusb_free_config_descriptor(config);

    const int interface = endpoints_.interface_number;
    const std::string interface_text = describe() + " interface " + std::to_string(interface);
    if (libusb_kernel_driver_active(handle_, interface) == 1) {
        result = libusb_detach_kernel_driver(handle_, interface);
        if (result != LIBUSB_SUCCESS) {
            throw std::runtime_error(
                interface_text +
                " is bound to a kernel driver that could not be detached: " + error_text(result));
        }
    }
    result = libusb_claim_interface(handle_, interface);
    if (result == LIBUSB_ERROR_BUSY) {
        throw std::runtime_error(interface_text +
                                 " is in use by another program (another hapticd? `sudo lsof " +
                                 usbfs_node(bus_, address_) + "` names it)");
    }
    if (result != LIBUSB_SUCCESS) {
        throw std::runtime_error("cannot claim " + interface_text + ": " + error_text(result));
    }
    claimed_ = true;
    if (endpoints_.alt_setting != 0) {
        result = libusb_set_interface_alt_setting(handle_, interface, endpoints_.alt_setting);
        if (result != LIBUSB_SUCCESS) {
            throw std::runtime_error("cannot select " + interface_text + " alternate setting " +
                                     std::to_string(endpoints_.alt_setting) + ": " +
                                     error_text(result));
        }
    }
    // A fresh start on both endpoints (data toggles reset, any halt from before cleared); this
    // is also where a stall seen in the tick is cleared (usb_link.hpp).
    for (const UsbEndpoint* endpoint : {&endpoints_.in, &endpoints_.out}) {
        result = libusb_clear_halt(handle_, endpoint->address);
        if (result != LIBUSB_SUCCESS) {
            throw std::runtime_error(describe() + ": cannot clear the halt of " +
                                     endpoint_text(endpoint->address) + ": " + error_text(result));
        }
    }
}

void UsbLink::allocate_transfers() {
    in_transfer_ = libusb_alloc_transfer(0);
    if (in_transfer_ == nullptr) throw std::bad_alloc();
    fill_transfer(in_transfer_, handle_, endpoints_.in, in_buffer_.data(),
                  static_cast<int>(in_buffer_.size()), &UsbLink::on_in_complete, this, 0);
    for (OutSlot& slot : out_) {
        slot.transfer = libusb_alloc_transfer(0);
        if (slot.transfer == nullptr) throw std::bad_alloc();
        fill_transfer(slot.transfer, handle_, endpoints_.out, slot.buffer.data(), 0,
                      &UsbLink::on_out_complete, this, kOutTimeoutMs);
        slot.busy = false;
    }
}

void UsbLink::close() noexcept { release(); }

void UsbLink::release() noexcept {
    if (handle_ != nullptr) {
        // Cancel what is in flight and wait for the callbacks. A transfer whose cancellation
        // says the device is gone is not waited for: libusb_close() drops it.
        if (in_submitted_) {
            const int result = libusb_cancel_transfer(in_transfer_);
            if (result == LIBUSB_ERROR_NO_DEVICE) in_submitted_ = false;
        }
        for (OutSlot& slot : out_) {
            if (!slot.busy) continue;
            if (libusb_cancel_transfer(slot.transfer) == LIBUSB_ERROR_NO_DEVICE) slot.busy = false;
        }
        const std::int64_t deadline = link::monotonic_now_ns() + kCancelWaitNs;
        while (transfers_in_flight() && link::monotonic_now_ns() < deadline) {
            if (handle_events(10'000'000, nullptr) < 0) break;
        }
        if (claimed_) (void)libusb_release_interface(handle_, endpoints_.interface_number);
        libusb_close(handle_);
    }
    // After libusb_close() no transfer of this handle is in flight any more: free them all.
    if (in_transfer_ != nullptr) libusb_free_transfer(in_transfer_);
    in_transfer_ = nullptr;
    for (OutSlot& slot : out_) {
        if (slot.transfer != nullptr) libusb_free_transfer(slot.transfer);
        slot.transfer = nullptr;
        slot.busy = false;
    }
    if (context_ != nullptr) libusb_exit(context_);
    context_ = nullptr;
    handle_ = nullptr;
    claimed_ = false;
    in_submitted_ = false;
    in_completed_ = 0;
    gone_ = false;
    halted_ = false;
}

bool UsbLink::transfers_in_flight() const noexcept {
    if (in_submitted_) return true;
    return std::any_of(out_.begin(), out_.end(), [](const OutSlot& slot) { return slot.busy; });
}

void LIBUSB_CALL UsbLink::on_in_complete(libusb_transfer* transfer) {
    auto* self = static_cast<UsbLink*>(transfer->user_data);
    self->in_status_ = transfer->status;
    self->in_length_ = transfer->actual_length;
    self->in_submitted_ = false;  // no longer in flight
    self->in_completed_ = 1;
}

void LIBUSB_CALL UsbLink::on_out_complete(libusb_transfer* transfer) {
    auto* self = static_cast<UsbLink*>(transfer->user_data);
    for (OutSlot& slot : self->out_) {
        if (slot.transfer == transfer) slot.busy = false;
    }
    switch (transfer->status) {
        case LIBUSB_TRANSFER_COMPLETED:
        case LIBUSB_TRANSFER_CANCELLED:  // close()
            break;
        case LIBUSB_TRANSFER_NO_DEVICE:
            self->gone_ = true;
            break;
        case LIBUSB_TRANSFER_STALL:
            self->halted_ = true;
            self->count(self->counts_.stalls);
            break;
        case LIBUSB_TRANSFER_TIMED_OUT:  // the device did not take the frame in kOutTimeoutMs
        case LIBUSB_TRANSFER_ERROR:
        case LIBUSB_TRANSFER_OVERFLOW:
            self->count(self->counts_.send_errors);
            break;
    }
}

bool UsbLink::submit_in() noexcept {
    in_completed_ = 0;
    const int result = libusb_submit_transfer(in_transfer_);
    if (result == LIBUSB_SUCCESS) {
        in_submitted_ = true;
        return true;
    }
    if (result == LIBUSB_ERROR_NO_DEVICE) {
        gone_ = true;
    } else if (result == LIBUSB_ERROR_PIPE) {
        halted_ = true;
        count(counts_.stalls);
    } else {
        count(counts_.receive_errors);
    }
    return false;
}

int UsbLink::handle_events(std::int64_t timeout_ns, int* completed) noexcept {
    const std::int64_t us = timeout_ns <= 0 ? 0 : (timeout_ns + 999) / 1000;
    timeval timeout{};
    timeout.tv_sec = static_cast<time_t>(us / 1'000'000);
    timeout.tv_usec = static_cast<suseconds_t>(us % 1'000'000);
    const int result = libusb_handle_events_timeout_completed(context_, &timeout, completed);
    return result == LIBUSB_ERROR_INTERRUPTED ? 0 : result;
}

LinkResult UsbLink::send(std::span<const std::byte> frame) noexcept {
    if (handle_ == nullptr || gone_ || halted_) return LinkResult::disconnected;
    if (frame.size() > Buffer{}.size()) {
        count(counts_.send_errors);
        return LinkResult::error;
    }
    auto free_slot = [this] {
        return std::find_if(out_.begin(), out_.end(), [](const OutSlot& s) { return !s.busy; });
    };
    auto slot = free_slot();
    if (slot == out_.end()) {
        // Collect completions that have not been handled yet (no receive() since).
        (void)handle_events(0, nullptr);
        if (gone_ || halted_) return LinkResult::disconnected;
        slot = free_slot();
        if (slot == out_.end()) {  // the device has not taken kOutTransfers frames
            count(counts_.send_errors);
            return LinkResult::error;
        }
    }
    std::memcpy(slot->buffer.data(), frame.data(), frame.size());
    slot->transfer->length = static_cast<int>(frame.size());
    const int result = libusb_submit_transfer(slot->transfer);
    if (result == LIBUSB_SUCCESS) {
        slot->busy = true;
        count(counts_.frames_sent);
        return LinkResult::ok;
    }
    if (result == LIBUSB_ERROR_NO_DEVICE) {
        gone_ = true;
        return LinkResult::disconnected;
    }
    if (result == LIBUSB_ERROR_PIPE) {
        halted_ = true;
        count(counts_.stalls);
        return LinkResult::disconnected;
    }
    count(counts_.send_errors);
    return LinkResult::error;
}

LinkResult UsbLink::receive(std::span<std::byte> frame, std::size_t& size,
                            std::int64_t deadline_ns) noexcept {
    if (handle_ == nullptr) return LinkResult::disconnected;
    bool last_pass = false;
    for (;;) {
        if (in_completed_ != 0) {
            in_completed_ = 0;
            switch (in_status_) {
                case LIBUSB_TRANSFER_COMPLETED: {
                    const auto length = static_cast<std::size_t>(in_length_);
                    if (length == 0 || length > protocol::kMaxFrameSize || length > frame.size()) {
                        count(counts_.framing_errors);  // not a frame (6.1): skip it
                        continue;
                    }
                    std::memcpy(frame.data(), in_buffer_.data(), length);  // before resubmitting
                    // Keep the IN transfer submitted. If the device is gone by now, say so at
                    // once rather than hand up its last frame: the servo then zeroes the force
                    // before it computes and sends another one to nobody.
                    if (!submit_in() && (gone_ || halted_)) return LinkResult::disconnected;
                    size = length;
                    count(counts_.frames_received);
                    return LinkResult::ok;
                }
                case LIBUSB_TRANSFER_NO_DEVICE:
                    gone_ = true;
                    return LinkResult::disconnected;
                case LIBUSB_TRANSFER_STALL:
                    halted_ = true;
                    count(counts_.stalls);
                    return LinkResult::disconnected;
                case LIBUSB_TRANSFER_OVERFLOW:  // more than a packet: not a frame
                    count(counts_.framing_errors);
                    continue;
                case LIBUSB_TRANSFER_CANCELLED:
                case LIBUSB_TRANSFER_TIMED_OUT:
                    continue;  // resubmitted below
                case LIBUSB_TRANSFER_ERROR:
                    count(counts_.receive_errors);
                    (void)submit_in();
                    return LinkResult::error;
            }
            continue;
        }
        if (gone_ || halted_) return LinkResult::disconnected;
        if (!in_submitted_ && !submit_in()) {
            return gone_ || halted_ ? LinkResult::disconnected : LinkResult::error;
        }
        if (last_pass) return LinkResult::timeout;
        const std::int64_t remaining_ns = deadline_ns - link::monotonic_now_ns();
        last_pass = remaining_ns <= 0;
        if (handle_events(remaining_ns, &in_completed_) < 0) {
            count(counts_.receive_errors);
            return LinkResult::error;
        }
    }
}

void UsbLink::discard_input() noexcept {
    if (handle_ == nullptr) return;
    // Whatever already completed is stale (before a handshake): drop it and resubmit, until
    // a pass of event handling brings nothing more. Bounded: a device that streams without
    // being asked is not waited out.
    for (int round = 0; round < 64 && !gone_ && !halted_; ++round) {
        if (in_completed_ != 0) {
            in_completed_ = 0;
            if (in_status_ == LIBUSB_TRANSFER_NO_DEVICE) gone_ = true;
            if (in_status_ == LIBUSB_TRANSFER_STALL) {
                halted_ = true;
                count(counts_.stalls);
            }
            continue;
        }
        if (!in_submitted_ && !submit_in()) return;
        if (handle_events(0, &in_completed_) < 0 || in_completed_ == 0) return;
    }
}

std::string UsbLink::describe() const {
    std::string text = "usb " + vid_pid_text(settings_.vendor_id, settings_.product_id);
    const std::string& serial = handle_ != nullptr ? usb_serial_ : settings_.serial_number;
    if (!serial.empty()) text += " serial " + serial;
    if (handle_ != nullptr) {
        text += " (bus " + std::to_string(bus_) + " device " + std::to_string(address_) + ")";
    }
    return text;
}

link::LinkCounters UsbLink::counters() const noexcept {
    link::LinkCounters c;
    c.frames_sent = counts_.frames_sent.load(std::memory_order_relaxed);
    c.frames_received = counts_.frames_received.load(std::memory_order_relaxed);
    c.send_errors = counts_.send_errors.load(std::memory_order_relaxed);
    c.receive_errors = counts_.receive_errors.load(std::memory_order_relaxed);
    c.framing_errors = counts_.framing_errors.load(std::memory_order_relaxed);
    c.stalls = counts_.stalls.load(std::memory_order_relaxed);
    c.reopens = counts_.reopens.load(std::memory_order_relaxed);
    return c;
}

}  // namespace hapticd::device::usb
