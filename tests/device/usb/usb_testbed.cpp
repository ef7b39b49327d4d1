// The umockdev USB device emulation (usb_testbed.hpp).
#include "usb_testbed.hpp"

#include <linux/usbdevice_fs.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <umockdev.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <map>
#include <stdexcept>
#include <string_view>

namespace hapticd::testing {
namespace {

namespace proto = device::protocol;

constexpr int kBus = 1;
constexpr std::uint8_t kEndpointOut = 0x01;
constexpr std::uint8_t kEndpointIn = 0x81;
constexpr const char* kManufacturer = "hapticd";
constexpr const char* kProduct = "hapticd emulated device";

std::string hex(const std::vector<std::uint8_t>& bytes) {
    std::string text;
    std::array<char, 3> digits{};
    for (const std::uint8_t b : bytes) {
        std::snprintf(digits.data(), digits.size(), "%02x", b);
        text += digits.data();
    }
    return text;
}

std::string three_digits(int value) {
    std::array<char, 8> text{};
    std::snprintf(text.data(), text.size(), "%03d", value);
    return text.data();
}

// clang-format off
/// USB 2.0 9.6.1: the device descriptor.
std::vector<std::uint8_t> device_descriptor(const UsbDeviceSpec& spec, bool has_serial) {
    const auto lo = [](std::uint16_t v) { return static_cast<std::uint8_t>(v & 0xFF); };
    const auto hi = [](std::uint16_t v) { return static_cast<std::uint8_t>(v >> 8); };
    return {18, 1, 0x00, 0x02,                            // bLength, DEVICE, bcdUSB 2.00
            0, 0, 0, 64,                                  // class per interface; bMaxPacketSize0
            lo(spec.vendor_id), hi(spec.vendor_id), lo(spec.product_id), hi(spec.product_id),
            0x00, 0x01,                                   // bcdDevice 1.00
            1, 2, static_cast<std::uint8_t>(has_serial ? 3 : 0),  // iManufacturer, iProduct,
                                                                  // iSerialNumber
            1};                                           // bNumConfigurations
}

/// 9.6.3, 9.6.5, 9.6.6: one configuration, one interface, two endpoints (transport.hpp).
std::vector<std::uint8_t> configuration_descriptor(const UsbDeviceSpec& spec) {
    const std::uint8_t type = spec.bulk ? 0x02 : 0x03;
    const std::uint8_t interval = spec.bulk ? 0 : 1;
    const auto mps_lo = static_cast<std::uint8_t>(spec.max_packet_size & 0xFF);
    const auto mps_hi = static_cast<std::uint8_t>(spec.max_packet_size >> 8);
    return {9, 2, 32, 0, 1, 1, 0, 0x80, 50,               // 32 bytes, 1 interface, 100 mA
            9, 4, 0, 0, 2, spec.interface_class, spec.interface_subclass,
                spec.interface_protocol, 0,               // interface 0, 2 endpoints
            7, 5, kEndpointOut, type, mps_lo, mps_hi, interval,
            7, 5, kEndpointIn, type, mps_lo, mps_hi, interval};
}
// clang-format on

/// 9.6.7: a string descriptor (UTF-16LE of ASCII), or the language list for index 0.
std::vector<std::uint8_t> string_descriptor(int index, const std::string& text) {
    if (index == 0) return {4, 3, 0x09, 0x04};  // en-US
    std::vector<std::uint8_t> out{static_cast<std::uint8_t>(2 + 2 * text.size()), 3};
    for (const char c : text) {
        out.push_back(static_cast<std::uint8_t>(c));
        out.push_back(0);
    }
    return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The ioctl handler: one per device, on umockdev's worker thread, under the device's mutex.

struct EmulatedUsbDevice::Client {
    UMockdevIoctlClient* client = nullptr;      ///< a reference, so that its address is not reused
    int generation = 0;                         ///< the plug-in it was opened in
    std::deque<UMockdevIoctlData*> pending_in;  ///< IN URBs waiting for data (references)
    std::deque<UMockdevIoctlData*> done;        ///< completed URBs waiting for REAPURB
};

struct EmulatedUsbDevice::Handler {
    EmulatedUsbDevice* device = nullptr;
    UMockdevIoctlBase* base = nullptr;
    std::map<UMockdevIoctlClient*, Client> clients;
    std::deque<std::vector<std::byte>> replies;  ///< one IN transfer each
    int generation = 0;
    bool in_halted = false;
    bool out_halted = false;
    bool stall_out_next = false;
    std::optional<int> fail_next_in;
    std::optional<std::uint64_t> unplug_at_command;
    UMockdevIoctlClient* claimed_by = nullptr;  ///< the file that claimed interface 0
    UrbCounts counts;
    std::array<std::byte, proto::DeviceEmulator::kMaxReplySize> reply_buffer{};

    ~Handler() {
        for (auto& [key, client] : clients) drop(client);
        if (base != nullptr) g_object_unref(base);
    }

    static void drop(Client& client) {
        for (UMockdevIoctlData* data : client.pending_in) g_object_unref(data);
        for (UMockdevIoctlData* data : client.done) g_object_unref(data);
        client.pending_in.clear();
        client.done.clear();
        if (client.client != nullptr) g_object_unref(client.client);
        client.client = nullptr;
    }

    static void complete(UMockdevIoctlClient* client, int error) {
        umockdev_ioctl_client_complete(client, error == 0 ? 0 : -1, error);
    }

    Client& state_of(UMockdevIoctlClient* client) {
        auto found = clients.find(client);
        if (found == clients.end()) {
            g_object_ref(client);
            found = clients.emplace(client, Client{client, generation, {}, {}}).first;
        }
        return found->second;
    }

    bool alive(const Client& client) const {
        return device->plugged_ && client.generation == generation;
    }

    /// Completes the URB with `status`, moving it to the client's reap queue.
    static void finish(Client& client, UMockdevIoctlData* urb_data, int status, int length) {
        auto* urb = reinterpret_cast<usbdevfs_urb*>(urb_data->data);
        urb->status = status;
        urb->actual_length = length;
        client.done.push_back(urb_data);
    }

    /// Completes pending IN URBs while there is something to complete them with.
    void serve_in() {
        for (auto& [key, client] : clients) {
            if (!alive(client)) continue;
            while (!client.pending_in.empty()) {
                UMockdevIoctlData* urb_data = client.pending_in.front();
                auto* urb = reinterpret_cast<usbdevfs_urb*>(urb_data->data);
                if (in_halted) {
                    finish(client, urb_data, -EPIPE, 0);
                } else if (fail_next_in) {
                    finish(client, urb_data, *fail_next_in, 0);
                    fail_next_in.reset();
                } else if (!replies.empty()) {
                    const std::vector<std::byte>& reply = replies.front();
                    const int room = urb->buffer_length;
                    const int length = std::min(room, static_cast<int>(reply.size()));
                    if (length > 0) {  // an empty reply has no data() to copy from
                        std::memcpy(urb->buffer, reply.data(), static_cast<std::size_t>(length));
                    }
                    finish(client, urb_data, static_cast<int>(reply.size()) > room ? -EOVERFLOW : 0,
                           length);
                    replies.pop_front();
                    ++counts.in_completed;
                } else {
                    break;  // NAK: the URB stays pending
                }
                client.pending_in.pop_front();
            }
        }
    }

    void answer_control(usbdevfs_urb* urb) {
        auto* setup = static_cast<std::uint8_t*>(urb->buffer);
        const int request_type = setup[0];
        const int request = setup[1];
        const int value = setup[2] | (setup[3] << 8);
        const int length = setup[6] | (setup[7] << 8);
        std::vector<std::uint8_t> answer;
        const UsbDeviceSpec& spec = device->spec_;
        const std::string serial = spec.usb_serial.value_or(spec.emulator.serial_number);
        if (request_type == 0x80 && request == 6) {  // GET_DESCRIPTOR
            const int type = value >> 8;
            const int index = value & 0xFF;
            if (type == 1) answer = device_descriptor(spec, !serial.empty());
            if (type == 2) answer = configuration_descriptor(spec);
            if (type == 3 && index == 0) answer = string_descriptor(0, "");
            if (type == 3 && index == 1) answer = string_descriptor(1, kManufacturer);
            if (type == 3 && index == 2) answer = string_descriptor(2, kProduct);
            if (type == 3 && index == 3 && !serial.empty()) answer = string_descriptor(3, serial);
        }
        if (answer.empty()) {  // a request this device does not know: it stalls (9.2.7)
            urb->status = -EPIPE;
            urb->actual_length = 0;
            return;
        }
        const int n = std::min(length, static_cast<int>(answer.size()));
        std::memcpy(setup + 8, answer.data(), static_cast<std::size_t>(n));
        urb->status = 0;
        urb->actual_length = n;
    }

    void submit(UMockdevIoctlClient* ioctl_client, Client& client, UMockdevIoctlData* arg) {
        UMockdevIoctlData* urb_data =
            umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_urb), nullptr);
        auto* urb = reinterpret_cast<usbdevfs_urb*>(urb_data->data);
        if (urb->buffer_length > 0) {
            // Resolving replaces urb->buffer with a local copy that is written back on reap.
            UMockdevIoctlData* buffer =
                umockdev_ioctl_data_resolve(urb_data, offsetof(usbdevfs_urb, buffer),
                                            static_cast<gsize>(urb->buffer_length), nullptr);
            if (buffer != nullptr) g_object_unref(buffer);  // its parent keeps it
        }
        if (urb->type == USBDEVFS_URB_TYPE_CONTROL) {
            ++counts.control;
            answer_control(urb);
            client.done.push_back(urb_data);
        } else if ((urb->endpoint & 0x80) != 0) {
            // Not completed within its own SUBMITURB, even with a reply waiting: umockdev writes
            // the resolved buffer back when an ioctl completes, and usbfs never touches the
            // caller's buffer before REAPURB. It is served at the next reap.
            ++counts.in_submitted;
            client.pending_in.push_back(urb_data);
            complete(ioctl_client, 0);
            return;
        } else {
            ++counts.out_submitted;
            if (stall_out_next) {
                stall_out_next = false;
                out_halted = true;
            }
            if (out_halted) {
                finish(client, urb_data, -EPIPE, 0);
            } else {
                const auto* bytes = static_cast<const std::byte*>(urb->buffer);
                const proto::DeviceEmulator::Reply reply = device->emulator_->handle(
                    std::span<const std::byte>(bytes, static_cast<std::size_t>(urb->buffer_length)),
                    reply_buffer);
                std::size_t offset = 0;
                for (std::size_t i = 0; i < reply.frames; ++i) {
                    const std::size_t size = reply.frame_sizes[i];
                    replies.emplace_back(
                        reply_buffer.begin() + static_cast<std::ptrdiff_t>(offset),
                        reply_buffer.begin() + static_cast<std::ptrdiff_t>(offset + size));
                    offset += size;
                }
                finish(client, urb_data, 0, urb->buffer_length);
                if (unplug_at_command &&
                    device->emulator_->counters().commands_applied >= *unplug_at_command) {
                    unplug_at_command.reset();
                    pull_cable();  // the command went out; its reply does not come back
                }
            }
        }
        serve_in();
        complete(ioctl_client, 0);
    }

