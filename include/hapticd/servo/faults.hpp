// Latched safety faults (docs/architecture.md §7.1). A fault zeroes the force in the tick that
// raises it and stays latched until reset outside the tick (request_fault_reset), or, for a
// link fault only (kLinkFaults), until the device has been back for a while (LinkRecovery). Faults
// form a bitmask so that several can be latched at once; each bit has a stable snake_case name for
// the summary's `faults` list and the telemetry's `faults` column (which carries the mask as an
// integer).
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "hapticd/servo/io.hpp"

namespace hapticd::servo {

enum Fault : std::uint32_t {
    kFaultDeviceLost = 1u << 0,     ///< read/write reported disconnected, or kStatusDisconnected
    kFaultReadTimeout = 1u << 1,    ///< more consecutive timeouts/dropped samples than allowed
    kFaultEncoderJump = 1u << 2,    ///< kStatusJump, or a step larger than encoder_jump_m
    kFaultOverrunBudget = 1u << 3,  ///< the loop overran its deadline more than allowed
    kFaultNonFinite = 1u << 4,      ///< NaN/Inf from the environment or in the force
    kFaultOverspeed = 1u << 5,      ///< |v_d| > max_speed_mps with SpeedAction::fault
    kFaultDeviceFault = 1u << 6,    ///< the device reported a fault of its own
    kFaultDeviceIo = 1u << 7,       ///< read or write returned IoResult::error
    kFaultEncoderStale = 1u << 8,   ///< kStatusStale: the counts repeat the last good ones
    /// The environment failed: a plugin's world returned an error, a value that is not
    /// finite, threw, or took longer than its time (env/plugin_environment.hpp).
    kFaultEnvironment = 1u << 9,
};

inline constexpr int kFaultCount = 10;

/// Link faults: the device or the wire between it and the host failed, not the device's
/// mechanics, the encoder or this host. They are the only faults that LinkRecovery
/// (link_recovery.hpp) may clear by itself, once the device has sent good samples again for
/// a while: a lost device (unplugged, ENODEV), reads that gave no sample (timeouts, dropped,
/// corrupted frames), I/O errors. Every other fault needs an operator (request_fault_reset):
/// encoder_jump and encoder_stale (the position may be wrong), device_fault (the device says so
/// itself), overspeed, non_finite (the environment is broken) and overrun_budget (this host cannot
/// keep the rate).
inline constexpr std::uint32_t kLinkFaults = kFaultDeviceLost | kFaultReadTimeout | kFaultDeviceIo;

/// True when `faults` is not empty and holds link faults only.
constexpr bool only_link_faults(std::uint32_t faults) noexcept {
    return faults != 0u && (faults & ~kLinkFaults) == 0u;
}

/// What one read gave (ServoLoop's sense step): whether it is a sample to use, and the faults
/// that the read's result and the sample's status imply. A read that says the device is gone
/// (or failed) is device_lost (device_io); counts that repeat the last good ones while the
/// handle may move are encoder_stale, a sensor fault like a jump, since the position and any
/// velocity from it are wrong.
struct ReadVerdict {
    bool have_sample = false;  ///< a sample, neither dropped nor from a device that is gone
    std::uint32_t faults = 0;  ///< Fault mask
};
constexpr ReadVerdict judge_read(IoResult result, std::uint32_t sample_status) noexcept {
    ReadVerdict verdict;
    if (result == IoResult::ok) verdict.have_sample = (sample_status & kStatusDropped) == 0u;
    if (result == IoResult::disconnected) verdict.faults |= kFaultDeviceLost;
    if (result == IoResult::error) verdict.faults |= kFaultDeviceIo;
    if ((sample_status & kStatusDisconnected) != 0u) {
        verdict.faults |= kFaultDeviceLost;
        verdict.have_sample = false;
    }
    if ((sample_status & kStatusDeviceFault) != 0u) verdict.faults |= kFaultDeviceFault;
    if ((sample_status & kStatusJump) != 0u) verdict.faults |= kFaultEncoderJump;
    if (verdict.have_sample && (sample_status & kStatusStale) != 0u) {
        verdict.faults |= kFaultEncoderStale;
    }
    return verdict;
}

/// The name of one fault bit ("device_lost", ...); "unknown" for anything else.
constexpr std::string_view fault_name(std::uint32_t fault_bit) noexcept {
    switch (fault_bit) {
        case kFaultDeviceLost:
            return "device_lost";
        case kFaultReadTimeout:
            return "read_timeout";
        case kFaultEncoderJump:
            return "encoder_jump";
        case kFaultOverrunBudget:
            return "overrun_budget";
        case kFaultNonFinite:
            return "non_finite";
        case kFaultOverspeed:
            return "overspeed";
        case kFaultDeviceFault:
            return "device_fault";
        case kFaultDeviceIo:
            return "device_io";
        case kFaultEncoderStale:
            return "encoder_stale";
        case kFaultEnvironment:
            return "environment";
        default:
            return "unknown";
    }
}

/// Calls `visit(std::string_view name)` for every bit set in `faults`, lowest bit first.
template <typename Visit>
constexpr void for_each_fault(std::uint32_t faults, Visit&& visit) {
    for (int bit = 0; bit < 32; ++bit) {
        const std::uint32_t mask = 1u << bit;
        if ((faults & mask) != 0u) visit(fault_name(mask));
    }
}

}  // namespace hapticd::servo
