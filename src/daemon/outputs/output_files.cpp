#include "hapticd/daemon/output_files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <optional>

#include "hapticd/device/plugin_loader.hpp"
#include "hapticd/install/plugin_files.hpp"

namespace hapticd::daemon {
namespace {

namespace fs = std::filesystem;

struct Identity {
    std::optional<struct stat> st;  ///< when the file exists
    std::string canonical;          ///< weakly canonical absolute path
};

Identity identify(const std::string& path) {
    Identity id;
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0) id.st = st;
    std::error_code ec;
    fs::path canonical = fs::weakly_canonical(fs::absolute(path, ec), ec);
    id.canonical = ec ? path : canonical.string();
    return id;
}

bool same_file(const Identity& a, const Identity& b) {
    if (a.st && b.st) return a.st->st_dev == b.st->st_dev && a.st->st_ino == b.st->st_ino;
    if (a.st || b.st) return false;
    return a.canonical == b.canonical;
}

std::string describe(const NamedPath& p, const Identity& id) {
    std::string text = p.option + " " + p.path;
    if (id.canonical != p.path && !id.canonical.empty()) text += " (" + id.canonical + ")";
    return text;
}

}  // namespace

void refuse_overlapping_paths(const std::vector<NamedPath>& inputs,
                              const std::vector<NamedPath>& outputs) {
    std::vector<Identity> in_ids;
    in_ids.reserve(inputs.size());
    for (const NamedPath& p : inputs) in_ids.push_back(identify(p.path));
    std::vector<Identity> out_ids;
    out_ids.reserve(outputs.size());
    for (const NamedPath& p : outputs) out_ids.push_back(identify(p.path));
    for (std::size_t o = 0; o < outputs.size(); ++o) {
        for (std::size_t i = 0; i < inputs.size(); ++i) {
            if (!same_file(out_ids[o], in_ids[i])) continue;
            throw OutputError(describe(outputs[o], out_ids[o]) + " is the same file as " +
                              describe(inputs[i], in_ids[i]) + ": refusing to overwrite an " +
                              "input; give " + outputs[o].option + " another path");
        }
        for (std::size_t other = 0; other < o; ++other) {
            if (!same_file(out_ids[o], out_ids[other])) continue;
            if (out_ids[o].st && S_ISCHR(out_ids[o].st->st_mode)) continue;  // /dev/null
            throw OutputError(describe(outputs[o], out_ids[o]) + " is the same file as " +
                              describe(outputs[other], out_ids[other]) +
                              ": two outputs cannot share a file; give each its own path");
        }
    }
}

std::string plugin_file(const std::string& plugin) {
    if (plugin.empty()) return {};
    if (plugin.find('/') != std::string::npos) return plugin;
    for (const std::string& dir : install::plugin_search_path()) {
        for (const std::string& file : install::plugin_file_names("device", plugin)) {
            std::string path = dir + "/" + file;
            std::error_code ec;
            if (fs::is_regular_file(path, ec)) return path;
        }
    }
    return {};
}

OwnedFd::~OwnedFd() {
    if (fd_ >= 0) ::close(fd_);
}

OwnedFd& OwnedFd::operator=(OwnedFd&& other) noexcept {
    if (this != &other) {
        if (fd_ >= 0) ::close(fd_);
        fd_ = other.release();
    }
    return *this;
}

namespace {

/// Opens `path` for writing, creating it if it is missing (and saying so); no truncation.
OutputFile open_for_writing(const std::string& option, const std::string& path) {
    bool created = true;
    int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0 && errno == EEXIST) {
        created = false;
        fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
        // A dangling symlink: create its target (and leave it, like any existing name).
        if (fd < 0 && errno == ENOENT)
            fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
    }
    if (fd < 0) {
        throw OutputError(option + " " + path +
                          ": cannot create the file: " + std::strerror(errno));
    }
    return OutputFile(OwnedFd(fd), option, path, created);
}

}  // namespace

OutputFile::~OutputFile() {
    if (fd_ && created_ && !begun_) ::unlink(path_.c_str());
}

void OutputFile::begin() {
    begun_ = true;
    struct stat st {};
    if (!fd_ || ::fstat(fd_.get(), &st) != 0 || !S_ISREG(st.st_mode)) return;
    if (::ftruncate(fd_.get(), 0) != 0) {
        throw OutputError(option_ + " " + path_ +
                          ": cannot empty the file: " + std::strerror(errno));
    }
}

OutputFile open_locked_log(const std::string& option, const std::string& path) {
    // No O_TRUNC: the file may be another daemon's live log; it is emptied once it is ours
    // and the run starts (OutputFile::begin()).
    OutputFile file = open_for_writing(option, path);
    struct stat st {};
    if (::fstat(file.fd(), &st) != 0 || !S_ISREG(st.st_mode)) return file;  // /dev/null, a pipe
    struct flock lock {};
    lock.l_type = F_WRLCK;
    lock.l_whence = SEEK_SET;  // l_start = l_len = 0: the whole file
    if (::fcntl(file.fd(), F_SETLK, &lock) != 0) {
        const int error = errno;
        if (error == EACCES || error == EAGAIN) {
            struct flock holder {};
            holder.l_type = F_WRLCK;
            holder.l_whence = SEEK_SET;
            std::string who = "another process";
            if (::fcntl(file.fd(), F_GETLK, &holder) == 0 && holder.l_type != F_UNLCK &&
                holder.l_pid > 0) {
                who = "process " + std::to_string(holder.l_pid);
            }
            throw OutputError(option + " " + path + ": the file is locked by " + who +
                              " (another hapticd writing its telemetry there?); give " + option +
                              " another path");
        }
        throw OutputError(option + " " + path + ": cannot lock the file: " + std::strerror(error));
    }
    return file;
}

OutputFile open_output(const std::string& option, const std::string& path) {
    return open_for_writing(option, path);
}

bool write_all(int fd, const std::string& text) noexcept {
    std::size_t done = 0;
    while (done < text.size()) {
        const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) return false;
        if (n == 0) {
            errno = EIO;
            return false;
        }
        done += static_cast<std::size_t>(n);
    }
    return true;
}

}  // namespace hapticd::daemon
