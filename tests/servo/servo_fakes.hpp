// Fakes for the servo tests: a virtual clock, a scripted device and small environments of
// both causalities. None of them allocates in read/write/evaluate/step.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "hapticd/servo/environment_port.hpp"
#include "hapticd/servo/io.hpp"

namespace hapticd::servo::fakes {

/// Virtual time shared by a FakeClock and a FakeDevice.
struct VirtualTime {
    std::int64_t now_ns = 0;
    std::int64_t wake_latency_ns = 0;  ///< added to every sleep
    std::int64_t sleeps = 0;
};

/// A PacingClock on virtual time: sleeping jumps the time to the deadline (plus latency).
struct FakeClock {
    VirtualTime* time;
    std::int64_t now_ns() noexcept { return time->now_ns; }
    void sleep_until_ns(std::int64_t deadline_ns) noexcept {
        ++time->sleeps;
        if (deadline_ns > time->now_ns) time->now_ns = deadline_ns;
        time->now_ns += time->wake_latency_ns;
    }
};

/// Returns `next` from read() and then advances it by `counts_per_read`; records writes.
/// Like a real device it stamps each sample with its clock: the virtual time of the read when
/// it has one, else one period (`seconds_per_read`) per read.
struct FakeDevice {
    Sample next{};
    std::array<std::int64_t, kMaxAxes> counts_per_read{};
    IoResult read_result = IoResult::ok;
    IoResult write_result = IoResult::ok;
    VirtualTime* time = nullptr;
    std::int64_t read_cost_ns = 0;  ///< virtual time each read takes
    Command last_command{};
    std::int64_t reads = 0;
    std::int64_t writes = 0;
    double max_abs_force_n = 0.0;

    double seconds_per_read = 1e-3;
    bool clock_stamps = true;         ///< false: device_time_s stays as `next` holds it
    std::int64_t stall_at_read = -1;  ///< this read (0, 1, ...) first stalls the host ...
    std::int64_t stall_ns = 0;        ///< ... for this long (virtual time), as kill -STOP would

    IoResult read(Sample& sample) noexcept {
        if (time != nullptr && reads == stall_at_read) time->now_ns += stall_ns;
        ++reads;
        if (clock_stamps && time != nullptr) {
            next.device_time_s = static_cast<double>(time->now_ns) * 1e-9;
        }
        sample = next;
        ++next.sequence;
        if (clock_stamps && time == nullptr) next.device_time_s += seconds_per_read;
        for (int axis = 0; axis < kMaxAxes; ++axis)
            next.encoder_counts[axis] += counts_per_read[axis];
        if (time != nullptr) time->now_ns += read_cost_ns;
        return read_result;
    }

    IoResult write(const Command& command) noexcept {
        ++writes;
        last_command = command;
        for (double force : command.force_n)
            max_abs_force_n = std::max(max_abs_force_n, std::abs(force));
        return write_result;
    }

    void set_position_counts(std::int64_t counts, int axis = 0) {
        next.encoder_counts[axis] = counts;
    }
};

/// Impedance: a rigid penalty wall filling x < wall_m (along axis 0), stiffness k_w and
/// damping b_w inside; it pushes the tool towards +x. Piecewise linear.
struct PlaneWall {
    double wall_m = 0.0;
    double stiffness_n_per_m = 1000.0;
    double damping_n_s_per_m = 0.0;
    int commits = 0;
    int resets = 0;

    PenaltyForce evaluate(const Vec3& x, const Vec3& v) const noexcept {
        PenaltyForce out;
        const double penetration_m = wall_m - x.x;
        if (penetration_m > 0.0) {
            out.force_n.x = stiffness_n_per_m * penetration_m - damping_n_s_per_m * v.x;
            out.stiffness_n_per_m[0][0] = stiffness_n_per_m;
            out.damping_n_s_per_m[0][0] = damping_n_s_per_m;
        }
        return out;
    }
    void commit(const Vec3&, const Vec3&) noexcept { ++commits; }
    void reset(const Vec3&) noexcept { ++resets; }
};
static_assert(ImpedancePort<PlaneWall>);

/// Impedance: a deliberately active environment, f = +gain v_e (negative damping).
struct ActiveDamper {
    double gain_n_s_per_m = 5.0;
    PenaltyForce evaluate(const Vec3&, const Vec3& v) const noexcept {
        PenaltyForce out;
        out.force_n = gain_n_s_per_m * v;
        out.damping_n_s_per_m = Mat3(-gain_n_s_per_m);
        return out;
    }
    void commit(const Vec3&, const Vec3&) noexcept {}
    void reset(const Vec3&) noexcept {}
};
static_assert(ImpedancePort<ActiveDamper>);

/// Impedance: returns NaN once `after_evaluations` evaluations have happened.
struct NanAfter {
    int after_evaluations = 0;
    mutable int evaluations = 0;
    PenaltyForce evaluate(const Vec3&, const Vec3&) const noexcept {
        PenaltyForce out;
        if (evaluations++ >= after_evaluations)
            out.force_n.x = std::numeric_limits<double>::quiet_NaN();
        return out;
    }
    void commit(const Vec3&, const Vec3&) noexcept {}
    void reset(const Vec3&) noexcept {}
};
static_assert(ImpedancePort<NanAfter>);

/// Admittance: the tool is always at `tool_m`.
struct FixedPoint {
    Vec3 tool_m{0.0};
    Vec3 step(const Vec3&, const Vec3&, const CouplingGains&, double) noexcept { return tool_m; }
    void reset(const Vec3&) noexcept {}
};
static_assert(AdmittancePort<FixedPoint>);

/// Admittance: god-object against the plane x >= wall_m: the constrained point nearest x_d.
struct ProxyPlane {
    double wall_m = 0.0;
    Vec3 step(const Vec3& x_d, const Vec3&, const CouplingGains&, double) noexcept {
        return {std::max(x_d.x, wall_m), x_d.y, x_d.z};
    }
    void reset(const Vec3&) noexcept {}
};
static_assert(AdmittancePort<ProxyPlane>);

}  // namespace hapticd::servo::fakes
