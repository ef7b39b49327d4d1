#!/usr/bin/python3
"""The passive model's stiffness limit with the coupling damper on a filtered velocity,
computed with numpy alone (no hapticd code): an independent check of
theory::coupling_conductance, check_coupling and size_impedance_coupling.

The coupling's impedance on the backward-difference velocity is, with a = exp(-2 pi f_c T),
    Z_c(z) = k_c T / (1 - 1/z) + b_c (1 - a) / (1 - a/z)
evaluated as complex numbers on z = e^{j theta}, and the passive model with q whole periods of
delay needs, at every 0 < theta <= pi,
    Re(1/Z_c) >= (1 - cos((1 + q) theta)) / (2 b).
The largest k_c is a bisection on the worst margin, found on a dense grid and refined with
scipy's bounded scalar minimiser around the grid's minimum.

usage: tools/scripts/velocity_filter_limits.py [--mass M] [--damping B] [--rate HZ]
           [--delay-periods Q] FC:BC ...     (f_c in Hz, 0 for none; b_c in N s/m)
"""
import argparse

import numpy as np
from scipy.optimize import minimize_scalar


def margin(theta, k_c, b_c, pole, b, period, q):
    z = np.exp(1j * theta)
    z_c = k_c * period / (1.0 - 1.0 / z) + b_c * (1.0 - pole) / (1.0 - pole / z)
    need = (1.0 - np.cos((1.0 + q) * theta)) / (2.0 * b)
    return (1.0 / z_c).real / need - 1.0


def worst(k_c, b_c, pole, b, period, q, grid):
    m = margin(grid, k_c, b_c, pole, b, period, q)
    i = int(np.argmin(m))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
    r = minimize_scalar(lambda t: margin(t, k_c, b_c, pole, b, period, q), bounds=(lo, hi),
                        method="bounded", options={"xatol": 1e-12})
    return (r.fun, r.x) if r.fun < m[i] else (m[i], grid[i])


def limit(b_c, f_c, b, rate, q):
    period = 1.0 / rate
    pole = np.exp(-2.0 * np.pi * f_c * period) if f_c > 0 else 0.0
    grid = np.concatenate([np.geomspace(1e-5, 1e-2, 3000), np.linspace(1e-2, np.pi, 200000)])
    lo, hi = 0.0, 1e6
    if worst(1e-9, b_c, pole, b, period, q, grid)[0] < 0.0:
        return None, None
    while hi - lo > 1e-11 * hi:
        mid = 0.5 * (lo + hi)
        if worst(mid, b_c, pole, b, period, q, grid)[0] >= 0.0:
            lo = mid
        else:
            hi = mid
    theta = worst(lo * (1 + 1e-6), b_c, pole, b, period, q, grid)[1]
    return lo, theta / (2.0 * np.pi * period)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--mass", type=float, default=0.1)  # does not enter (21)
    parser.add_argument("--damping", type=float, default=2.0)
    parser.add_argument("--rate", type=float, default=1000.0)
    parser.add_argument("--delay-periods", type=int, default=0)
    parser.add_argument("designs", nargs="+", help="FC:BC")
    args = parser.parse_args()
    print("| f_c (Hz) | b_c (N s/m) | passive k_c (N/m) | binds at (Hz) |")
    print("|---|---|---|---|")
    for design in args.designs:
        f_c, b_c = (float(v) for v in design.split(":"))
        k_c, where = limit(b_c, f_c, args.damping, args.rate, args.delay_periods)
        if k_c is None:
            print(f"| {f_c:g} | {b_c:g} | infeasible | |")
        else:
            print(f"| {f_c:g} | {b_c:g} | {k_c:.9g} | {where:.6g} |")


if __name__ == "__main__":
    main()
