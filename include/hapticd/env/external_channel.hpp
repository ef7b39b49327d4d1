// The shared memory of an external world (external_world.h): created by the daemon per
// instance, read and written by the servo tick without waiting, removed when the daemon lets
// go. The file policy (docs/external-worlds.md): the path is the control socket's with
// ".world" for ".sock" (the socket's directory, the socket's group); the daemon creates it
// with O_EXCL and O_NOFOLLOW; a channel there already is replaced only when it is a channel
// that its daemon let go of, or whose daemon is gone; anything else there is refused, by name.
// A scene loaded while a scene of this process renders through the path (hapticctl scene)
// makes its channel at PATH.next, and claim_path() moves it into place once the loop has taken
// the scene: a scene that is refused leaves the world in force its file.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <string>

#include "hapticd/env/external_world.h"

namespace hapticd::env {

/// What the header says about the run (written once).
struct ChannelShape {
    std::uint32_t axes = 1;
    std::uint32_t lockstep_every = 0;
    double rate_hz = 1000.0;
    double stale_after_s = 0.1;
};

/// The channel beside a control socket: SOCKET.sock -> SOCKET.world, else SOCKET + ".world".
std::string channel_beside(const std::string& socket_path);

class ExternalChannel {
  public:
    /// Creates the channel at `path`, mode 0660 and given to `group` when it exists (and the
    /// daemon may; else `note` says so); "" for a private mapping no other process can reach
    /// (a reader that only checks a scene). Throws std::runtime_error naming the path and why.
    ExternalChannel(const std::string& path, const ChannelShape& shape, const std::string& group,
                    std::string& note);
    /// Marks the channel closed, unmaps it and removes the file if it is still this one.
    ~ExternalChannel();
    ExternalChannel(const ExternalChannel&) = delete;
    ExternalChannel& operator=(const ExternalChannel&) = delete;

    /// Where worlds find it, once claimed.
    const std::string& path() const noexcept { return path_; }
    /// Moves a channel made beside one in force into its path (no-op otherwise): "" or why not.
    std::string claim_path();

    /// The daemon's block, sequence-locked (one writer: the servo tick). Never waits.
    void publish(const hapticd_world_tick& tick) noexcept;
    /// One attempt at a consistent copy of the world's block: false while it is being written
    /// or when a write raced the copy. Never waits.
    bool try_take(hapticd_world_update& update) const noexcept;

  private:
    /// Where the file is now: path_, or staged_path_ until claimed.
    const std::string& file_path() const noexcept {
        return staged_path_.empty() ? path_ : staged_path_;
    }

    std::string path_;
    std::string staged_path_;  ///< PATH.next until claim_path()
    int fd_ = -1;
    void* memory_ = nullptr;
    dev_t device_ = 0;
    ino_t inode_ = 0;
};

}  // namespace hapticd::env