    /// The device is gone for every file: what is in flight fails with -ENODEV.
    void pull_cable() {
        device->plugged_ = false;
        for (auto& [key, client] : clients) {
            for (UMockdevIoctlData* urb : client.pending_in) finish(client, urb, -ENODEV, 0);
            client.pending_in.clear();
        }
        replies.clear();
        claimed_by = nullptr;
    }

    void reap(UMockdevIoctlClient* ioctl_client, Client& client, UMockdevIoctlData* arg,
              int empty_error) {
        serve_in();
        if (client.done.empty()) {
            complete(ioctl_client, empty_error);
            return;
        }
        UMockdevIoctlData* urb_data = client.done.front();
        client.done.pop_front();
        UMockdevIoctlData* slot = umockdev_ioctl_data_resolve(arg, 0, sizeof(void*), nullptr);
        umockdev_ioctl_data_set_ptr(slot, 0, urb_data);
        g_object_unref(slot);
        g_object_unref(urb_data);
        complete(ioctl_client, 0);
    }

    void discard(UMockdevIoctlClient* ioctl_client, Client& client, UMockdevIoctlData* arg) {
        const gulong address = *reinterpret_cast<const gulong*>(arg->data);
        const auto found = std::find_if(
            client.pending_in.begin(), client.pending_in.end(),
            [address](const UMockdevIoctlData* data) { return data->client_addr == address; });
        if (found == client.pending_in.end()) {  // already completed (or never submitted)
            complete(ioctl_client, EINVAL);
            return;
        }
        ++counts.discarded;
        finish(client, *found, -ENOENT, 0);
        client.pending_in.erase(found);
        complete(ioctl_client, 0);
    }

