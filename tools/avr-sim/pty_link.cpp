#include "pty_link.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

namespace hapticd::avr_sim {
namespace {

[[noreturn]] void fail(const std::string& what) {
    throw std::runtime_error(what + ": " + std::strerror(errno));
}

}  // namespace

PtyLink::PtyLink(const std::string& link_path) : link_path_(link_path) {
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (master_ < 0) fail("posix_openpt");
    if (::grantpt(master_) != 0 || ::unlockpt(master_) != 0) fail("grantpt/unlockpt");
    const char* name = ::ptsname(master_);
    if (name == nullptr) fail("ptsname");
    slave_path_ = name;
    slave_ = ::open(slave_path_.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (slave_ < 0) fail("open " + slave_path_);
    termios raw{};
    if (::tcgetattr(slave_, &raw) != 0) fail("tcgetattr " + slave_path_);
    ::cfmakeraw(&raw);
    if (::tcsetattr(slave_, TCSANOW, &raw) != 0) fail("tcsetattr " + slave_path_);
    struct stat existing {};
    if (::lstat(link_path_.c_str(), &existing) == 0) {
        if (!S_ISLNK(existing.st_mode)) {
            errno = EEXIST;
            fail("--link " + link_path_ + " exists and is not a symbolic link");
        }
        ::unlink(link_path_.c_str());
    }
    if (::symlink(slave_path_.c_str(), link_path_.c_str()) != 0) fail("--link " + link_path_);
}

PtyLink::~PtyLink() {
    ::unlink(link_path_.c_str());
    if (slave_ >= 0) ::close(slave_);
    if (master_ >= 0) ::close(master_);
}

std::size_t PtyLink::read(std::uint8_t* bytes, std::size_t capacity) {
    const ssize_t n = ::read(master_, bytes, capacity);
    if (n > 0) return static_cast<std::size_t>(n);
    if (n < 0 && errno != EAGAIN && errno != EINTR && errno != EIO) fail("read " + slave_path_);
    return 0;
}

void PtyLink::write(const std::uint8_t* bytes, std::size_t size) {
    std::size_t written = 0;
    int waits = 0;
    while (written < size) {
        const ssize_t n = ::write(master_, bytes + written, size - written);
        if (n > 0) {
            written += static_cast<std::size_t>(n);
            continue;
        }
        if (n < 0 && errno != EAGAIN && errno != EINTR) fail("write " + slave_path_);
        if (++waits > 1000) return;  // nobody reads: the bytes are lost, as on a real line
        pollfd port{master_, POLLOUT, 0};
        ::poll(&port, 1, 1);
    }
}

bool PtyLink::wait_readable(std::int64_t timeout_ns) {
    pollfd port{master_, POLLIN, 0};
    const timespec timeout{static_cast<time_t>(timeout_ns / 1'000'000'000),
                           static_cast<long>(timeout_ns % 1'000'000'000)};
    return ::ppoll(&port, 1, &timeout, nullptr) > 0 && (port.revents & POLLIN) != 0;
}

}  // namespace hapticd::avr_sim
