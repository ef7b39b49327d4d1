#include "hapticd/env/external_channel.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "hapticd/install/group_access.hpp"

namespace hapticd::env {
namespace {

constexpr std::size_t kWord = sizeof(std::uint64_t);
constexpr std::string_view kSocketSuffix = ".sock";

std::string errno_text(int error) { return std::strerror(error); }

std::runtime_error channel_error(const std::string& path, const std::string& why) {
    return std::runtime_error("external world channel " + path + ": " + why);
}

// The words of a block in the mapping, as atomics: a seqlock's payload in relaxed atomic
// words has no data race (Boehm 2012, as servo/seqlock.hpp).
std::atomic_ref<std::uint64_t> word(void* memory, std::size_t offset) {
    return std::atomic_ref<std::uint64_t>(
        *static_cast<std::uint64_t*>(static_cast<void*>(static_cast<char*>(memory) + offset)));
}

template <typename Block>
void store_block(void* memory, std::size_t offset, const Block& block) noexcept {
    static_assert(sizeof(Block) % kWord == 0);
    std::array<std::uint64_t, sizeof(Block) / kWord> words{};
    std::memcpy(words.data(), &block, sizeof(Block));
    auto sequence = word(memory, offset);
    const std::uint64_t before = sequence.load(std::memory_order_relaxed);
    sequence.store(before + 1, std::memory_order_relaxed);  // odd: a write in progress
    std::atomic_thread_fence(std::memory_order_release);
    for (std::size_t i = 1; i < words.size(); ++i) {
        word(memory, offset + i * kWord).store(words[i], std::memory_order_relaxed);
    }
    sequence.store(before + 2, std::memory_order_release);
}

template <typename Block>
bool try_load_block(void* memory, std::size_t offset, Block& block) noexcept {
    auto sequence = word(memory, offset);
    const std::uint64_t before = sequence.load(std::memory_order_acquire);
    if ((before & 1u) != 0u) return false;
    std::array<std::uint64_t, sizeof(Block) / kWord> words{};
    words[0] = before;
    for (std::size_t i = 1; i < words.size(); ++i) {
        words[i] = word(memory, offset + i * kWord).load(std::memory_order_relaxed);
    }
    std::atomic_thread_fence(std::memory_order_acquire);
    if (sequence.load(std::memory_order_relaxed) != before) return false;
    std::memcpy(static_cast<void*>(&block), words.data(), sizeof(Block));
    return true;
}

bool process_alive(pid_t pid) { return pid > 0 && (::kill(pid, 0) == 0 || errno == EPERM); }

// What is at a channel's path already, when it is not refused (judge_existing throws).
enum class Existing {
    replaceable,  ///< nothing, or a channel whose daemon let go of it or is gone
    ours,         ///< the channel of a scene this process renders now
};

Existing judge_existing(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0) {
        if (errno == ENOENT) return Existing::replaceable;  // gone meanwhile
        throw channel_error(path, "exists, and cannot be read to see whose it is (" +
                                      errno_text(errno) + "): remove it");
    }
    hapticd_world_header header{};
    const ssize_t got = ::pread(fd, &header, sizeof header, 0);
    ::close(fd);
    if (got != static_cast<ssize_t>(sizeof header) ||
        std::memcmp(header.magic, HAPTICD_WORLD_MAGIC, sizeof header.magic) != 0) {
        throw channel_error(path,
                            "exists and is not an external world's channel: remove it, or "
                            "give the control socket another name");
    }
    if (header.closed != 0u) return Existing::replaceable;
    if (header.daemon_pid == ::getpid()) return Existing::ours;
    if (process_alive(header.daemon_pid)) {
        throw channel_error(path, "is in use: hapticd pid " + std::to_string(header.daemon_pid) +
                                      " renders a world through it (one channel per instance)");
    }
    return Existing::replaceable;
}

// Creates the file at `path`, or `path` + ".next" while a scene of this process renders
// through `path` (`staged`: claim_path() moves it into place once the scene is taken).
int create_file(const std::string& path, bool& staged) {
    staged = false;
    for (int attempt = 0; attempt < 3; ++attempt) {
        const std::string target = staged ? path + ".next" : path;
        const int fd = ::open(target.c_str(), O_RDWR | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC,
                              S_IRUSR | S_IWUSR | S_IRGRP | S_IWGRP);
        if (fd >= 0) return fd;
        if (errno != EEXIST) throw channel_error(target, "cannot be created: " + errno_text(errno));
        // A ".next" is only ever this process's (a scene that was not taken, left by a crash).
        if (!staged && judge_existing(path) == Existing::ours) {
            staged = true;
            continue;
        }
        if (staged) (void)judge_existing(target);  // refuses what is not a channel
        if (::unlink(target.c_str()) != 0 && errno != ENOENT) {
            throw channel_error(target,
                                "a channel left by a daemon that is gone cannot be "
                                "removed: " +
                                    errno_text(errno));
        }
    }
    throw channel_error(path, "another process keeps creating it");
}

}  // namespace

