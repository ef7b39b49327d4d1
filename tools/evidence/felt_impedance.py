"""The impedance the hand feels, Z_P(jω) = F_h/v_h, from one logged run of the Z-width
experiment (zwidth_hil.py): the handle's sampled position x[n] (the log's x0_m), the force
the device commanded f[n] (f0_n) and the hand's set-point s[n], which the experiment sets.

The operator is the sim's stiff grasp: a hand mass m_h rigid on the handle, held through a
spring k_h and a damper b_h from a set-point s(t) that the experiment moves. The force of the
hand on the handle, as a force sensor between them would read it, is

    F_h = (b_h + k_h/(jω)) (V_s - V) - jω m_h V,    so    Z_P = Z_h (V_s/V - 1) - jω m_h,

with Z_h = b_h + k_h/(jω): the hand's own physics and the ratio of the set-point's velocity
to the handle's, nothing of the device (its m, b, force) enters. The record starts and ends
at rest, so its transform is the whole transient's (no window, no leakage), evaluated at any
frequency; the samples are differenced (rest at both ends), which multiplies both transforms
by the same 1 - e^{-jωT}. The set-point is linear between samples (docs/sim-device.md), so
its continuous transform is the samples' times T sinc²(ωT/2) exactly; the handle's is the
samples' times T, up to aliasing, which the free-motion run measures (its Z_P is m jω + b).

The device side, for a cross-check: f[n] acts from nT + D for one period (zero-order hold
after the loop delay D), so its continuous transform is the samples' times
T sinc(ωT/2) e^{-jω(T/2 + D)}, and Z_P = m jω + b - F/V (the device's equation of motion).
"""

import numpy as np


def transform(samples, frequency_hz, period_s):
    """The differenced samples' transform, sum over n of (s[n+1] - s[n]) e^{-jωnT}."""
    steps = np.diff(np.asarray(samples, dtype=float))
    theta = 2.0 * np.pi * np.asarray(frequency_hz, dtype=float)[:, None] * period_s
    return np.exp(-1j * theta * np.arange(len(steps))[None, :]) @ steps


def sinc(x):
    return np.sinc(x / np.pi)  # numpy's sinc is sin(πx)/(πx)


def hand_side(position_m, set_point_m, frequency_hz, period_s, hand):
    """Z_P (N s/m, complex) at each frequency from the hand's force: `hand` is
    (mass kg, stiffness N/m, damping N s/m)."""
    mass, stiffness, damping = hand
    omega = 2.0 * np.pi * np.asarray(frequency_hz, dtype=float)
    theta = omega * period_s
    ratio = sinc(theta / 2.0) ** 2 * transform(set_point_m, frequency_hz, period_s) / \
        transform(position_m, frequency_hz, period_s)
    return (damping + stiffness / (1j * omega)) * (ratio - 1.0) - 1j * omega * mass


def device_side(position_m, force_n, frequency_hz, period_s, device_mass_kg,
                device_damping_n_s_per_m, delay_s):
    """Z_P (N s/m, complex) from the device's equation: m jω + b - F/V, F the held force."""
    omega = 2.0 * np.pi * np.asarray(frequency_hz, dtype=float)
    theta = omega * period_s
    force = sinc(theta / 2.0) * np.exp(-1j * omega * (period_s / 2.0 + delay_s)) * \
        transform(force_n, frequency_hz, period_s)
    velocity = 1j * omega * transform(position_m, frequency_hz, period_s)
    return device_mass_kg * 1j * omega + device_damping_n_s_per_m - force / velocity


def fit_mass_damper_spring(frequency_hz, impedance):
    """k/(jω) + b + jω m fitted to Z_P: b the mean real part; m and k by least squares on the
    imaginary part m ω - k/ω, each frequency weighted by 1/|Z_P| (relative error).
    Returns (stiffness N/m, damping N s/m, mass kg)."""
    omega = 2.0 * np.pi * np.asarray(frequency_hz, dtype=float)
    z = np.asarray(impedance)
    weight = 1.0 / np.abs(z)
    rows = np.column_stack([omega, -1.0 / omega]) * weight[:, None]
    (mass, stiffness), *_ = np.linalg.lstsq(rows, z.imag * weight, rcond=None)
    return float(stiffness), float(np.mean(z.real)), float(mass)


def static_stiffness(position_m, force_n, before, after):
    """The stiffness the handle is held with between two rests, samples `before` and
    `after`: -(f_after - f_before)/(x_after - x_before) (N/m), from the device's force (at
    rest the hand's force is minus it)."""
    return -(force_n[after] - force_n[before]) / (position_m[after] - position_m[before])


def largest_speed(position_m, period_s, first, last):
    """The largest backward-difference speed (m/s) over samples first..last."""
    x = np.asarray(position_m[max(first - 1, 0):last + 1], dtype=float)
    return float(np.max(np.abs(np.diff(x)))) / period_s if len(x) > 1 else 0.0
