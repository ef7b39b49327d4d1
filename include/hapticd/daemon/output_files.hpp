// The files a run writes (--log, --summary), checked and opened before the device is: an
// output that is also an input (the config, the scene, the plugin) or another output is
// refused, the telemetry log is locked against a second daemon, and a path that cannot be
// created is found before the run, not after it. Every refusal is an OutputError whose
// message names the option(s) and the path; hapticd exits 2 on it.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "hapticd/input/input_error.hpp"

namespace hapticd::daemon {

/// An output path refused, or not created, before the run: bad input (exit 2).
struct OutputError : input::InputError {
    explicit OutputError(const std::string& message) : InputError(message) {}
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

/// An output opened before the run: created when missing, not yet emptied. Until begin(),
/// destroying it removes the file if it created it (a refused run leaves no output behind)
/// and leaves a file that was there as it was.
class OutputFile {
  public:
    OutputFile() = default;
    OutputFile(OwnedFd fd, std::string option, std::string path, bool created)
        : fd_(std::move(fd)),
          option_(std::move(option)),
          path_(std::move(path)),
          created_(created) {}
    ~OutputFile();
    OutputFile(OutputFile&&) noexcept = default;
    OutputFile& operator=(OutputFile&&) noexcept = default;
    OutputFile(const OutputFile&) = delete;
    OutputFile& operator=(const OutputFile&) = delete;

    /// The run starts: empties the file (when it is a regular file) and keeps it from now
    /// on. Throws OutputError.
    void begin();
    int fd() const noexcept { return fd_.get(); }
    /// The descriptor, now owned by the caller.
    int release() noexcept { return fd_.release(); }
    explicit operator bool() const noexcept { return static_cast<bool>(fd_); }

  private:
    OwnedFd fd_;
    std::string option_;
    std::string path_;
    bool created_ = false;
    bool begun_ = false;
};

/// Opens (creating it, mode 0644) the telemetry log `path` for `option` and takes an
/// exclusive write lock on it without waiting (fcntl F_SETLK): a second daemon on the same
/// file is refused, naming the holder's pid, and the first one's log is not touched.
/// Throws OutputError.
OutputFile open_locked_log(const std::string& option, const std::string& path);

/// Opens (creating it) `path` for `option` now, so that an unwritable path is found before
/// the run. Throws OutputError.
OutputFile open_output(const std::string& option, const std::string& path);

/// Writes all of `text` to `fd`; false (errno set) when the system refused part of it.
bool write_all(int fd, const std::string& text) noexcept;

}  // namespace hapticd::daemon
