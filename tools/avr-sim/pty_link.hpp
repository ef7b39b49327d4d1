// The emulated board's serial port: a pseudo-terminal whose slave a host opens as it would
// /dev/ttyACM0, reached through a symbolic link at a path the harness is given.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace hapticd::avr_sim {

class PtyLink {
  public:
    /// Creates the pty (raw, no echo) and the link at `link_path` to its slave. An existing
    /// symbolic link there is replaced; anything else is refused (std::runtime_error).
    explicit PtyLink(const std::string& link_path);
    ~PtyLink();  // removes the link
    PtyLink(const PtyLink&) = delete;
    PtyLink& operator=(const PtyLink&) = delete;

    /// Reads what the host wrote, without blocking: the bytes read (0 if none).
    std::size_t read(std::uint8_t* bytes, std::size_t capacity);
    /// Writes to the host (whole, retrying while the pty is full for at most 1 s).
    void write(const std::uint8_t* bytes, std::size_t size);
    /// Waits up to timeout_ns for the host to write; true if it did.
    bool wait_readable(std::int64_t timeout_ns);

    const std::string& slave_path() const { return slave_path_; }

  private:
    int master_ = -1;
    int slave_ = -1;  // held open so that the master never sees a hangup between hosts
    std::string slave_path_;
    std::string link_path_;
};

}  // namespace hapticd::avr_sim
