#include "outputs/outputs_directory.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <ostream>
#include <stdexcept>

#include "hapticd/daemon/journal.hpp"

namespace hapticd::daemon {
namespace {

// The longest file name (NAME_MAX).
constexpr std::size_t kMaxNameBytes = 255;

const char* const kAllowed =
    "allowed a file name alone (take1.csv), or an absolute path to a file directly in ";

// The directory of --log or --summary FILE, when that names a regular file (or one still to
// be made): /dev/null's directory is no place for a run's files.
std::optional<std::string> directory_of_output(const std::string& file) {
    struct stat st {};
    if (::stat(file.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) return std::nullopt;
    const std::filesystem::path parent = std::filesystem::path(file).parent_path();
    return parent.empty() ? std::string(".") : parent.string();
}

}  // namespace

OutputsDirectory::OutputsDirectory(std::string path) : path_(std::move(path)) {
    fd_ = ::open(path_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd_ < 0) throw std::runtime_error(path_ + ": " + std::strerror(errno));
}

OutputsDirectory::~OutputsDirectory() { ::close(fd_); }

OutputsDirectory::NewFile OutputsDirectory::create(const std::string& name) const {
    NewFile file{.fd = -1, .path = (std::filesystem::path(path_) / name).string(), .error = {}};
    file.fd =
        ::openat(fd_, name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0640);
    if (file.fd < 0) {
        const int error = errno;
        file.error = error == EEXIST ? std::string("it exists, and no file is ever overwritten")
                                     : std::string(std::strerror(error));
    }
    return file;
}

bool OutputsDirectory::remove(const std::string& name) const {
    return ::unlinkat(fd_, name.c_str(), 0) == 0;
}

OutputsDirectory::ClientFile OutputsDirectory::client_file(const std::string& requested) const {
    const auto refused = [&](const std::string& why) {
        return ClientFile{.name = {},
                          .refusal = "\"" + requested + "\" " + why + ": " + kAllowed + path_ +
                                     " (docs/control.md, \"Paths and strings\")"};
    };
    const std::filesystem::path path(requested);
    if (path.is_absolute()) {
        if (path.lexically_normal().string() != requested || path.filename().empty()) {
            return refused("is not in normal form (a '.', '..', '//' or a trailing '/')");
        }
        struct stat wanted {};
        struct stat ours {};
        if (::stat(path.parent_path().c_str(), &wanted) != 0 || ::fstat(fd_, &ours) != 0 ||
            wanted.st_dev != ours.st_dev || wanted.st_ino != ours.st_ino) {
            return refused("is outside this daemon's directory for a client's files");
        }
    } else if (requested.find('/') != std::string::npos) {
        return refused("is a relative path (the daemon's working directory is not the client's)");
    }
    std::string name = path.filename().string();
    if (name.empty() || name == "." || name == ".." || name.front() == '.') {
        return refused("is no file name a client may have (empty, or beginning with '.')");
    }
    if (name.size() > kMaxNameBytes) return refused("has a name longer than 255 bytes");
    return {.name = std::move(name), .refusal = {}};
}

std::optional<std::string> outputs_directory_path(const RunOptions& options) {
    if (const char* logs = std::getenv("LOGS_DIRECTORY"); logs != nullptr && *logs != '\0') {
        const std::string all(logs);
        return all.substr(0, all.find(':'));
    }
    if (options.log_path) {
        if (auto directory = directory_of_output(*options.log_path)) return directory;
    }
    if (options.summary_path && *options.summary_path != "-") {
        return directory_of_output(*options.summary_path);
    }
    return std::nullopt;
}

std::unique_ptr<OutputsDirectory> open_outputs_directory(const RunOptions& options,
                                                         std::ostream& log) {
    const std::optional<std::string> path = outputs_directory_path(options);
    if (!path) return nullptr;
    try {
        return std::make_unique<OutputsDirectory>(*path);
    } catch (const std::exception& e) {
        log << priority::warning << "hapticd: WARNING: the directory for the flight recorder's "
            << "files and a client's recordings cannot be opened: " << e.what()
            << "; they will have nowhere to go\n";
        return nullptr;
    }
}

}  // namespace hapticd::daemon
