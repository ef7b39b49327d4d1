// Opening and configuring a serial port (serial_port.hpp, docs/transport-serial.md).
#include "hapticd/device/serial/serial_port.hpp"

#include <fcntl.h>
#include <grp.h>
#include <linux/serial.h>
#include <pwd.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <thread>
#include <utility>

namespace hapticd::device::serial {
namespace {

namespace fs = std::filesystem;

/// How long DTR is held off before it is raised again (reset_on_open), as avrdude does.
constexpr auto kDtrLowTime = std::chrono::milliseconds(100);

std::string error_text(int error) { return std::strerror(error); }

/// "serial port /dev/ttyACM0 (device.serial.port in cfg.toml)"
std::string port_name(const SerialSettings& settings) {
    return "serial port " + settings.port + " (device.serial.port in " + settings.source + ")";
}

[[noreturn]] void fail_step(const SerialSettings& settings, const std::string& step, int error) {
    throw std::runtime_error(port_name(settings) + ": " + step + " failed: " + error_text(error));
}

/// Closes the descriptor unless released (open_serial_port's error paths).
class FdGuard {
  public:
    explicit FdGuard(int fd) : fd_(fd) {}
    ~FdGuard() {
        if (fd_ >= 0) ::close(fd_);
    }
    FdGuard(const FdGuard&) = delete;
    FdGuard& operator=(const FdGuard&) = delete;
    int release() { return std::exchange(fd_, -1); }

  private:
    int fd_;
};

speed_t baud_constant(std::uint32_t baud) {
    switch (baud) {
        case 9'600:
            return B9600;
        case 19'200:
            return B19200;
        case 38'400:
            return B38400;
        case 57'600:
            return B57600;
        case 115'200:
            return B115200;
        case 230'400:
            return B230400;
        case 460'800:
            return B460800;
        case 500'000:
            return B500000;
        case 576'000:
            return B576000;
        case 921'600:
            return B921600;
        case 1'000'000:
            return B1000000;
        case 1'152'000:
            return B1152000;
        case 1'500'000:
            return B1500000;
        case 2'000'000:
            return B2000000;
        case 2'500'000:
            return B2500000;
        case 3'000'000:
            return B3000000;
        case 3'500'000:
            return B3500000;
        case 4'000'000:
            return B4000000;
        default:
            return B0;  // read_serial_settings() lets no other rate through
    }
}

/// Raw 8N1 at the configured rate, no flow control, reads that never block (VMIN = VTIME =
/// 0: poll() does the waiting); HUPCL as reset_on_open says. Read back and checked, because
/// tcsetattr() succeeds if any one of the changes was made.
void configure_line(int fd, const SerialSettings& settings) {
    termios line{};
    if (::tcgetattr(fd, &line) != 0) fail_step(settings, "tcgetattr", errno);
    ::cfmakeraw(&line);
    line.c_iflag &= ~static_cast<tcflag_t>(IXOFF | IXANY);  // cfmakeraw leaves them
    line.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | PARENB | CRTSCTS | CSIZE);
    line.c_cflag |= CS8 | CLOCAL | CREAD;
    // HUPCL set: the last close drops DTR, and the next open raises it again: a reset of an
    // Arduino-style board. Cleared, DTR stays up across close and reopen.
    if (settings.reset_on_open) {
        line.c_cflag |= HUPCL;
    } else {
        line.c_cflag &= ~static_cast<tcflag_t>(HUPCL);
    }
    line.c_cc[VMIN] = 0;
    line.c_cc[VTIME] = 0;
    const speed_t speed = baud_constant(settings.baud);
    if (::cfsetspeed(&line, speed) != 0) fail_step(settings, "cfsetspeed", errno);
    if (::tcsetattr(fd, TCSANOW, &line) != 0) fail_step(settings, "tcsetattr", errno);

