// The device model that `haptic-tune identify` fits (docs/identification.md), per axis:
//
//     m dv/dt + b v = F - F_c sign(v) + F_0                                        (10)+
//
// F the logged force command f{i}_n (on the handle along +axis, held by the device over
// one period: zero-order hold, from the loop delay D after its sample on), m the mass (kg), b the
// viscous damping (N s/m), F_c >= 0 the Coulomb friction (N; it opposes the motion), F_0 a constant
// force offset (N; it adds to the command: an amplifier offset, gravity on a tilted axis, a cable's
// pull).
//
// The step below is the exact solution of this model over one hold interval, including
// stops and reversals inside the interval: between events the motion is the closed form of
// the linear mass-damper under a constant force; a velocity reversal is found by solving
// v(t) = 0 in closed form; at rest the handle sticks while |F + F_0| <= F_c (Coulomb
// friction with equal static and kinetic levels, the Filippov solution). Written as
// templates so that Ceres' jets differentiate it (automatic derivatives).
#pragma once

#include <cmath>
#include <cstddef>

namespace hapticd::tune {

/// The loop delay D = (whole_periods + fraction) T from the sample at t_n = nT to the force
/// computed from it acting (the zero-order hold of (13), shifted by D, as
/// device/sim/command_pipeline.hpp renders it): period n, [t_n, t_{n+1}), sees F[n - q - 1]
/// for its first fraction T and F[n - q] for the rest, q = whole_periods.
struct HoldDelay {
    std::size_t whole_periods = 0;
    double fraction = 0.0;  ///< in [0, 1)

    /// Forces before period n that it needs: F[n - history()] is the oldest.
    std::size_t history() const { return whole_periods + (fraction > 0.0 ? 1 : 0); }
};

/// Splits `delay_s` (finite, >= 0) at the period `period_s`. A delay within 1e-9 periods of
/// a whole number of periods is that number (1e-3 s at 1 kHz is one period, exactly).
inline HoldDelay split_hold_delay(double delay_s, double period_s) {
    const double periods = delay_s / period_s;
    const double whole = std::round(periods);
    if (std::abs(periods - whole) < 1e-9) return {static_cast<std::size_t>(whole), 0.0};
    const double floor = std::floor(periods);
    return {static_cast<std::size_t>(floor), periods - floor};
}

/// Position (m) and velocity (m/s) of the handle.
template <typename T>
struct MotionState {
    T x;
    T v;
};

/// Constants of the mass-damper over a hold of length h, with a = b/m:
///   decay = e^{-a h},  phi1 = (1 - e^{-a h})/a,  phi2 = (h - phi1)/a,
/// so that under a constant net force u (damping excluded)
///   v(h) = v(0) decay + (u/m) phi1,   x(h) = x(0) + v(0) phi1 + (u/m) phi2.
template <typename T>
struct HoldConstants {
    T decay;
    T phi1;  ///< s
    T phi2;  ///< s^2
};

template <typename T, typename H>
HoldConstants<T> hold_constants(const T& a, const H& h) {
    using std::expm1;
    const T z = a * h;
    const T em1 = expm1(-z);  // e^{-z} - 1, accurate for small z
    HoldConstants<T> c{em1 + 1.0, -em1 / a, T(0.0)};
    // phi2 = (z + e^{-z} - 1)/a^2 loses digits as z -> 0; its series is h^2 (1/2 - z/6 + ...).
    if (z < 1e-2) {
        c.phi2 = h * h * (0.5 - z * (1.0 / 6.0 - z * (1.0 / 24.0 - z * (1.0 / 120.0 - z / 720.0))));
    } else {
        c.phi2 = (z + em1) / (a * a);
    }
    return c;
}

/// Advances `state` over one hold of length `h` (s) under the held force `push` = F + F_0
/// (N), for mass m, a = b/m and Coulomb level `coulomb` >= 0. `full` must be
/// hold_constants(a, h). Exact, including a stop or a reversal inside the hold. A state at
/// rest is one with v exactly 0 (which the step itself produces when the handle sticks).
template <typename T>
void hold_step(MotionState<T>& state, const T& mass, const T& a, const T& coulomb, const T& push,
               const HoldConstants<T>& full, double h) {
    using std::abs;
    using std::log1p;
    T remaining(h);
    bool partial = false;
    // At most three phases: moving, stopped (by the opposing net force), then stuck or moving
    // the other way (in which case the net force drives the motion and cannot stop it again).
    for (int phase = 0; phase < 3; ++phase) {
        double direction = 0.0;
        if (state.v == 0.0) {
            if (abs(push) <= coulomb) return;  // stiction holds for the rest of the hold
            direction = push > 0.0 ? 1.0 : -1.0;
        } else {
            direction = state.v > 0.0 ? 1.0 : -1.0;
        }
        const T drive = push - coulomb * direction;  // net force, damping excluded
        const T accel = drive / mass;
        if (drive * direction < 0.0) {
            // The velocity decays towards -drive/b, across zero: v(t) = 0 at
            // t = ln(1 - v b/drive)/a, b = a m.
            const T t_stop = log1p(-state.v * a * mass / drive) / a;
            if (t_stop < remaining) {
                const HoldConstants<T> c = hold_constants(a, t_stop);
                state.x += state.v * c.phi1 + accel * c.phi2;
                state.v = T(0.0);
                remaining -= t_stop;
                partial = true;
                continue;
            }
        }
        const HoldConstants<T> c = partial ? hold_constants(a, remaining) : full;
        state.x += state.v * c.phi1 + accel * c.phi2;
        state.v = state.v * c.decay + accel * c.phi1;
        return;
    }
}

}  // namespace hapticd::tune
