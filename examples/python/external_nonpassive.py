#!/usr/bin/env python3
"""Render a deliberately non-passive world through hapticd's external world channel.

    PYTHONPATH=python examples/python/external_nonpassive.py --instance sim

external_mass_spring.py's mass on a spring, with a NEGATIVE damping (--damping-n-s-per-m,
default -15 N s/m: more than the device and the hand dissipate), so that the world injects
energy; --integration explicit (forward Euler, unstable at 100 Hz against the coupling's
stiffness) injects more. With the daemon's passivity controller on the environment port
([external] passivity = "control", docs/external-worlds.md) the handle stays stable: the
controller removes what the world injects, and the summary's external_world energy_removed_j
counts it. With passivity = "off" the motion grows. The options are external_mass_spring.py's;
the damping may be negative.
"""

import os
import sys
from typing import Optional, Sequence, Tuple

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import external_mass_spring  # noqa: E402  (the sibling example, from this directory)


def step(x0: float, v0: float, xd: float, vd: float, dt_s: float, *, mass_kg: float = 0.5,
         stiffness_n_per_m: float = 100.0, damping_n_s_per_m: float = -15.0,
         coupling_stiffness_n_per_m: float = 0.0,
         coupling_damping_n_s_per_m: float = 0.0) -> Tuple[float, float]:
    """One axis of the non-passive mass over dt_s: external_mass_spring.step, explicit."""
    return external_mass_spring.step(
        x0, v0, xd, vd, dt_s, mass_kg=mass_kg, stiffness_n_per_m=stiffness_n_per_m,
        damping_n_s_per_m=damping_n_s_per_m, coupling_stiffness_n_per_m=coupling_stiffness_n_per_m,
        coupling_damping_n_s_per_m=coupling_damping_n_s_per_m, explicit=True)


def main(argv: Optional[Sequence[str]] = None) -> int:
    return external_mass_spring.main(argv, prog="external_nonpassive",
                                     description=__doc__.splitlines()[0], nonpassive=True,
                                     damping_n_s_per_m=-15.0)


if __name__ == "__main__":
    sys.exit(main())
