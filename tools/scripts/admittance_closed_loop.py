#!/usr/bin/python3
"""Closed-loop poles of the admittance display, computed independently of hapticd.

The exact admittance model (include/hapticd/tune/exact_admittance.hpp) builds one state
matrix per case and takes its eigenvalues. This script gets the same poles another way:
scipy samples the device (and a single-mass operator) under a zero-order hold, the force
sensor's output at nT- is C s[n] + D F[n-1], and the loop

    F = K_PI(z) (v_d - v_com),   v_d = (1 - z^-1)/T x,   v_com = Y_v(z) F_h,
    K_PI = k_p + k_i T/(1 - z^-1),  Y_v = 1/(Z_cA + Z_e),  Y_cA = 1/b_c + T/(m_c (1 - z^-1))

is closed on transfer-function polynomials; the poles are the roots of the characteristic
polynomial (numpy.roots). tests/tune/exact_admittance_test.cpp holds the C++ eigenvalues to
the numbers this prints:

    /usr/bin/python3 tools/scripts/admittance_closed_loop.py
"""

import json

import numpy as np
from numpy.polynomial import polynomial as P
from scipy import signal


def plant(m, b, m_h=0.0, b_h=0.0, k_h=0.0):
    """Device (10) with a rigid hand m_h, b_h, k_h: states (x, v), input F_d, outputs x, F_h."""
    mass = m + m_h
    a = np.array([[0.0, 1.0], [-k_h / mass, -(b + b_h) / mass]])
    bb = np.array([[0.0], [-1.0 / mass]])
    # F_h = -m_h dv/dt - b_h v - k_h x, dv/dt = (-k_h x - (b + b_h) v - F_d)/(m + m_h).
    c = np.array([[1.0, 0.0], [m_h * k_h / mass - k_h, m_h * (b + b_h) / mass - b_h]])
    d = np.array([[0.0], [m_h / mass]])
    return a, bb, c, d


def with_force_filter(a, bb, c, d, cutoff_hz, zeta):
    """Append the second-order low-pass w^2/(s^2 + 2 zeta w s + w^2) on the continuous F_h:
    states (x, v, F_f, dF_f/dt), outputs x and F_f (no feedthrough: F_f is continuous)."""
    w = 2.0 * np.pi * cutoff_hz
    af = np.array([[0.0, 1.0], [-w * w, -2.0 * zeta * w]])
    bf = np.array([[0.0], [w * w]])
    big_a = np.block([[a, np.zeros((2, 2))], [bf @ c[1:2], af]])
    big_b = np.vstack([bb, bf * d[1, 0]])
    big_c = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
    return big_a, big_b, big_c, np.zeros((2, 1))


def poly_z_inverse(num, den):
    """A ratio of polynomials in z^-1, coefficients lowest power first."""
    return np.array(num, dtype=float), np.array(den, dtype=float)


