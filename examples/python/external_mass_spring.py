#!/usr/bin/env python3
"""Render a virtual mass on a spring through hapticd's external world channel.

    PYTHONPATH=python examples/python/external_mass_spring.py --instance sim --mass-kg 0.5

On each of the scene's axes a mass (--mass-kg) hangs on a spring (--stiffness-n-per-m) to the
anchor 0 with a damper (--damping-n-s-per-m), and the daemon's coupling ties it to the handle
with the gains k_c, b_c each step carries (docs/external-worlds.md). The world integrates the
mass over each interval with implicit (backward) Euler, which never adds energy; it starts at
rest where the daemon has the tool. In lockstep the world answers each step that waits;
free-running it writes at --rate-hz. Runs for --duration-s, or until the daemon lets go of the
channel or Ctrl-C; prints the updates written and the energy the daemon's passivity controller
removed.
"""

import argparse
import math
import sys
from typing import List, Optional, Sequence, Tuple

from hapticd import external


def step(x0: float, v0: float, xd: float, vd: float, dt_s: float, *, mass_kg: float,
         stiffness_n_per_m: float, damping_n_s_per_m: float,
         coupling_stiffness_n_per_m: float, coupling_damping_n_s_per_m: float,
         explicit: bool = False) -> Tuple[float, float]:
    """One axis of the mass over dt_s: its (position, velocity) at the end, from (x0, v0), the
    handle at xd moving at vd, the spring k_s and damper b_s to the anchor 0 and the coupling
    k_c, b_c. Implicit (backward) Euler, or, with `explicit`, forward Euler."""
    m, k_s, b_s = mass_kg, stiffness_n_per_m, damping_n_s_per_m
    k_c, b_c = coupling_stiffness_n_per_m, coupling_damping_n_s_per_m
    if explicit:
        # m a0 = -k_s x0 - b_s v0 + k_c (xd - x0) + b_c (vd - v0); x1 = x0 + dt v0, v1 = v0 + dt a0
        a0 = (-k_s * x0 - b_s * v0 + k_c * (xd - x0) + b_c * (vd - v0)) / m
        return x0 + dt_s * v0, v0 + dt_s * a0
    # Backward Euler, the handle moving linearly from xd at vd over the interval:
    #   m (v1 - v0)/dt = -k_s x1 - b_s v1 + k_c (xd1 - x1) + b_c (vd - v1)
    #   x1 = x0 + dt v1,   xd1 = xd + vd dt
    # Putting x1 in the first:
    #   m (v1 - v0) = dt [k_c xd1 + b_c vd - (k_s + k_c)(x0 + dt v1) - (b_s + b_c) v1]
    #   v1 (m + dt (b_s + b_c) + dt^2 (k_s + k_c)) = m v0 + dt (k_c xd1 + b_c vd - (k_s + k_c) x0)
    # so v1 is that quotient, and x1 = x0 + dt v1: the 2x2 linear update solved exactly.
    denominator = m + dt_s * (b_s + b_c) + dt_s * dt_s * (k_s + k_c)
    if not denominator > 0.0:
        raise ValueError(f"m + dt (b_s + b_c) + dt^2 (k_s + k_c) = {denominator!r}: the implicit "
                         f"step needs it > 0 (a damping too negative for dt = {dt_s!r})")
    xd1 = xd + vd * dt_s
    v1 = (m * v0 + dt_s * (k_c * xd1 + b_c * vd - (k_s + k_c) * x0)) / denominator
    return x0 + dt_s * v1, v1


