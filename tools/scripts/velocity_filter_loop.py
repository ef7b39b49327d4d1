#!/usr/bin/python3
"""The sampled-data loop of the pen display with the coupling damper on a filtered velocity,
written from scratch with numpy/scipy (no hapticd code): an independent check of
tune::closed_loop_poles with a velocity filter (tests/tune/exact_model_test.cpp).

Device and a heavy hand: (m + m_h) dv/dt + (b + b_h) v = -F, sampled with an exact
zero-order hold (no delay). The coupling, a = exp(-2 pi f_c T):
    u[n] = a u[n-1] + (1 - a) ((x_d[n] - x_d[n-1]) - (x_e[n] - x_e[n-1])) / T
    F[n] = k_c (x_d[n] - x_e[n]) + b_c u[n]
against a rigid wall (x_e = 0) or an implicit-Euler mass-spring environment,
    m_e (x_e[n] - 2 x_e[n-1] + x_e[n-2]) / T^2 = F[n] - k_e x_e[n] - b_e (x_e[n] - x_e[n-1]) / T,
solved with the coupling in the tick. Prints the spectral radius and the dominant frequency.

usage: tools/scripts/velocity_filter_loop.py
"""
import numpy as np
from scipy.linalg import expm


def sampled_plant(mass, damping, period):
    a = np.array([[0.0, 1.0], [0.0, -damping / mass]])
    b = np.array([[0.0], [-1.0 / mass]])
    aug = np.zeros((3, 3))
    aug[:2, :2] = a * period
    aug[:2, 2:] = b * period
    e = expm(aug)
    return e[:2, :2], e[:2, 2]


def poles(device, hand, coupling, environment, rate):
    m, b = device
    m_h, b_h = hand
    k_c, b_c, f_c = coupling
    t = 1.0 / rate
    a = np.exp(-2.0 * np.pi * f_c * t) if f_c > 0 else 0.0
    phi, gamma = sampled_plant(m + m_h, b + b_h, t)
    if environment is None:
        # state (x, v, x_d[n-1], u[n-1]); F = k x + b_c (a u1 + (1 - a)(x - x1)/T)
        force = np.array([k_c + b_c * (1 - a) / t, 0.0, -b_c * (1 - a) / t, b_c * a])
        u_row = np.array([(1 - a) / t, 0.0, -(1 - a) / t, a])
        loop = np.zeros((4, 4))
        loop[:2, :] = np.hstack([phi, np.zeros((2, 2))]) + np.outer(gamma, force)
        loop[2, 0] = 1.0
        loop[3, :] = u_row
    else:
        m_e, k_e, b_e = environment
        c0 = m_e / t**2 + b_e / t + k_e
        c1 = -2 * m_e / t**2 - b_e / t
        c2 = m_e / t**2
        # state (x, v, x_d1, x_e1, x_e2, u1). F = P - g x_e with
        # P = k x + b_w (x - x_d1)/T + (b_w/T) x_e1 + a b_c u1, g = k + b_w/T, b_w = (1 - a) b_c;
        # F = c0 x_e + c1 x_e1 + c2 x_e2  =>  x_e = (P - c1 x_e1 - c2 x_e2)/(g + c0).
        b_w = (1 - a) * b_c
        p = np.array([k_c + b_w / t, 0.0, -b_w / t, b_w / t, 0.0, a * b_c])
        rhs = np.array([0.0, 0.0, 0.0, c1, c2, 0.0])
        g = k_c + b_w / t
        x_e = (p - rhs) / (g + c0)
        force = p - g * x_e
        u_row = (1 - a) / t * (np.array([1.0, 0, -1.0, 1.0, 0, 0]) - x_e)
        u_row[5] += a
        loop = np.zeros((6, 6))
        loop[:2, :] = np.hstack([phi, np.zeros((2, 4))]) + np.outer(gamma, force)
        loop[2, 0] = 1.0
        loop[3, :] = x_e
        loop[4, 3] = 1.0
        loop[5, :] = u_row
    lam = np.linalg.eigvals(loop)
    i = int(np.argmax(np.abs(lam)))
    return abs(lam[i]), abs(np.angle(lam[i])) * rate / (2 * np.pi)


def main():
    device = (0.1, 2.0)
    cases = [
        ((0.5, 1.0), (3600.0, 0.5, 100.0), None),
        ((0.5, 1.0), (3600.0, 0.5, 0.0), None),
        ((2.0, 0.0), (1500.0, 1.0, 30.0), None),
        ((0.5, 1.0), (3000.0, 0.5, 100.0), (0.01, 1e4, 0.0)),
        ((1.0, 0.3), (2500.0, 2.0, 300.0), (0.1, 1e3, 1.0)),
    ]
    for hand, coupling, environment in cases:
        r, f = poles(device, hand, coupling, environment, 1000.0)
        print(f"hand {hand} coupling {coupling} environment {environment}: "
              f"radius {r:.15g} at {f:.10g} Hz")


if __name__ == "__main__":
    main()
