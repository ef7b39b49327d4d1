// Link-fault recovery: clears the fault latch by itself when every fault latched is a link
// fault (kLinkFaults: device_lost, read_timeout, device_io) and the device has been back,
// sending good samples, for `settle` without a break. Every other fault still needs an
// operator. The device plugins reconnect on their own (a USB device that is unplugged and
// plugged in again, a serial line that resynchronises); the servo only has to see that the
// samples are good again and start over, as an operator's reset would:
//
//   fault raised (tick F): force zero from that tick on (SafetySupervisor), reported
//   device back (tick B):  the first good sample; the count starts at 1
//   a bad tick:            the count starts again from 0
//   count == settle_ticks: the latch clears after that tick (B + settle_ticks - 1), exactly
//                          like request_fault_reset(); the next tick re-initialises the
//                          coupling and the environment where the handle is, and the soft
//                          start waits for a still handle before it ramps the force in
//   timeout:               if the latch is still held `timeout` after the fault (the device
//                          did not come back, or not steadily enough to settle), give up:
//                          ServoLoop::run() returns RunExit::fault
//
// A good tick: read() returned IoResult::ok with a sample that is neither disconnected nor
// dropped, and no link fault was raised in that tick (the write went through too).
//
// Deterministic: it counts ticks (settle) and scheduled periods (timeout), never wall time,
// so a lockstep run recovers on the same tick every time.
//
// Real-time: update() is a few integer operations; nothing allocates, locks or throws.
#pragma once

#include <cstdint>
#include <string>

#include "hapticd/input/range.hpp"
#include "hapticd/servo/faults.hpp"

namespace hapticd::servo {

/// [safety] reconnect_settle, and reconnect_timeout (which must also exceed the settle).
inline constexpr input::Range kSettleRange{.lo = 0.0, .hi = 60.0, .lo_open = true, .unit = "s"};
inline constexpr input::Range kTimeoutRange{.lo = 0.0, .hi = 3600.0, .unit = "s; 0: wait for ever"};

struct LinkRecoverySettings {
    /// Off: link faults stay latched like any other ([safety] reconnect = false). On by
    /// default, as in the daemon's config: a replugged device comes back.
    bool enabled = true;
    /// How long the device must send good samples without a break before the latch clears,
    /// s, in (0, 60] ([safety] reconnect_settle).
    double settle_s = 0.5;
    /// How long after the fault the latch may stay held before the run gives up, s; 0: wait
    /// for ever. Otherwise > settle_s, <= 3600 ([safety] reconnect_timeout).
    double timeout_s = 5.0;

    /// Ceres-style: false, with the field, its value and the allowed range in `error`.
    bool is_valid(std::string* error) const;
    /// Throws std::invalid_argument with is_valid()'s message.
    void validate() const;
};

/// What update() decided at the end of a tick.
enum class LinkAction {
    none,     ///< nothing to do (no link fault, still settling, or not enabled)
    recover,  ///< clear the latch now, as request_fault_reset() does
    give_up,  ///< the device did not come back in time: end the run on the fault
};

class LinkRecovery {
  public:
    LinkRecovery() = default;
    /// Converts the settings to ticks at `rate_hz` (settle: at least 1 tick). Validates.
    LinkRecovery(const LinkRecoverySettings& settings, double rate_hz);

    /// End of a tick. `latched`: the Fault mask latched now; `good_tick`: this tick read a
    /// good sample and raised no link fault; `periods`: periods this tick covered (1, or more
    /// after an overrun).
    LinkAction update(std::uint32_t latched, bool good_tick, std::uint64_t periods) noexcept;

    /// Forget the progress (after an operator's reset).
    void reset() noexcept;

    bool enabled() const noexcept { return enabled_; }
    /// True when `latched` is a fault this component will clear on its own (while the run
    /// must keep ticking to see the device come back).
    bool recoverable(std::uint32_t latched) const noexcept {
        return enabled_ && only_link_faults(latched);
    }
    bool gave_up() const noexcept { return gave_up_; }
    std::uint64_t settle_ticks() const noexcept { return settle_ticks_; }
    /// 0: no timeout.
    std::uint64_t timeout_periods() const noexcept { return timeout_periods_; }
    /// Good ticks in a row so far (0 when no link fault is latched).
    std::uint64_t good_ticks() const noexcept { return good_ticks_; }
    /// Periods the current link fault has been latched.
    std::uint64_t latched_periods() const noexcept { return latched_periods_; }

  private:
    bool enabled_ = false;
    std::uint64_t settle_ticks_ = 1;
    std::uint64_t timeout_periods_ = 0;
    std::uint64_t good_ticks_ = 0;
    std::uint64_t latched_periods_ = 0;
    bool gave_up_ = false;
};

}  // namespace hapticd::servo
