// The [device.serial] keys and opening the port (serial_settings.hpp, serial_port.hpp): bad
// configuration names device.serial.<key>; the line really is raw 8N1 at the baud rate with
// HUPCL cleared and the port held exclusively; open() failures say what to do (not found,
// permission denied, busy, not a tty, no DTR to pulse).
#include "hapticd/device/serial/serial_port.hpp"

#include <fcntl.h>
#include <gmock/gmock.h>
#include <grp.h>
#include <gtest/gtest.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "hapticd/device/link/protocol_device.hpp"
#include "hapticd/device/serial/serial_link.hpp"
#include "hapticd/device/serial/serial_settings.hpp"
#include "pty_device.hpp"
#include "scratch_dir.hpp"
#include "serial_test_util.hpp"

namespace hapticd::testing {
namespace {

using device::serial::PortReport;
using device::serial::SerialLink;
using device::serial::SerialSettings;
using ::testing::HasSubstr;

/// read_serial_settings() on `table` as the [device.serial] of test.toml, then finish().
SerialSettings read_table(const std::string& table) {
    device::DeviceConfig config;
    config.source = "test.toml";
    config.plugin_table_toml = table;
    device::PluginTable parsed(config, "serial", "docs/transport-serial.md");
    device::TableReader& reader = parsed.reader();
    SerialSettings settings = device::serial::read_serial_settings(reader);
    reader.finish();
    return settings;
}

/// The message read() throws for `table` ("" if it does not throw).
std::string error_for(const std::string& table) {
    try {
        (void)read_table(table);
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return "";
}

/// The message open() throws ("" if it opens).
std::string open_error(const SerialSettings& settings) {
    try {
        SerialLink link(settings);
        link.open();
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return "";
}

TEST(SerialSettings, DefaultsAndEveryKey) {
    const SerialSettings defaults = read_table("port = \"/dev/ttyACM0\"\n");
    EXPECT_EQ(defaults.port, "/dev/ttyACM0");
    EXPECT_EQ(defaults.baud, 2'000'000u);
    EXPECT_FALSE(defaults.reset_on_open);
    EXPECT_TRUE(defaults.exclusive);
    EXPECT_EQ(defaults.source, "test.toml");

    const SerialSettings all = read_table(
        "port = \"/dev/serial/by-id/usb-x-if00\"\nbaud = 115200\nreset_on_open = true\n"
        "reset_wait_ms = 500\nexclusive = false\n");
    EXPECT_EQ(all.port, "/dev/serial/by-id/usb-x-if00");
    EXPECT_EQ(all.baud, 115'200u);
    EXPECT_TRUE(all.reset_on_open);
    EXPECT_EQ(all.reset_wait_ms, 500u);
    EXPECT_FALSE(all.exclusive);
    for (const std::uint32_t rate : device::serial::kStandardBaudRates) {
        EXPECT_EQ(read_table("port = \"p\"\nbaud = " + std::to_string(rate) + "\n").baud, rate);
    }
}

TEST(SerialSettings, BadValuesNameTheKey) {
    EXPECT_THAT(error_for(""), HasSubstr("[device.serial] port is missing: required"));
    EXPECT_THAT(error_for("port = \"\"\n"),
                HasSubstr("test.toml:1: [device.serial] port = \"\" is empty"));
    EXPECT_THAT(error_for("port = 3\n"), HasSubstr("[device.serial] port = 3 is not a string"));

    const std::string slow = error_for("port = \"p\"\nbaud = 1200\n");
    EXPECT_THAT(slow, HasSubstr("test.toml:2: [device.serial] baud = 1200 is not allowed"));
    EXPECT_THAT(slow, HasSubstr("9600, 19200, 38400, 57600, 115200"));
    EXPECT_THAT(slow, HasSubstr("3500000, 4000000"));
    EXPECT_THAT(error_for("port = \"p\"\nbaud = 2000001\n"),
                HasSubstr("[device.serial] baud = 2000001 is not allowed"));
    EXPECT_THAT(error_for("port = \"p\"\nbaud = \"fast\"\n"),
                HasSubstr("[device.serial] baud = \"fast\" is not allowed"));
    EXPECT_THAT(error_for("port = \"p\"\nbaud = 115200.0\n"),
                HasSubstr("[device.serial] baud = 115200.0 is not allowed"));
    EXPECT_THAT(
        error_for("port = \"p\"\nreset_on_open = 1\n"),
        HasSubstr("[device.serial] reset_on_open = 1 is not a boolean: allowed true or false"));
    EXPECT_THAT(
        error_for("port = \"p\"\nreset_wait_ms = 20000\n"),
        HasSubstr("[device.serial] reset_wait_ms = 20000 is out of range: allowed 0..10000 (ms)"));
    EXPECT_THAT(error_for("port = \"p\"\nexclusive = \"yes\"\n"),
                HasSubstr("[device.serial] exclusive = \"yes\" is not a boolean"));
    const std::string unknown = error_for("port = \"p\"\nbuad = 9600\n");
    EXPECT_THAT(unknown, HasSubstr("test.toml:2: [device.serial] buad = 9600 is not a known key"));
    EXPECT_THAT(unknown, HasSubstr("docs/transport-serial.md"));
}

TEST(SerialSettings, TheLinkFactoryWaitsOnePeriodForRoomToWrite) {
    device::DeviceConfig config;
    config.rate_hz = 500.0;
    config.source = "cfg.toml";
    config.plugin_table_toml = "port = \"/dev/ttyX\"\n";
    device::PluginTable parsed(config, "serial", "docs/transport-serial.md");
    device::TableReader& reader = parsed.reader();
    const device::link::ProtocolSettings protocol;
    const auto link =
        device::serial::make_serial_link(reader, device::link::LinkContext{config, protocol});
    const auto& serial = dynamic_cast<const SerialLink&>(*link);
    EXPECT_EQ(serial.settings().write_timeout_ns, 2'000'000);  // one period at 500 Hz
    EXPECT_EQ(serial.settings().source, "cfg.toml");
    EXPECT_EQ(link->describe(), "serial /dev/ttyX at 2000000 baud");
    EXPECT_FALSE(serial.is_open());  // made, not opened
}

class SerialPortTest : public ::testing::Test {
  protected:
    PtyPair pair_;
};

TEST_F(SerialPortTest, TheLineIsRaw8N1AtTheBaudRateWithHupclCleared) {
    // Start from a cooked line with HUPCL set, as a terminal would leave it.
    termios cooked{};
    ASSERT_EQ(tcgetattr(pair_.slave(), &cooked), 0);
    cooked.c_lflag |= ICANON | ECHO | ISIG;
    cooked.c_iflag |= ICRNL | IXON | IXOFF;
    cooked.c_oflag |= OPOST | ONLCR;
    cooked.c_cflag |= HUPCL | PARENB;
    ASSERT_EQ(tcsetattr(pair_.slave(), TCSANOW, &cooked), 0);

    SerialSettings settings = settings_for(pair_.slave_path());
    settings.baud = 115'200;
    SerialLink link(settings);
    link.open();
    termios line{};
    ASSERT_EQ(tcgetattr(pair_.slave(), &line), 0);  // the same tty, seen from our descriptor
    EXPECT_EQ(cfgetospeed(&line), B115200);
    EXPECT_EQ(cfgetispeed(&line), B115200);
    EXPECT_EQ(line.c_lflag & (ICANON | ECHO | ECHONL | ISIG | IEXTEN), 0u);
    EXPECT_EQ(line.c_iflag & (ICRNL | INLCR | IGNCR | IXON | IXOFF | IXANY | ISTRIP), 0u);
    EXPECT_EQ(line.c_oflag & OPOST, 0u);
    EXPECT_EQ(line.c_cflag & CSIZE, static_cast<tcflag_t>(CS8));
    EXPECT_EQ(line.c_cflag & (PARENB | CSTOPB | CRTSCTS), 0u);
    EXPECT_EQ(line.c_cflag & (CLOCAL | CREAD), static_cast<tcflag_t>(CLOCAL | CREAD));
    EXPECT_EQ(line.c_cflag & HUPCL, 0u);  // closing must not drop DTR (docs/transport-serial.md)
    EXPECT_EQ(line.c_cc[VMIN], 0);
    EXPECT_EQ(line.c_cc[VTIME], 0);
    // A pty has no serial_struct: no low latency to ask for, and open() did not mind.
    EXPECT_FALSE(link.report().low_latency);
    EXPECT_EQ(link.report().latency_timer_ms, -1);
    EXPECT_EQ(link.describe(), "serial " + pair_.slave_path() + " at 115200 baud");

    // Every byte value goes through unchanged (no CR/LF mapping, no XON/XOFF, no echo).
    Bytes all(256);
    for (int i = 0; i < 256; ++i) all[static_cast<std::size_t>(i)] = static_cast<std::byte>(i);
    ASSERT_EQ(write(pair_.master(), all.data(), all.size()), 256);
    Bytes got(512);
    std::size_t total = 0;
    for (int attempt = 0; attempt < 200 && total < 256; ++attempt) {
        const ssize_t n = ::read(pair_.slave(), got.data() + total, got.size() - total);
        if (n > 0) total += static_cast<std::size_t>(n);
        usleep(1000);
    }
    got.resize(total);
    EXPECT_EQ(got, all);
}

TEST_F(SerialPortTest, ExclusiveHoldsThePortAgainstASecondOpener) {
    SerialLink first(settings_for(pair_.slave_path()));
    first.open();
    int excl = 0;
    ASSERT_EQ(ioctl(pair_.slave(), TIOCGEXCL, &excl), 0);
    EXPECT_EQ(excl, 1);  // TIOCEXCL (root passes it anyway: flock holds against root too)

    const std::string busy = open_error(settings_for(pair_.slave_path()));
    EXPECT_THAT(busy, HasSubstr("serial port " + pair_.slave_path() +
                                " (device.serial.port in test.toml): busy"));
    EXPECT_THAT(busy, HasSubstr("pid " + std::to_string(getpid())));  // who holds it
    EXPECT_THAT(busy, HasSubstr("device.serial.exclusive = false"));

    first.close();
    ASSERT_EQ(ioctl(pair_.slave(), TIOCGEXCL, &excl), 0);
    EXPECT_EQ(excl, 0);
    EXPECT_EQ(open_error(settings_for(pair_.slave_path())), "");  // free again
}

TEST_F(SerialPortTest, NotExclusiveShares) {
    SerialSettings shared = settings_for(pair_.slave_path());
    shared.exclusive = false;
    SerialLink first(shared);
    first.open();
    EXPECT_EQ(open_error(shared), "");
    int excl = 1;
    ASSERT_EQ(ioctl(pair_.slave(), TIOCGEXCL, &excl), 0);
    EXPECT_EQ(excl, 0);
}

TEST_F(SerialPortTest, ResetOnOpenNeedsModemControlLines) {
    SerialSettings settings = settings_for(pair_.slave_path());
    settings.reset_on_open = true;
    const std::string message = open_error(settings);
    EXPECT_THAT(message, HasSubstr("device.serial.reset_on_open = true, but DTR cannot be "
                                   "driven on this port"));
}

TEST(SerialPortErrors, NotFoundListsThePortsThatExist) {
    const ScratchDir by_id;  // a /dev/serial/by-id of our own
    const std::filesystem::path& dir = by_id.path();
    std::filesystem::create_symlink("../../ttyACM7", dir / "usb-Lab_Paddle_HX-0042-if00");
    SerialSettings settings = settings_for("/dev/ttyHAPTIC-missing");
    const std::string listed = device::serial::open_error_message(ENOENT, settings, dir.string());
    EXPECT_THAT(listed, HasSubstr("serial port /dev/ttyHAPTIC-missing (device.serial.port in "
                                  "test.toml): not found"));
    EXPECT_THAT(listed, HasSubstr("usb-Lab_Paddle_HX-0042-if00 -> ../../ttyACM7"));

    // A by-id style link whose device is gone: the message says so.
    const std::filesystem::path dangling = dir / "usb-Gone-if00";
    std::filesystem::create_symlink("/dev/ttyHAPTIC-gone", dangling);
    EXPECT_THAT(open_error(settings_for(dangling.string())),
                HasSubstr("not found. It is a link to /dev/ttyHAPTIC-gone, which does not exist"));

    // The real thing: the real open(), this machine's /dev/serial/by-id (none here).
    const std::string real = open_error(settings);
    EXPECT_THAT(real, HasSubstr("/dev/ttyHAPTIC-missing (device.serial.port in test.toml): "
                                "not found"));
    if (!std::filesystem::exists("/dev/serial/by-id")) {
        EXPECT_THAT(real, HasSubstr("is the device plugged in"));
    }
}

TEST(SerialPortErrors, NotATerminal) {
    EXPECT_THAT(open_error(settings_for("/dev/null")),
                HasSubstr("/dev/null (device.serial.port in test.toml): not a serial port"));
}

TEST(SerialPortErrors, PermissionDeniedSaysWhichGroupAndTheUdevRule) {
    // A real EACCES: open() from a child process that dropped to nobody; a pty slave is
    // crw--w---- (owner and group tty) for its owner only.
    if (geteuid() != 0) GTEST_SKIP() << "needs root to drop privileges to nobody";
    PtyPair pair;
    int pipe_fds[2];
    ASSERT_EQ(pipe(pipe_fds), 0);
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        close(pipe_fds[0]);
        std::string message = "setuid failed";
        if (setgid(65534) == 0 && setuid(65534) == 0) {
            message = open_error(settings_for(pair.slave_path()));
        }
        (void)!write(pipe_fds[1], message.data(), message.size());
        _exit(0);
    }
    close(pipe_fds[1]);
    std::string message;
    char buffer[512];
    for (ssize_t n; (n = ::read(pipe_fds[0], buffer, sizeof buffer)) > 0;) {
        message.append(buffer, static_cast<std::size_t>(n));
    }
    close(pipe_fds[0]);
    int status = 0;
    waitpid(child, &status, 0);
    EXPECT_THAT(message, HasSubstr("(device.serial.port in test.toml): permission denied"));
    EXPECT_THAT(message, HasSubstr("config/udev/70-hapticd.rules"));
    // Who owns it, as stat() says (devpts here: root, mode 600 or 620, group root or tty).
    struct stat info {};
    ASSERT_EQ(stat(pair.slave_path().c_str(), &info), 0);
    char mode[8];
    std::snprintf(mode, sizeof mode, "%03o", static_cast<unsigned>(info.st_mode & 0777));
    EXPECT_THAT(message, HasSubstr(std::string("mode ") + mode));
    // Its group may not write it: joining the group would not help, and the message does
    // not say it would.
    EXPECT_THAT(message, ::testing::Not(HasSubstr("usermod")));
}

TEST(SerialPortErrors, PermissionDeniedOnAGroupNodeSuggestsTheGroup) {
    // A node like /dev/ttyACM0 on Debian: root:dialout, mode 660.
    if (geteuid() != 0 || getgrnam("dialout") == nullptr) GTEST_SKIP() << "needs root, dialout";
    const ScratchDir dir;
    const std::string path = dir.write("ttyACM0", "");
    ASSERT_EQ(chown(path.c_str(), 0, getgrnam("dialout")->gr_gid), 0);
    ASSERT_EQ(chmod(path.c_str(), 0660), 0);
    const std::string message = device::serial::open_error_message(EACCES, settings_for(path));
    EXPECT_THAT(message, HasSubstr("it belongs to user root, group dialout, mode 660"));
    EXPECT_THAT(message, HasSubstr("sudo usermod -aG dialout $USER"));
    EXPECT_THAT(message, HasSubstr("config/udev/70-hapticd.rules"));
}

TEST(SerialPortErrors, OtherErrnoValues) {
    const SerialSettings settings = settings_for("/dev/ttyACM0");
    EXPECT_THAT(device::serial::open_error_message(EBUSY, settings),
                HasSubstr("busy: another program has it open exclusively"));
    EXPECT_THAT(device::serial::open_error_message(ENODEV, settings),
                HasSubstr("no device behind it"));
    EXPECT_THAT(device::serial::open_error_message(EIO, settings),
                HasSubstr("being unplugged or reset"));
    EXPECT_THAT(device::serial::open_error_message(EACCES, settings),
                HasSubstr("config/udev/70-hapticd.rules"));
}

}  // namespace
}  // namespace hapticd::testing