    unsigned int endpoint_arg(UMockdevIoctlData* arg) {
        UMockdevIoctlData* data =
            umockdev_ioctl_data_resolve(arg, 0, sizeof(unsigned int), nullptr);
        const unsigned int endpoint = *reinterpret_cast<const unsigned int*>(data->data);
        g_object_unref(data);
        return endpoint;
    }

    gboolean handle(UMockdevIoctlClient* ioctl_client) {
        const gulong request = umockdev_ioctl_client_get_request(ioctl_client);
        UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(ioctl_client);
        forget_closed_files();
        Client& client = state_of(ioctl_client);
        if (!alive(client)) {
            // Unplugged: what completed can still be reaped (USBDEVFS_CAP_REAP_AFTER_DISCONNECT),
            // everything else fails with ENODEV, as usbfs does.
            if (request == USBDEVFS_REAPURB || request == USBDEVFS_REAPURBNDELAY) {
                reap(ioctl_client, client, arg, ENODEV);
            } else {
                complete(ioctl_client, ENODEV);
            }
            return TRUE;
        }
        switch (request) {
            case USBDEVFS_GET_CAPABILITIES: {
                UMockdevIoctlData* data =
                    umockdev_ioctl_data_resolve(arg, 0, sizeof(guint32), nullptr);
                *reinterpret_cast<guint32*>(data->data) = USBDEVFS_CAP_BULK_CONTINUATION |
                                                          USBDEVFS_CAP_NO_PACKET_SIZE_LIM |
                                                          USBDEVFS_CAP_REAP_AFTER_DISCONNECT;
                g_object_unref(data);
                complete(ioctl_client, 0);
                return TRUE;
            }
            case USBDEVFS_GETDRIVER:
                complete(ioctl_client, ENODATA);  // no kernel driver on the interface
                return TRUE;
            case USBDEVFS_CLAIMINTERFACE:
                // One file at a time, as usbfs does (another hapticd has it: EBUSY).
                if (claimed_by != nullptr && claimed_by != ioctl_client) {
                    ++counts.busy_claims;
                    complete(ioctl_client, EBUSY);
                    return TRUE;
                }
                claimed_by = ioctl_client;
                ++counts.claims;
                complete(ioctl_client, 0);
                return TRUE;
            case USBDEVFS_RELEASEINTERFACE:
                if (claimed_by == ioctl_client) claimed_by = nullptr;
                ++counts.releases;
                complete(ioctl_client, 0);
                return TRUE;
            case USBDEVFS_CLEAR_HALT: {
                const unsigned int endpoint = endpoint_arg(arg);
                ((endpoint & 0x80) != 0 ? in_halted : out_halted) = false;
                ++counts.clear_halts;
                complete(ioctl_client, 0);
                return TRUE;
            }
            case USBDEVFS_SETINTERFACE:
            case USBDEVFS_RESET:
            case USBDEVFS_RESETEP:
                complete(ioctl_client, 0);
                return TRUE;
            case USBDEVFS_SUBMITURB:
                submit(ioctl_client, client, arg);
                return TRUE;
            case USBDEVFS_REAPURB:
            case USBDEVFS_REAPURBNDELAY:
                reap(ioctl_client, client, arg, EAGAIN);
                return TRUE;
            case USBDEVFS_DISCARDURB:
                discard(ioctl_client, client, arg);
                return TRUE;
            default:
                complete(ioctl_client, ENOTTY);
                return TRUE;
        }
    }

