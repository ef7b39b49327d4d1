// What names a run in its summary and its file names (docs/daemon.md "Summary"): the
// version that ran, when it started and on which host. `{start}` in --log and --summary is
// replaced by the start time, so that each start of a service writes files of its own.
#pragma once

#include <chrono>
#include <string>

namespace hapticd::daemon {

struct RunStamp {
    std::string version;     ///< hapticd's version (install/version.hpp)
    std::string started_at;  ///< ISO 8601, UTC, milliseconds: 2026-12-03T12:41:00.123Z
    std::string start_name;  ///< the same instant for a file name: 20261203T124100.123Z
    std::string host;        ///< gethostname()
};

/// The stamp of a run that starts at `start`.
RunStamp stamp_run(std::chrono::system_clock::time_point start);

/// The placeholder that with_start() replaces.
inline constexpr const char* kStartPlaceholder = "{start}";

/// `path` with every `{start}` replaced by the stamp's start_name.
std::string with_start(std::string path, const RunStamp& stamp);

}  // namespace hapticd::daemon