def closed_loop_poles(case):
    t = 1.0 / case["rate_hz"]
    a, b, c, d = plant(case["m"], case["b"], case.get("m_h", 0.0), case.get("b_h", 0.0),
                       case.get("k_h", 0.0))
    if "filter_hz" in case:
        a, b, c, d = with_force_filter(a, b, c, d, case["filter_hz"], case["filter_zeta"])
    phi, gamma, _, _, _ = signal.cont2discrete((a, b, c, d), t, method="zoh")
    # Transfer functions from F[n] to x[n] and to F_h(nT-), as polynomials in z^-1:
    # y = C (zI - Φ)^-1 Γ F  (+ D z^-1 F for the sensor: the force held at nT-).
    num_x, den = signal.ss2tf(phi, gamma, c[0:1], np.zeros((1, 1)))
    num_f, _ = signal.ss2tf(phi, gamma, c[1:2], np.zeros((1, 1)))
    # ss2tf gives polynomials in z (highest first) of equal degree n: in z^-1 (lowest first)
    # the same coefficient lists read in order.
    den_p = den
    x_p = num_x[0]
    f_p = P.polyadd(num_f[0], P.polymul([0.0, d[1, 0]], den_p)) if "filter_hz" not in case \
        else num_f[0]
    kp, ki = case["kp"], case["ki"]
    # K_PI = (kp (1 - z^-1) + ki T) / (1 - z^-1)
    k_num = P.polyadd(P.polymul([kp], [1.0, -1.0]), [ki * t])
    k_den = np.array([1.0, -1.0])
    if ki == 0.0:  # no integrator: no common factor (1 - z^-1) to leave a spurious root at 1
        k_num, k_den = np.array([kp]), np.array([1.0])
    # Y_v = 1 / (Z_cA + Z_e). Free space: Z_e = 0, Y_v = Y_cA; rigid wall: Y_v = 0.
    env = case["environment"]
    if env == "rigid wall":
        y_num, y_den = np.array([0.0]), np.array([1.0])
    else:
        inv_bc = 0.0 if case.get("b_c") is None else 1.0 / case["b_c"]
        # Y_cA = (inv_bc (1 - z^-1) + T/m_c) / (1 - z^-1)
        y_num = P.polyadd(P.polymul([inv_bc], [1.0, -1.0]), [t / case["m_c"]])
        y_den = np.array([1.0, -1.0])
    # 1 - K [ (1 - z^-1)/T X/F - Y_v F_h/F ] = 0, with X/F = x_p/den, F_h/F = f_p/den:
    # den k_den y_den T - k_num [ (1 - z^-1) x_p y_den - T y_num f_p ] = 0.
    lhs = P.polymul(P.polymul(den_p, k_den), y_den) * t
    inner = P.polysub(P.polymul(P.polymul([1.0, -1.0], x_p), y_den),
                      P.polymul(y_num, f_p) * t)
    char = P.polysub(lhs, P.polymul(k_num, inner))
    # char is in z^-1, lowest first, which is z^N char(1/z) highest first, as np.roots takes.
    if case.get("k_h", 0.0) == 0.0:
        # An ungrounded handle: z = 1 (where it sits) is a root; divide it out, as the C++
        # model deflates it, so that the roots near 1 stay well conditioned.
        char, remainder = np.polydiv(char, [1.0, -1.0])
        assert abs(remainder[-1]) < 1e-9 * np.max(np.abs(char)), remainder
    roots = np.roots(char)
    return sorted(roots, key=lambda r: (-abs(r), r.imag))


CASES = [
    {"name": "PI loop alone, hands-off", "m": 2.0, "b": 5.0, "rate_hz": 1000.0,
     "kp": 40.0, "ki": 2000.0, "environment": "rigid wall"},
    {"name": "stiff grasp, free space", "m": 2.0, "b": 5.0, "rate_hz": 1000.0,
     "kp": 4.0, "ki": 100.0, "m_h": 1.0, "b_h": 2.0, "k_h": 1000.0,
     "environment": "free space", "m_c": 0.5, "b_c": 30.0},
    {"name": "heavy hand, free space, pure-mass coupling", "m": 0.5, "b": 3.0,
     "rate_hz": 2000.0, "kp": 2.0, "ki": 0.0, "m_h": 3.0, "b_h": 1.0,
     "environment": "free space", "m_c": 2.0, "b_c": None},
    # The force sensor behind a second-order low-pass (force_sensor_filter.hpp).
    {"name": "stiff grasp, free space, 100 Hz filter", "m": 2.0, "b": 5.0, "rate_hz": 1000.0,
     "kp": 4.0, "ki": 100.0, "m_h": 1.0, "b_h": 2.0, "k_h": 1000.0,
     "environment": "free space", "m_c": 0.5, "b_c": 30.0, "filter_hz": 100.0,
     "filter_zeta": 0.5},
    {"name": "heavy hand, free space, 50 Hz Butterworth", "m": 0.5, "b": 3.0,
     "rate_hz": 2000.0, "kp": 2.0, "ki": 0.0, "m_h": 3.0, "b_h": 1.0,
     "environment": "free space", "m_c": 2.0, "b_c": None, "filter_hz": 50.0,
     "filter_zeta": 0.7071067811865476},
]


def main():
    out = []
    for case in CASES:
        roots = [r for r in closed_loop_poles(case) if abs(r) > 1e-9]
        out.append({"case": case["name"],
                    "poles": [[float(r.real), float(r.imag)] for r in roots]})
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
