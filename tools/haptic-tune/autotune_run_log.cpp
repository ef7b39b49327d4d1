#include "autotune_run_log.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "autotune_error.hpp"

namespace hapticd::tools {
namespace {

/// The directory for the run's temporary log: $TMPDIR when set and not empty, else /tmp.
/// A TMPDIR that is not a directory is an error (exit 2, before anything runs), not a
/// reason to pick another directory: whoever set it expects temporary files there, as
/// mktemp(1) does.
std::string temporary_directory() {
    const char* tmpdir = std::getenv("TMPDIR");
    if (tmpdir == nullptr || *tmpdir == '\0') return "/tmp";
    const std::string named = "TMPDIR=" + std::string(tmpdir);
    const std::string why =
        ": the identification run's temporary log goes there; set TMPDIR to a directory, or "
        "give --record FILE to keep the log in FILE; nothing was run or written";
    struct stat st {};
    if (::stat(tmpdir, &st) != 0) throw AutotuneError(named + ": " + std::strerror(errno) + why);
    if (!S_ISDIR(st.st_mode)) throw AutotuneError(named + " is not a directory" + why);
    return tmpdir;
}

}  // namespace

RunLog::~RunLog() {
    if (temporary_ && !started) ::unlink(path_.c_str());
}

void RunLog::create_temporary() {
    const std::string directory = temporary_directory();
    std::string name = directory + "/haptic-tune-autotune-XXXXXX.csv";
    const int fd = ::mkstemps(name.data(), 4);  // O_CREAT | O_EXCL, a fresh name
    if (fd < 0) {
        throw AutotuneError("cannot create a temporary file for the identification run's log in " +
                            directory + ": " + std::strerror(errno) +
                            " (set TMPDIR to another directory, or give --record FILE); "
                            "nothing was run or written");
    }
    ::close(fd);
    path_ = name;
    temporary_ = true;
}

std::string RunLog::note() const {
    if (!started) return "";
    return temporary_ ? " (the run's log is kept: " + path_ + ")"
                      : " (the run's log: " + path_ + ", --record)";
}

void RunLog::discard() {
    if (!temporary_) return;
    ::unlink(path_.c_str());
    temporary_ = false;
}

}  // namespace hapticd::tools
