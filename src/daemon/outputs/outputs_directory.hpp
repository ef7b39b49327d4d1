// Where a run's files go beside --log and --summary, and what a client may have the daemon
// write there (docs/control.md, "Paths and strings"): the flight recorder's files, and the
// recordings and identify logs a client asks for. One directory, opened once at the start of the
// run; every file in it is created new (O_EXCL) and never through a symbolic link (O_NOFOLLOW),
// relative to the opened directory. So a path a client names cannot lead anywhere else,
// whatever `..` or links it holds, and no file there is ever overwritten.
#pragma once

#include <iosfwd>
#include <memory>
#include <optional>
#include <string>

#include "hapticd/daemon/run.hpp"

namespace hapticd::daemon {

class OutputsDirectory {
  public:
    /// Opens the directory `path`. Throws std::runtime_error naming it and why not.
    explicit OutputsDirectory(std::string path);
    ~OutputsDirectory();
    OutputsDirectory(const OutputsDirectory&) = delete;
    OutputsDirectory& operator=(const OutputsDirectory&) = delete;

    const std::string& path() const noexcept { return path_; }

    /// A file created new in the directory (mode 0640), or why not.
    struct NewFile {
        int fd = -1;        ///< the caller's to close; -1: not created
        std::string path;   ///< the directory's path and the name
        std::string error;  ///< why not: the system's reason, or that the name exists
    };
    NewFile create(const std::string& name) const;
    /// Removes `name` from the directory (a file create() made that is of no use); false when
    /// it could not.
    bool remove(const std::string& name) const;

    /// What a client's `path` names: a file name alone ("take1.csv"), or an absolute path to
    /// a file directly in this directory, however the directory is spelled (the same
    /// directory, by device and inode). `name` is empty when refused, and `refusal` says why
    /// and what is allowed.
    struct ClientFile {
        std::string name;
        std::string refusal;
    };
    ClientFile client_file(const std::string& requested) const;

  private:
    std::string path_;
    int fd_ = -1;
};

/// The run's outputs directory: $LOGS_DIRECTORY's first entry (a service's), else the
/// directory of --log, else of --summary FILE. A --log or --summary that is not a regular
/// file (/dev/null, a FIFO) names no directory. None: nullopt.
std::optional<std::string> outputs_directory_path(const RunOptions& options);

/// The run's outputs directory opened, or null when there is none or it cannot be opened
/// (a warning on `log` says why, and what will have nowhere to go).
std::unique_ptr<OutputsDirectory> open_outputs_directory(const RunOptions& options,
                                                         std::ostream& log);

/// The refusal of a client's file when the run has no outputs directory.
inline constexpr const char* kNoOutputsDirectory =
    "this daemon has no directory for a client's files: it runs without LOGS_DIRECTORY, --log "
    "or --summary FILE (docs/control.md, \"Paths and strings\")";

}  // namespace hapticd::daemon