    termios now{};
    if (::tcgetattr(fd, &now) != 0) fail_step(settings, "tcgetattr", errno);
    if (::cfgetospeed(&now) != speed || ::cfgetispeed(&now) != speed) {
        throw std::runtime_error(
            port_name(settings) + ": its driver does not take " + std::to_string(settings.baud) +
            " baud (device.serial.baud); try another rate of " + baud_rates_text());
    }
    const bool raw = (now.c_lflag & (ICANON | ECHO | ISIG)) == 0 && (now.c_cflag & CSIZE) == CS8 &&
                     (now.c_cflag & PARENB) == 0;
    if (!raw) {
        throw std::runtime_error(port_name(settings) +
                                 ": the driver did not accept raw 8N1 mode (termios)");
    }
}

/// ASYNC_LOW_LATENCY: the ftdi_sio driver then sets the adapter's latency timer to 1 ms.
/// A pty has no serial_struct (ENOTTY); other drivers may refuse (EINVAL, EPERM): all of it
/// is harmless, the report says so.
bool request_low_latency(int fd) {
    serial_struct info{};
    if (::ioctl(fd, TIOCGSERIAL, &info) != 0) return false;
    if ((info.flags & ASYNC_LOW_LATENCY) != 0) return true;
    info.flags |= ASYNC_LOW_LATENCY;
    return ::ioctl(fd, TIOCSSERIAL, &info) == 0;
}

/// An FTDI adapter's latency timer, ms, from sysfs; -1 when the port has none.
int latency_timer_ms(const std::string& port) {
    std::error_code error;
    const fs::path device = fs::canonical(port, error);
    if (error) return -1;
    std::ifstream in("/sys/class/tty/" + device.filename().string() + "/device/latency_timer");
    int value = -1;
    if (!(in >> value)) return -1;
    return value;
}

/// reset_on_open: DTR (and RTS) off, then on again. The falling edge of the DTR pin (it is
/// active low) reaches RESET through the board's auto-reset capacitor. Then wait for the
/// bootloader to hand over to the firmware, and drop whatever it printed.
void pulse_dtr(int fd, const SerialSettings& settings) {
    int lines = TIOCM_DTR | TIOCM_RTS;
    if (::ioctl(fd, TIOCMBIC, &lines) != 0) {
        throw std::runtime_error(port_name(settings) +
                                 ": device.serial.reset_on_open = true, but DTR cannot be "
                                 "driven on this port (TIOCMBIC: " +
                                 error_text(errno) + ")");
    }
    std::this_thread::sleep_for(kDtrLowTime);
    if (::ioctl(fd, TIOCMBIS, &lines) != 0) fail_step(settings, "raising DTR (TIOCMBIS)", errno);
    std::this_thread::sleep_for(std::chrono::milliseconds(settings.reset_wait_ms));
}

/// Who may open `path`: "it belongs to user root, group dialout, mode 660"; empty if it
/// cannot be looked at.
std::string file_owner_text(const struct stat& info) {
    const passwd* user = ::getpwuid(info.st_uid);
    const group* grp = ::getgrgid(info.st_gid);
    std::string text = "it belongs to user ";
    text += user != nullptr ? user->pw_name : std::to_string(info.st_uid);
    text += ", group ";
    text += grp != nullptr ? grp->gr_name : std::to_string(info.st_gid);
    char mode[16];
    std::snprintf(mode, sizeof mode, "%03o", static_cast<unsigned>(info.st_mode & 0777));
    text += ", mode ";
    text += mode;
    return text;
}

/// The advice for EACCES: join the node's group if that group may read and write it (and is
/// not root's), and in any case the udev rule.
std::string access_advice(const std::string& path) {
    const std::string rule =
        "install the udev rule in config/udev/70-hapticd.rules (docs/transport-serial.md)";
    struct stat info {};
    if (::stat(path.c_str(), &info) != 0) return ". Check its permissions, or " + rule + ".";
    std::string text = " (" + file_owner_text(info) + ")";
    const group* grp = ::getgrgid(info.st_gid);
    const bool group_may_use = (info.st_mode & 0060) == 0060 && info.st_gid != 0 && grp != nullptr;
    if (group_may_use) {
        const std::string name = grp->gr_name;
        text += ". Either add your user to group " + name + " (`sudo usermod -aG " + name +
                " $USER`, then log in again), or " + rule + ".";
    } else {
        text += ". Its group cannot open it either: " + rule + ", or run as its owner.";
    }
    return text;
}

std::string joined(const std::vector<std::string>& items, const std::string& separator) {
    std::string text;
    for (const std::string& item : items) text += (text.empty() ? "" : separator) + item;
    return text;
}

}  // namespace

std::vector<std::string> present_ports(const std::string& by_id_dir) {
    std::vector<std::string> by_id;
    std::error_code error;
    for (const fs::directory_entry& entry : fs::directory_iterator(by_id_dir, error)) {
        std::error_code link_error;
        const fs::path target = fs::read_symlink(entry.path(), link_error);
        by_id.push_back(entry.path().string() +
                        (link_error ? std::string() : " -> " + target.string()));
    }
    std::sort(by_id.begin(), by_id.end());
    std::vector<std::string> nodes;
    for (const fs::directory_entry& entry : fs::directory_iterator("/dev", error)) {
        const std::string name = entry.path().filename().string();
        if (name.rfind("ttyACM", 0) == 0 || name.rfind("ttyUSB", 0) == 0) {
            nodes.push_back(entry.path().string());
        }
    }
    std::sort(nodes.begin(), nodes.end());
    by_id.insert(by_id.end(), nodes.begin(), nodes.end());
    return by_id;
}