std::string channel_beside(const std::string& socket_path) {
    if (socket_path.size() > kSocketSuffix.size() && socket_path.ends_with(kSocketSuffix)) {
        return socket_path.substr(0, socket_path.size() - kSocketSuffix.size()) + ".world";
    }
    return socket_path + ".world";
}

ExternalChannel::ExternalChannel(const std::string& path, const ChannelShape& shape,
                                 const std::string& group, std::string& note)
    : path_(path) {
    if (path.empty()) {
        memory_ = ::mmap(nullptr, HAPTICD_WORLD_SIZE, PROT_READ | PROT_WRITE,
                         MAP_SHARED | MAP_ANONYMOUS, -1, 0);
        if (memory_ == MAP_FAILED) {
            memory_ = nullptr;
            throw channel_error("(private)", "mmap: " + errno_text(errno));
        }
    } else {
        bool staged = false;
        fd_ = create_file(path, staged);
        if (staged) staged_path_ = path + ".next";
        try {
            // The umask (the unit's 0027) must not take the group's write away.
            if (::fchmod(fd_, S_IRUSR | S_IWUSR | S_IRGRP | S_IWGRP) != 0) {
                throw channel_error(file_path(), "chmod 0660: " + errno_text(errno));
            }
            note =
                install::give_to_group(file_path(), group, "external world channel " + file_path(),
                                       "docs/external-worlds.md");
            // Its page reserved now: a full /run is an error here, not a SIGBUS in the tick.
            const int error = ::posix_fallocate(fd_, 0, HAPTICD_WORLD_SIZE);
            if (error != 0)
                throw channel_error(path, "cannot reserve its page: " + errno_text(error));
            struct stat st {};
            if (::fstat(fd_, &st) != 0) throw channel_error(path, "fstat: " + errno_text(errno));
            device_ = st.st_dev;
            inode_ = st.st_ino;
            memory_ =
                ::mmap(nullptr, HAPTICD_WORLD_SIZE, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, 0);
            if (memory_ == MAP_FAILED) {
                memory_ = nullptr;
                throw channel_error(path, "mmap: " + errno_text(errno));
            }
        } catch (...) {
            ::unlink(file_path().c_str());
            ::close(fd_);
            throw;
        }
    }
    hapticd_world_header header{};
    header.version = HAPTICD_WORLD_VERSION;
    header.size = HAPTICD_WORLD_SIZE;
    header.axes = shape.axes;
    header.lockstep_every = shape.lockstep_every;
    header.rate_hz = shape.rate_hz;
    header.stale_after_s = shape.stale_after_s;
    header.daemon_pid = ::getpid();
    std::memcpy(memory_, &header, sizeof header);
    publish(hapticd_world_tick{});
    // The magic last, released: a world that sees it sees the header and the first block.
    std::uint64_t magic = 0;
    std::memcpy(&magic, HAPTICD_WORLD_MAGIC, sizeof magic);
    word(memory_, 0).store(magic, std::memory_order_release);
}

ExternalChannel::~ExternalChannel() {
    if (memory_ != nullptr) {
        auto* header = static_cast<hapticd_world_header*>(memory_);
        std::atomic_ref<std::uint32_t>(header->closed).store(1u, std::memory_order_release);
        ::munmap(memory_, HAPTICD_WORLD_SIZE);
    }
    if (fd_ >= 0) {
        // Only the file this channel made: a scene that replaced this one has made its own.
        const std::string& file = file_path();
        struct stat st {};
        if (::stat(file.c_str(), &st) == 0 && st.st_dev == device_ && st.st_ino == inode_) {
            ::unlink(file.c_str());
        }
        ::close(fd_);
    }
}

std::string ExternalChannel::claim_path() {
    if (staged_path_.empty()) return {};
    if (::rename(staged_path_.c_str(), path_.c_str()) != 0) {
        return "external world channel " + staged_path_ + ": cannot be moved to " + path_ + ": " +
               errno_text(errno) + "; a world may map " + staged_path_ + " instead";
    }
    staged_path_.clear();
    return {};
}

void ExternalChannel::publish(const hapticd_world_tick& tick) noexcept {
    store_block(memory_, HAPTICD_WORLD_TICK_OFFSET, tick);
}

bool ExternalChannel::try_take(hapticd_world_update& update) const noexcept {
    return try_load_block(memory_, HAPTICD_WORLD_UPDATE_OFFSET, update);
}

}  // namespace hapticd::env