class MassSpring:
    """The mass on `axes` axes, as World.run()'s step function: each call integrates it over
    dt_s against the step's handle and coupling gains and returns (position, velocity). It
    starts at rest at `position_m`, or where the first step has the tool."""

    def __init__(self, axes: int, mass_kg: float = 0.5, stiffness_n_per_m: float = 100.0,
                 damping_n_s_per_m: float = 1.0, *, explicit: bool = False,
                 position_m: Optional[Sequence[float]] = None):
        if not 1 <= axes <= 3:
            raise ValueError(f"axes = {axes}: 1 to 3")
        if not (mass_kg > 0.0 and math.isfinite(mass_kg)):
            raise ValueError(f"mass {mass_kg!r} kg: a finite mass > 0")
        if not (stiffness_n_per_m >= 0.0 and math.isfinite(stiffness_n_per_m)):
            raise ValueError(f"stiffness {stiffness_n_per_m!r} N/m: finite and >= 0")
        if not math.isfinite(damping_n_s_per_m):
            raise ValueError(f"damping {damping_n_s_per_m!r} N s/m: a finite number")
        self.axes = axes
        self.mass_kg = mass_kg
        self.stiffness_n_per_m = stiffness_n_per_m
        self.damping_n_s_per_m = damping_n_s_per_m
        self.explicit = explicit
        self.position_m: Optional[List[float]] = (
            [float(x) for x in position_m][:axes] if position_m is not None else None)
        self.velocity_mps = [0.0] * axes

    def __call__(self, now: external.Step, dt_s: float) -> Tuple[List[float], List[float]]:
        if self.position_m is None:
            self.position_m = list(now.tool_position_m[:self.axes])
        for axis in range(self.axes):
            self.position_m[axis], self.velocity_mps[axis] = step(
                self.position_m[axis], self.velocity_mps[axis], now.handle_position_m[axis],
                now.handle_velocity_mps[axis], dt_s, mass_kg=self.mass_kg,
                stiffness_n_per_m=self.stiffness_n_per_m,
                damping_n_s_per_m=self.damping_n_s_per_m,
                coupling_stiffness_n_per_m=now.stiffness_n_per_m,
                coupling_damping_n_s_per_m=now.damping_n_s_per_m, explicit=self.explicit)
        return list(self.position_m), list(self.velocity_mps)


def main(argv: Optional[Sequence[str]] = None, *, prog: str = "external_mass_spring",
         description: Optional[str] = None, nonpassive: bool = False,
         damping_n_s_per_m: float = 1.0) -> int:
    """The example's command line (external_nonpassive.py runs it `nonpassive`: a negative
    default damping, whose sign it allows, and a choice of integration)."""
    parser = argparse.ArgumentParser(prog=prog,
                                     description=description or __doc__.splitlines()[0])
    channel = parser.add_mutually_exclusive_group(required=True)
    channel.add_argument("--instance", help="hapticd@NAME's channel, /run/hapticd/NAME.world")
    channel.add_argument("--channel", metavar="PATH",
                         help="a channel's path (SOCKET.world beside a daemon's --socket)")
    parser.add_argument("--mass-kg", type=float, default=0.5, help="the mass (default 0.5)")
    parser.add_argument("--stiffness-n-per-m", type=float, default=100.0,
                        help="the spring to the anchor 0 (default 100)")
    parser.add_argument("--damping-n-s-per-m", type=float, default=damping_n_s_per_m,
                        help=f"the damper (default {damping_n_s_per_m:g}"
                             f"{'; negative allowed' if nonpassive else ''})")
    if nonpassive:
        parser.add_argument("--integration", choices=("implicit", "explicit"),
                            default="implicit",
                            help="backward Euler (default), or forward Euler, which at this "
                                 "rate and the coupling's stiffness injects energy of its own")
    parser.add_argument("--rate-hz", type=float, default=100.0,
                        help="the world's rate when the channel is free-running (default 100)")
    parser.add_argument("--duration-s", type=float, default=None,
                        help="stop after this long (the daemon's time in lockstep; default: "
                             "until the daemon lets go, or Ctrl-C)")
    arguments = parser.parse_args(argv)
    explicit = nonpassive and arguments.integration == "explicit"
    if arguments.damping_n_s_per_m < 0.0 and not nonpassive:
        parser.error(f"--damping-n-s-per-m {arguments.damping_n_s_per_m:g}: >= 0 (a negative "
                     f"damping is external_nonpassive.py's)")
    return external.serve(
        lambda world: MassSpring(world.axes, arguments.mass_kg, arguments.stiffness_n_per_m,
                                 arguments.damping_n_s_per_m, explicit=explicit),
        name=prog, path=arguments.channel, instance=arguments.instance,
        rate_hz=arguments.rate_hz, duration_s=arguments.duration_s)

if __name__ == "__main__":
    sys.exit(main())
