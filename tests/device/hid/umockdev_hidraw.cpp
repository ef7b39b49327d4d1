// Emulated hidraw nodes in a umockdev testbed (umockdev_hidraw.hpp).
#include "umockdev_hidraw.hpp"

#include <fcntl.h>
#include <linux/hidraw.h>
#include <pty.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <umockdev.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>

#include "hapticd/device/protocol/transport.hpp"

namespace hapticd::testing {
namespace {

constexpr int kHidrawMajor = 240;  ///< hidraw's major is dynamic; any char major will do
constexpr unsigned kBusUsb = 3;    ///< BUS_USB, the bus of HID_ID

std::string hex(unsigned value, int digits) {
    char text[16];
    std::snprintf(text, sizeof text, "%0*x", digits, value);
    return text;
}

/// What the ioctl handler of one /dev node answers; lives as long as the testbed, because
/// umockdev keeps the handler attached (detaching it under a client that still holds the
/// node open would break that client's next read()).
struct IoctlTarget {
    std::mutex mutex;
    std::vector<std::uint8_t> descriptor;
    std::uint16_t vid = 0;
    std::uint16_t pid = 0;
};

/// umockdev "handle-ioctl", on umockdev's thread: the hidraw ioctls hidapi uses.
gboolean on_hidraw_ioctl(UMockdevIoctlBase* /*handler*/, UMockdevIoctlClient* client,
                         gpointer user_data) {
    auto* target = static_cast<IoctlTarget*>(user_data);
    const gulong request = umockdev_ioctl_client_get_request(client);
    UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
    GError* error = nullptr;
    std::lock_guard lock(target->mutex);
    if (request == HIDIOCGRDESCSIZE) {
        UMockdevIoctlData* data = umockdev_ioctl_data_resolve(arg, 0, sizeof(int), &error);
        if (data == nullptr) return FALSE;
        const int size = static_cast<int>(target->descriptor.size());
        std::memcpy(data->data, &size, sizeof size);
        g_object_unref(data);
        umockdev_ioctl_client_complete(client, 0, 0);
        return TRUE;
    }
    if (request == HIDIOCGRDESC) {
        UMockdevIoctlData* data =
            umockdev_ioctl_data_resolve(arg, 0, sizeof(hidraw_report_descriptor), &error);
        if (data == nullptr) return FALSE;
        hidraw_report_descriptor descriptor{};
        std::memcpy(&descriptor, data->data, sizeof descriptor);
        if (descriptor.size > HID_MAX_DESCRIPTOR_SIZE) {
            g_object_unref(data);
            umockdev_ioctl_client_complete(client, -1, EINVAL);
            return TRUE;
        }
        const std::size_t n = std::min<std::size_t>(descriptor.size, target->descriptor.size());
        std::memcpy(descriptor.value, target->descriptor.data(), n);
        std::memcpy(data->data, &descriptor, sizeof descriptor);
        g_object_unref(data);
        umockdev_ioctl_client_complete(client, 0, 0);
        return TRUE;
    }
    if (request == HIDIOCGRAWINFO) {
        UMockdevIoctlData* data =
            umockdev_ioctl_data_resolve(arg, 0, sizeof(hidraw_devinfo), &error);
        if (data == nullptr) return FALSE;
        hidraw_devinfo info{};
        info.bustype = kBusUsb;
        info.vendor = static_cast<__s16>(target->vid);
        info.product = static_cast<__s16>(target->pid);
        std::memcpy(data->data, &info, sizeof info);
        g_object_unref(data);
        umockdev_ioctl_client_complete(client, 0, 0);
        return TRUE;
    }
    return FALSE;  // umockdev's default: ENOTTY, or the pty's own termios ioctls
}

struct Node {
    HidrawNodeSpec spec;
    std::vector<std::string> syspaths;  ///< usb device, interface, hid, hidraw
    std::string devnode;
    int master = -1;
    int slave = -1;  ///< held open and flock()ed while plugged (see plug())
};

}  // namespace

bool in_umockdev_environment() { return umockdev_in_mock_environment() != FALSE; }

struct UmockdevHidraw::Impl {
    UMockdevTestbed* testbed = nullptr;
    std::vector<Node> nodes;
    std::map<std::string, std::unique_ptr<IoctlTarget>> targets;  ///< by /dev node
    std::map<std::string, UMockdevIoctlBase*> handlers;