    static gboolean on_handle_ioctl(UMockdevIoctlBase* /*base*/, UMockdevIoctlClient* client,
                                    gpointer user_data) {
        auto* handler = static_cast<Handler*>(user_data);
        std::lock_guard lock(handler->device->mutex_);
        return handler->handle(client);
    }

    /// Forgets the files that were closed (umockdev 0.17 emits no "client-vanished"; a
    /// closed file shows as a client that is no longer connected).
    void forget_closed_files() {
        for (auto it = clients.begin(); it != clients.end();) {
            if (umockdev_ioctl_client_get_connected(it->first) != FALSE) {
                ++it;
                continue;
            }
            if (claimed_by == it->first) claimed_by = nullptr;
            drop(it->second);
            it = clients.erase(it);
        }
    }
};

// ---------------------------------------------------------------------------------------------

EmulatedUsbDevice::EmulatedUsbDevice(UsbDeviceSpec spec, int port)
    : spec_(std::move(spec)),
      port_(port),
      emulator_(std::make_unique<proto::DeviceEmulator>(spec_.emulator)),
      handler_(std::make_shared<Handler>()) {
    handler_->device = this;
    handler_->base = umockdev_ioctl_base_new();
    g_signal_connect(handler_->base, "handle-ioctl", G_CALLBACK(&Handler::on_handle_ioctl),
                     handler_.get());
}

void EmulatedUsbDevice::stall_in() {
    std::lock_guard lock(mutex_);
    handler_->in_halted = true;
    handler_->serve_in();
}

void EmulatedUsbDevice::stall_out() {
    std::lock_guard lock(mutex_);
    handler_->stall_out_next = true;
}

void EmulatedUsbDevice::fail_next_in(int status) {
    std::lock_guard lock(mutex_);
    handler_->fail_next_in = status;
    handler_->serve_in();
}

void EmulatedUsbDevice::unplug_at_command(std::uint64_t n) {
    std::lock_guard lock(mutex_);
    handler_->unplug_at_command = n;
}

void EmulatedUsbDevice::inject_in(std::vector<std::byte> bytes) {
    std::lock_guard lock(mutex_);
    handler_->replies.push_back(std::move(bytes));
    handler_->serve_in();
}

UrbCounts EmulatedUsbDevice::counts() const {
    std::lock_guard lock(mutex_);
    UrbCounts counts = handler_->counts;
    counts.open_files = static_cast<std::uint64_t>(
        std::count_if(handler_->clients.begin(), handler_->clients.end(), [](const auto& entry) {
            return umockdev_ioctl_client_get_connected(entry.second.client) != FALSE;
        }));
    return counts;
}

bool EmulatedUsbDevice::in_halted() const {
    std::lock_guard lock(mutex_);
    return handler_->in_halted;
}

bool EmulatedUsbDevice::out_halted() const {
    std::lock_guard lock(mutex_);
    return handler_->out_halted;
}

bool EmulatedUsbDevice::plugged() const {
    std::lock_guard lock(mutex_);
    return plugged_;
}

int EmulatedUsbDevice::bus() const { return kBus; }

int EmulatedUsbDevice::address() const {
    std::lock_guard lock(mutex_);
    return address_;
}

std::string EmulatedUsbDevice::devnode() const {
    return "/dev/bus/usb/" + three_digits(kBus) + "/" + three_digits(address());
}

std::string EmulatedUsbDevice::syspath() const {
    return "/sys/devices/usb" + std::to_string(kBus) + "/" + std::to_string(kBus) + "-" +
           std::to_string(port_);
}

// ---------------------------------------------------------------------------------------------

struct UsbTestbed::Impl {
    UMockdevTestbed* testbed = nullptr;
};

bool UsbTestbed::preload_active() {
    const char* preload = std::getenv("LD_PRELOAD");
    return preload != nullptr &&
           std::string_view(preload).find("libumockdev-preload") != std::string_view::npos;
}

UsbTestbed::UsbTestbed() : impl_(std::make_unique<Impl>()) {
    if (!preload_active()) {
        throw std::runtime_error(
            "the USB tests need libumockdev-preload.so in LD_PRELOAD: run them through ctest or "
            "`umockdev-wrapper <test>`");
    }
    impl_->testbed = umockdev_testbed_new();
    gchar* root = umockdev_testbed_get_root_dir(impl_->testbed);
    root_dir_ = root;
    g_free(root);
}

UsbTestbed::~UsbTestbed() {
    for (const auto& device : devices_) {
        g_signal_handlers_disconnect_by_data(device->handler_->base, device->handler_.get());
    }
    g_object_unref(impl_->testbed);  // removes the directory, stops the worker
    devices_.clear();
}

EmulatedUsbDevice& UsbTestbed::add(UsbDeviceSpec spec) {
    const int port = static_cast<int>(devices_.size()) + 1;
    devices_.push_back(
        std::unique_ptr<EmulatedUsbDevice>(new EmulatedUsbDevice(std::move(spec), port)));
    EmulatedUsbDevice& device = *devices_.back();
    device.address_ = next_address_++;
    device.plugged_ = true;
    add_to_sysfs(device);
    return device;
}

void UsbTestbed::add_to_sysfs(EmulatedUsbDevice& device) {
    const UsbDeviceSpec& spec = device.spec_;
    const std::string serial = spec.usb_serial.value_or(spec.emulator.serial_number);
    const std::string devnode = device.devnode();
    // The handler first, so that the device can be opened as soon as it is visible (umockdev
    // issue 173).
    GError* error = nullptr;
    if (!umockdev_testbed_attach_ioctl(impl_->testbed, devnode.c_str(), device.handler_->base,
                                       &error)) {
        const std::string message = error != nullptr ? error->message : "?";
        g_clear_error(&error);
        throw std::runtime_error("umockdev: cannot attach the ioctl handler to " + devnode + ": " +
                                 message);
    }
    std::vector<std::uint8_t> descriptors = device_descriptor(spec, !serial.empty());
    const std::vector<std::uint8_t> configuration = configuration_descriptor(spec);
    descriptors.insert(descriptors.end(), configuration.begin(), configuration.end());
    const std::string address = std::to_string(device.address_);
    std::array<char, 8> vid{};
    std::array<char, 8> pid{};
    std::snprintf(vid.data(), vid.size(), "%04x", spec.vendor_id);
    std::snprintf(pid.data(), pid.size(), "%04x", spec.product_id);
    std::string record = "P: " + device.syspath().substr(4) + "\n" +  // without "/sys"
                         "N: " + devnode.substr(5) + "\n" +           // without "/dev/"
                         "E: SUBSYSTEM=usb\nE: DEVTYPE=usb_device\nE: DRIVER=usb\n"
                         "E: BUSNUM=" +
                         three_digits(kBus) + "\nE: DEVNUM=" + three_digits(device.address_) +
                         "\nE: DEVNAME=" + devnode + "\n" + "A: busnum=" + std::to_string(kBus) +
                         "\\n\nA: devnum=" + address +
                         "\\n\nA: speed=12\\n\nA: bConfigurationValue=1\\n\n" +
                         "A: idVendor=" + vid.data() + "\\n\nA: idProduct=" + pid.data() + "\\n\n";
    if (!serial.empty()) record += "A: serial=" + serial + "\\n\n";
    record += "H: descriptors=" + hex(descriptors) + "\n";
    if (!umockdev_testbed_add_from_string(impl_->testbed, record.c_str(), &error)) {
        const std::string message = error != nullptr ? error->message : "?";
        g_clear_error(&error);
        throw std::runtime_error("umockdev: cannot add " + devnode + ": " + message);
    }
}

void UsbTestbed::unplug(EmulatedUsbDevice& device) {
    {
        std::lock_guard lock(device.mutex_);
        if (device.plugged_) device.handler_->pull_cable();
        device.handler_->unplug_at_command.reset();
    }
    umockdev_testbed_remove_device(impl_->testbed, device.syspath().c_str());
}

void UsbTestbed::replug(EmulatedUsbDevice& device, bool fresh_emulator) {
    {
        std::lock_guard lock(device.mutex_);
        EmulatedUsbDevice::Handler& handler = *device.handler_;
        ++handler.generation;  // files opened before stay dead
        handler.replies.clear();
        handler.in_halted = false;
        handler.out_halted = false;
        handler.stall_out_next = false;
        handler.fail_next_in.reset();
        handler.unplug_at_command.reset();
        if (fresh_emulator) {
            device.emulator_ = std::make_unique<proto::DeviceEmulator>(device.spec_.emulator);
        }
        device.address_ = next_address_++;
        device.plugged_ = true;
    }
    add_to_sysfs(device);
}

void UsbTestbed::open_to_other_users() {
    // Sticky and world-writable like /tmp: libusb's hotplug monitor binds its (emulated)
    // netlink socket in the testbed's root, so any user must be able to create files there.
    if (::chmod(root_dir_.c_str(), 01777) != 0) {
        throw std::runtime_error("chmod " + root_dir_ + ": " + std::strerror(errno));
    }
    // The preload connects a file opened on an emulated node to its ioctl socket: let any user
    // connect (the node's own permissions are what is being tested).
    for (const auto& device : devices_) {
        const std::string socket = root_dir_ + "/ioctl" + device->devnode();
        if (::chmod(socket.c_str(), 0777) != 0) {
            throw std::runtime_error("chmod " + socket + ": " + std::strerror(errno));
        }
    }
}

}  // namespace hapticd::testing
