// A FrameLink straight into a DeviceEmulator on the calling thread: ProtocolDevice's logic
// without an OS transport, deterministic. The emulator answers each sent frame at once, so
// receive() never has to wait: an empty queue is a timeout (a dropped reply), and a link
// whose device is absent reports disconnected, as a transport would after ENODEV.
#pragma once

#include <array>
#include <atomic>
#include <cstring>
#include <functional>
#include <memory>
#include <stdexcept>

#include "hapticd/device/link/frame_link.hpp"
#include "hapticd/device/protocol/device_emulator.hpp"

namespace hapticd::testing {

namespace proto = hapticd::device::protocol;

/// What the test and the link share: the device behind the link, and whether it is plugged in.
struct LoopbackBench {
    std::unique_ptr<proto::DeviceEmulator> device;
    std::atomic<bool> present{true};
    std::atomic<int> opens{0};
    /// Rewrites each reply frame before the host sees it (a device's bytes no emulator sends).
    std::function<void(std::span<std::byte>)> tamper;
};

class LoopbackLink final : public device::link::FrameLink {
  public:
    explicit LoopbackLink(LoopbackBench& bench) : bench_(bench) {}

    void open() override {
        if (!bench_.present.load()) throw std::runtime_error("loopback: no device plugged in");
        queued_ = 0;
        head_ = 0;
        bench_.opens.fetch_add(1);
    }
    void close() noexcept override { queued_ = 0; }

    device::link::LinkResult send(std::span<const std::byte> frame) noexcept override {
        using device::link::LinkResult;
        if (!bench_.present.load()) return LinkResult::disconnected;
        std::array<std::byte, proto::DeviceEmulator::kMaxReplySize> out{};
        const proto::DeviceEmulator::Reply reply = bench_.device->handle(frame, out);
        std::size_t offset = 0;
        for (std::size_t i = 0; i < reply.frames; ++i) {
            if (bench_.tamper) bench_.tamper(std::span(out.data() + offset, reply.frame_sizes[i]));
            push(std::span<const std::byte>(out.data() + offset, reply.frame_sizes[i]));
            offset += reply.frame_sizes[i];
        }
        frames_sent_.fetch_add(1, std::memory_order_relaxed);
        return LinkResult::ok;
    }

    device::link::LinkResult receive(std::span<std::byte> frame, std::size_t& size,
                                     std::int64_t /*deadline_ns*/) noexcept override {
        using device::link::LinkResult;
        if (!bench_.present.load()) return LinkResult::disconnected;
        if (queued_ == 0) return LinkResult::timeout;
        const Slot& slot = slots_[head_];
        std::memcpy(frame.data(), slot.bytes.data(), slot.size);
        size = slot.size;
        head_ = (head_ + 1) % slots_.size();
        --queued_;
        frames_received_.fetch_add(1, std::memory_order_relaxed);
        return LinkResult::ok;
    }

    void discard_input() noexcept override { queued_ = 0; }
    std::string describe() const override { return "loopback"; }
    /// Any thread, as FrameLink asks: relaxed atomics.
    device::link::LinkCounters counters() const noexcept override {
        device::link::LinkCounters c;
        c.frames_sent = frames_sent_.load(std::memory_order_relaxed);
        c.frames_received = frames_received_.load(std::memory_order_relaxed);
        c.framing_errors = framing_errors_.load(std::memory_order_relaxed);
        return c;
    }
    /// The test's stand-in for transport garbage (bad COBS, a wrong report ID) dropped.
    void count_framing_error() noexcept { framing_errors_.fetch_add(1, std::memory_order_relaxed); }

  private:
    struct Slot {
        std::array<std::byte, proto::kMaxFrameSize> bytes{};
        std::size_t size = 0;
    };
    void push(std::span<const std::byte> frame) noexcept {
        if (queued_ == slots_.size()) return;  // full: a real transport would drop too
        Slot& slot = slots_[(head_ + queued_) % slots_.size()];
        std::memcpy(slot.bytes.data(), frame.data(), frame.size());
        slot.size = frame.size();
        ++queued_;
    }

    LoopbackBench& bench_;
    std::array<Slot, 8> slots_{};
    std::size_t head_ = 0;
    std::size_t queued_ = 0;
    std::atomic<std::uint64_t> frames_sent_{0};
    std::atomic<std::uint64_t> frames_received_{0};
    std::atomic<std::uint64_t> framing_errors_{0};
};

}  // namespace hapticd::testing
