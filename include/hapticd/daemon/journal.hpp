// Priorities on hapticd's messages for the journal (sd-daemon(3), systemd.exec(5)).
//
// A message line that begins with "<N>" (SD_ERR, SD_WARNING, SD_NOTICE, SD_INFO) has syslog
// priority N; a line without one is SD_INFO. When stderr is the journal's stream
// (JOURNAL_STREAM names its device and inode), the prefixes are passed on and journald takes
// them, so that `journalctl -p warning -u hapticd@NAME` shows the faults and errors only.
// Anywhere else (a terminal, a file, a test's stream) PriorityLineFilter strips them.
#pragma once

#include <array>
#include <cstddef>
#include <streambuf>

namespace hapticd::daemon::priority {

inline constexpr const char* err = "<3>";      ///< the run cannot start or ends on a fault
inline constexpr const char* warning = "<4>";  ///< a fault, a refusal, a lost output
inline constexpr const char* notice = "<5>";   ///< a fault cleared, a stop by signal
inline constexpr const char* info = "<6>";     ///< what runs, and its figures

}  // namespace hapticd::daemon::priority

namespace hapticd::daemon {

/// True when `fd` is the stream systemd connected to the journal: JOURNAL_STREAM is
/// "DEVICE:INODE" of `fd` (systemd.exec(5)).
bool is_journal_stream(int fd);

/// Passes characters on to `target`; unless `keep_priorities`, drops a "<N>" (N one digit)
/// at the start of each line.
class PriorityLineFilter : public std::streambuf {
  public:
    PriorityLineFilter(std::streambuf* target, bool keep_priorities)
        : target_(target), keep_(keep_priorities) {}
    /// What may have been the start of a prefix, when no more comes: text after all.
    ~PriorityLineFilter() override;
    PriorityLineFilter(const PriorityLineFilter&) = delete;
    PriorityLineFilter& operator=(const PriorityLineFilter&) = delete;

  protected:
    int_type overflow(int_type c) override;
    int sync() override;

  private:
    bool flush_pending();
    std::streambuf* target_;
    bool keep_;
    bool line_start_ = true;
    std::array<char, 3> pending_{};  ///< the start of a line that may be "<N>"
    std::size_t pending_size_ = 0;
};

}  // namespace hapticd::daemon
