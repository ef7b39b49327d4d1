#include "hapticd/install/group_access.hpp"

#include <fcntl.h>
#include <grp.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>

namespace hapticd::install {

std::string give_to_group(const std::string& path, const std::string& group_name,
                          const std::string& what, const std::string& doc) {
    if (group_name.empty()) return {};
    std::array<char, 4096> buffer{};
    struct group entry {};
    struct group* found = nullptr;
    if (::getgrnam_r(group_name.c_str(), &entry, buffer.data(), buffer.size(), &found) != 0 ||
        found == nullptr) {
        return what + ": no group \"" + group_name +
               "\" on this system, so only this daemon's user may connect (" + doc + ")";
    }
    // Under the unit the file is born in group hapticd (Group=hapticd), and chown() is outside
    // its system call filter (@privileged): only a daemon in another group, root outside the
    // unit, hands the file over (docs/install.md).
    struct stat st {};
    if (::lstat(path.c_str(), &st) == 0 && st.st_gid == found->gr_gid) return {};
    if (::fchownat(AT_FDCWD, path.c_str(), static_cast<uid_t>(-1), found->gr_gid,
                   AT_SYMLINK_NOFOLLOW) != 0) {
        return what + ": could not give it to group \"" + group_name +
               "\": " + std::strerror(errno) + "; only this daemon's user may connect";
    }
    return {};
}

}  // namespace hapticd::install
