// The files a run writes (--log, --summary), checked and opened before the device is: an
// output that is also an input (the config, the scene, the plugin) or another output is
// refused, the telemetry log is locked against a second daemon, and a path that cannot be
// created is found before the run, not after it. Every refusal is an OutputError whose
// message names the option(s) and the path; hapticd exits 2 on it.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace hapticd::daemon {

struct OutputError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// A file and the option (or config key) that names it: {"--config", "lab.toml"}.
struct NamedPath {
    std::string option;
    std::string path;
};

/// Throws OutputError when an output names the same file as an input or as another output:
/// the same inode (st_dev, st_ino) for files that exist, else the same canonical path
/// (symlinks and ".." resolved). Two outputs on one character device (/dev/null) are allowed.
void refuse_overlapping_paths(const std::vector<NamedPath>& inputs,
                              const std::vector<NamedPath>& outputs);

/// The shared object `plugin` (a name or a path, as [device] plugin) resolves to, as
/// device::load_device() would find it; empty when none is found (the load will say so).
std::string plugin_file(const std::string& plugin);

/// A file descriptor that closes itself.
class OwnedFd {
  public:
    OwnedFd() = default;
    explicit OwnedFd(int fd) : fd_(fd) {}
    ~OwnedFd();
    OwnedFd(OwnedFd&& other) noexcept : fd_(other.release()) {}
    OwnedFd& operator=(OwnedFd&& other) noexcept;
    OwnedFd(const OwnedFd&) = delete;
    OwnedFd& operator=(const OwnedFd&) = delete;
    int get() const noexcept { return fd_; }
    int release() noexcept {
        const int fd = fd_;
        fd_ = -1;
        return fd;
    }
    explicit operator bool() const noexcept { return fd_ >= 0; }

  private:
    int fd_ = -1;
};

/// Opens (creating it, mode 0644) the telemetry log `path` for `option`, takes an exclusive
/// write lock on it without waiting (fcntl F_SETLK; a second daemon on the same file is
/// refused, naming the holder's pid), and only then empties it. Throws OutputError.
OwnedFd open_locked_log(const std::string& option, const std::string& path);

/// Creates (or empties) `path` for `option` now, so that an unwritable path is found before
/// the run. Throws OutputError.
OwnedFd open_output(const std::string& option, const std::string& path);

/// Writes all of `text` to `fd`; false (errno set) when the system refused part of it.
bool write_all(int fd, const std::string& text) noexcept;

}  // namespace hapticd::daemon
