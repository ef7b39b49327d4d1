// Where autotune's identification run writes its log: --record FILE, or a temporary file
// (docs/autotune.md "The file written").
#pragma once

#include <string>

namespace hapticd::tools {

/// The identification run's log, when autotune runs hapticd: --record FILE (the user's,
/// always kept), or a temporary file created exclusively in $TMPDIR (else /tmp). The
/// temporary is removed only when autotune succeeds; once hapticd has started, every
/// failure keeps it (hapticd's last message may name it) and autotune's error names it. A
/// temporary that hapticd never got (nothing ran) is removed.
class RunLog {
  public:
    RunLog() = default;
    RunLog(const RunLog&) = delete;
    RunLog& operator=(const RunLog&) = delete;
    ~RunLog();

    void record_to(const std::string& path) { path_ = path; }
    /// A fresh file in $TMPDIR (else /tmp), created exclusively. Throws AutotuneError,
    /// naming the directory, when TMPDIR is not a directory or the file cannot be made.
    void create_temporary();
    const std::string& path() const { return path_; }
    bool temporary() const { return temporary_; }

    /// For an error message: where the log is, once hapticd has started.
    std::string note() const;
    /// Success: the temporary is not needed any more.
    void discard();

    bool started = false;  ///< hapticd was started: the file is its log

  private:
    std::string path_;
    bool temporary_ = false;
};

}  // namespace hapticd::tools