std::vector<std::string> port_holders(const std::string& path) {
    std::vector<std::string> holders;
    std::error_code error;
    const fs::path wanted = fs::canonical(path, error);
    if (error) return holders;
    for (const fs::directory_entry& process : fs::directory_iterator("/proc", error)) {
        const std::string pid = process.path().filename().string();
        if (pid.empty() || !std::all_of(pid.begin(), pid.end(), ::isdigit)) continue;
        std::error_code fd_error;
        for (const fs::directory_entry& fd :
             fs::directory_iterator(process.path() / "fd", fd_error)) {
            std::error_code link_error;
            if (fs::read_symlink(fd.path(), link_error) != wanted || link_error) continue;
            std::ifstream comm_file(process.path() / "comm");
            std::string comm;
            std::getline(comm_file, comm);
            holders.push_back("pid " + pid + " (" + comm + ")");
            break;
        }
    }
    return holders;
}

std::string open_error_message(int error, const SerialSettings& settings,
                               const std::string& by_id_dir) {
    std::string text = port_name(settings) + ": ";
    switch (error) {
        case ENOENT:
        case ENOTDIR: {
            text += "not found. ";
            std::error_code link_error;
            if (fs::is_symlink(settings.port, link_error)) {
                text += "It is a link to " + fs::read_symlink(settings.port, link_error).string() +
                        ", which does not exist: the device is unplugged, or came back under "
                        "another name. ";
            }
            const std::vector<std::string> ports = present_ports(by_id_dir);
            if (ports.empty()) {
                text += "No serial port is present (" + by_id_dir +
                        " is empty or missing, no /dev/ttyACM* or /dev/ttyUSB*): is the device "
                        "plugged in and powered? `dmesg | tail` shows what the kernel saw.";
            } else {
                text += "Present: " + joined(ports, "; ") + ". Prefer a " + by_id_dir +
                        " path: it stays the same when the device "
                        "is replugged.";
            }
            return text;
        }
        case EACCES:
        case EPERM:
            return text + "permission denied" + access_advice(settings.port);
        case EBUSY:
        case EWOULDBLOCK: {
            text += "busy: another program has it open exclusively (TIOCEXCL or flock)";
            const std::vector<std::string> holders = port_holders(settings.port);
            if (!holders.empty()) text += ": " + joined(holders, ", ");
            text +=
                ". Close it (a serial monitor, another hapticd; ModemManager probes a new "
                "/dev/ttyACM* for some seconds after it appears: docs/transport-serial.md), or "
                "set device.serial.exclusive = false to share the port.";
            return text;
        }
        case ENXIO:
        case ENODEV:
            return text + "no device behind it (" + error_text(error) +
                   "): it was unplugged or its driver is gone.";
        case EIO:
            return text + "I/O error: the device is being unplugged or reset.";
        default:
            return text + "cannot open: " + error_text(error);
    }
}

int open_serial_port(const SerialSettings& settings, PortReport& report) {
    report = PortReport{};
    // O_NONBLOCK: open() does not wait for carrier detect, and reads and writes never block
    // (poll() waits). It does NOT keep the kernel from raising DTR: tty_port_block_til_ready()
    // raises DTR and RTS on every open unless the saved baud rate is B0 (see the docs).
    const int fd = ::open(settings.port.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) throw std::runtime_error(open_error_message(errno, settings));
    FdGuard guard(fd);
    if (::isatty(fd) == 0) {
        throw std::runtime_error(port_name(settings) +
                                 ": not a serial port (not a terminal device)");
    }
    if (settings.exclusive) {
        // flock first: it also holds against root, whom TIOCEXCL lets through.
        if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
            throw std::runtime_error(open_error_message(errno, settings));
        }
        if (::ioctl(fd, TIOCEXCL) != 0) fail_step(settings, "TIOCEXCL", errno);
    }
    configure_line(fd, settings);
    report.low_latency = request_low_latency(fd);
    report.latency_timer_ms = latency_timer_ms(settings.port);
    if (settings.reset_on_open) {
        pulse_dtr(fd, settings);
        report.dtr_pulsed = true;
    }
    if (::tcflush(fd, TCIOFLUSH) != 0) fail_step(settings, "tcflush", errno);
    return guard.release();
}

}  // namespace hapticd::device::serial