    std::string add(const char* subsystem, const std::string& name, const std::string& parent,
                    const std::vector<std::string>& attributes,
                    const std::vector<std::string>& properties) {
        auto c_array = [](const std::vector<std::string>& strings) {
            std::vector<gchar*> array;
            array.reserve(strings.size() + 1);
            for (const std::string& s : strings) array.push_back(const_cast<gchar*>(s.c_str()));
            array.push_back(nullptr);
            return array;
        };
        std::vector<gchar*> a = c_array(attributes);
        std::vector<gchar*> p = c_array(properties);
        gchar* path = umockdev_testbed_add_devicev(testbed, subsystem, name.c_str(),
                                                   parent.empty() ? nullptr : parent.c_str(),
                                                   a.data(), p.data());
        if (path == nullptr) throw std::runtime_error("umockdev: cannot add " + name);
        std::string result = path;
        g_free(path);
        return result;
    }
};

UmockdevHidraw::UmockdevHidraw() : impl_(std::make_unique<Impl>()) {
    impl_->testbed = umockdev_testbed_new();  // sets $UMOCKDEV_DIR, which the check needs
    if (!in_umockdev_environment()) {
        g_object_unref(impl_->testbed);
        throw std::runtime_error(
            "not running under libumockdev-preload: run this test through ctest (which uses "
            "umockdev-wrapper), or as `umockdev-wrapper <test>`");
    }
}

UmockdevHidraw::~UmockdevHidraw() {
    for (std::size_t i = 0; i < impl_->nodes.size(); ++i) unplug(static_cast<int>(i));
    g_object_unref(impl_->testbed);  // detaches the ioctl handlers, removes the tree
    for (auto& [devnode, handler] : impl_->handlers) g_object_unref(handler);
}

int UmockdevHidraw::plug(const HidrawNodeSpec& spec) {
    Impl& impl = *impl_;
    const int index = static_cast<int>(impl.nodes.size());
    Node node;
    node.spec = spec;
    if (node.spec.report_descriptor.empty()) {
        node.spec.report_descriptor.assign(device::protocol::hid::kReportDescriptor.begin(),
                                           device::protocol::hid::kReportDescriptor.end());
    }
    const std::string number = std::to_string(spec.hidraw_number);
    node.devnode = "/dev/hidraw" + number;

    // In the order that leaves no half-made device to a client that enumerates meanwhile (a
    // reconnecting ProtocolDevice does, every few milliseconds): first what answers the
    // node's ioctls, then the node, then the sysfs tree through which hidapi finds it. A node
    // without its ioctl socket would be opened as a plain pty (HIDIOCGRDESCSIZE fails), and a
    // socket bound but not yet listening makes libumockdev-preload exit(1) in open().

    // The ioctls, once per /dev node for the testbed's lifetime: bound and listening when
    // umockdev_testbed_attach_ioctl() returns.
    auto& target = impl.targets[node.devnode];
    if (!target) target = std::make_unique<IoctlTarget>();
    {
        std::lock_guard lock(target->mutex);
        target->descriptor = node.spec.report_descriptor;
        target->vid = spec.vid;
        target->pid = spec.pid;
    }
    if (!impl.handlers.contains(node.devnode)) {
        UMockdevIoctlBase* handler = umockdev_ioctl_base_new();
        g_signal_connect(handler, "handle-ioctl", G_CALLBACK(on_hidraw_ioctl), target.get());
        GError* error = nullptr;
        if (!umockdev_testbed_attach_ioctl(impl.testbed, node.devnode.c_str(), handler, &error)) {
            const std::string message = error != nullptr ? error->message : "?";
            g_clear_error(&error);
            g_object_unref(handler);
            throw std::runtime_error("umockdev_testbed_attach_ioctl(" + node.devnode +
                                     "): " + message);
        }
        impl.handlers.emplace(node.devnode, handler);
    }
    // The node: a raw pty that delivers whole reports (VMIN = a report), set up before its
    // link appears, so no client ever sees it cooked. /dev/pts/N is a name any process on the
    // machine can open, and a number is reused as soon as its pty is gone: a test of another
    // suite that still holds the path of a pty it closed (the serial tests' hosts reconnect
    // to a symlink to their unplugged device's pty) opens this one when it gets that number,
    // and a serial host sets the line VMIN = 0, flushes both queues and writes its own frames.
    // So the node keeps its slave open with flock(LOCK_EX), as a serial host does with the
    // port it holds (it backs off, "busy", before touching the line), and sets the line up
    // and empties both queues only once it has the lock (after such a host let go).
    char slave_name[256] = {};
    if (openpty(&node.master, &node.slave, slave_name, nullptr, nullptr) != 0) {
        throw std::runtime_error(std::string("openpty: ") + std::strerror(errno));
    }
    (void)fcntl(node.master, F_SETFD, FD_CLOEXEC);  // children must not keep the pty up
    (void)fcntl(node.slave, F_SETFD, FD_CLOEXEC);
    while (::flock(node.slave, LOCK_EX) != 0) {
        if (errno != EINTR) {
            throw std::runtime_error(std::string("flock(") + slave_name +
                                     "): " + std::strerror(errno));
        }
    }
    (void)::ioctl(node.slave, TIOCNXCL);  // what such a host may have left (TIOCEXCL)
    termios mode{};
    if (tcgetattr(node.slave, &mode) != 0) {
        throw std::runtime_error(std::string("tcgetattr: ") + std::strerror(errno));
    }
    cfmakeraw(&mode);
    mode.c_cc[VMIN] = static_cast<cc_t>(device::protocol::hid::kReportSize);
    mode.c_cc[VTIME] = 0;
    if (tcsetattr(node.slave, TCSANOW, &mode) != 0) {
        throw std::runtime_error(std::string("tcsetattr: ") + std::strerror(errno));
    }
    (void)tcflush(node.slave, TCIOFLUSH);
    (void)tcflush(node.master, TCIFLUSH);
    const std::string link_path = root_dir() + node.devnode;
    if (g_mkdir_with_parents((root_dir() + "/dev").c_str(), 0755) != 0) {
        throw std::runtime_error("mkdir " + root_dir() + "/dev: " + std::strerror(errno));
    }
    (void)::unlink(link_path.c_str());
    if (::symlink(slave_name, link_path.c_str()) != 0) {
        throw std::runtime_error("symlink " + link_path + ": " + std::strerror(errno));
    }

    // The device in sysfs: from here enumeration lists it.
    const std::string bus = std::to_string(index + 1);
    const std::string vid = hex(spec.vid, 4);
    const std::string pid = hex(spec.pid, 4);

    const std::string usb =
        impl.add("usb", "usb" + bus + "/" + bus + "-1", "",
                 {"idVendor", vid, "idProduct", pid, "manufacturer", spec.manufacturer, "product",
                  spec.product, "serial", spec.serial, "bcdDevice", "0100", "busnum", bus, "devnum",
                  "2", "speed", "12"},
                 {"DEVTYPE", "usb_device", "PRODUCT", vid + "/" + pid + "/100", "BUSNUM", bus,
                  "DEVNUM", "002"});
    const std::string interface = impl.add("usb", bus + "-1:1.0", usb,
                                           {"bInterfaceNumber", "00", "bInterfaceClass", "03",
                                            "bInterfaceSubClass", "00", "bInterfaceProtocol", "00"},
                                           {"DEVTYPE", "usb_interface", "INTERFACE", "3/0/0"});
    const std::string hid_name = "0003:" + hex(spec.vid, 4) + ":" + hex(spec.pid, 4) + "." +
                                 hex(static_cast<unsigned>(index + 1), 4);
    const std::string hid =
        impl.add("hid", hid_name, interface, {},
                 {"HID_ID", "0003:" + hex(spec.vid, 8) + ":" + hex(spec.pid, 8), "HID_NAME",
                  spec.manufacturer + " " + spec.product, "HID_PHYS", "usb-emulated-1/input0",
                  "HID_UNIQ", spec.serial});
    umockdev_testbed_set_attribute_binary(impl.testbed, hid.c_str(), "report_descriptor",
                                          node.spec.report_descriptor.data(),
                                          static_cast<gint>(node.spec.report_descriptor.size()));
    const std::string dev = std::to_string(kHidrawMajor) + ":" + number;
    const std::string hidraw =
        impl.add("hidraw", "hidraw/hidraw" + number, hid, {"dev", dev},
                 {"DEVNAME", node.devnode, "MAJOR", std::to_string(kHidrawMajor), "MINOR", number});
    umockdev_testbed_set_attribute_link(impl.testbed, hidraw.c_str(), "device",
                                        ("../../../" + hid_name).c_str());
    node.syspaths = {usb, interface, hid, hidraw};

    impl.nodes.push_back(std::move(node));
    return index;
}

void UmockdevHidraw::unplug(int index) {
    Node& node = impl_->nodes.at(static_cast<std::size_t>(index));
    if (node.master < 0) return;
    // Children first: umockdev removes the class and bus links of the device it is given.
    for (auto path = node.syspaths.rbegin(); path != node.syspaths.rend(); ++path) {
        umockdev_testbed_remove_device(impl_->testbed, path->c_str());
    }
    (void)::unlink((root_dir() + node.devnode).c_str());
    ::close(node.master);  // the slave hangs up, for every client and for the node's own hold
    ::close(node.slave);
    node.master = -1;
    node.slave = -1;
}

bool UmockdevHidraw::plugged(int node) const {
    return impl_->nodes.at(static_cast<std::size_t>(node)).master >= 0;
}

std::string UmockdevHidraw::devnode(int node) const {
    return impl_->nodes.at(static_cast<std::size_t>(node)).devnode;
}

int UmockdevHidraw::master_fd(int node) const {
    return impl_->nodes.at(static_cast<std::size_t>(node)).master;
}

const HidrawNodeSpec& UmockdevHidraw::spec(int node) const {
    return impl_->nodes.at(static_cast<std::size_t>(node)).spec;
}

std::string UmockdevHidraw::root_dir() const {
    gchar* dir = umockdev_testbed_get_root_dir(impl_->testbed);
    std::string result = dir;
    g_free(dir);
    return result;
}

}  // namespace hapticd::testing
