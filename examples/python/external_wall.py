#!/usr/bin/env python3
"""Render a rigid wall through hapticd's external world channel.

    PYTHONPATH=python examples/python/external_wall.py --instance sim

The wall is the plane x0 = --offset-m with free space on the side --normal points to (as a
scene's [[wall]] normal: -1, the default, is the demo wall's, free space x0 < offset). The tool
is a god-object: the handle projected onto free space, the other axes the handle's. The daemon's coupling pulls the handle toward the tool, so it feels the wall with
the coupling's stiffness (docs/external-worlds.md). In lockstep the world answers each step
that waits; free-running it writes at --rate-hz. Runs for --duration-s, or until the daemon
lets go of the channel or Ctrl-C; prints the updates written and the energy the daemon's
passivity controller removed.
"""

import argparse
import math
import sys
from typing import List, Optional, Sequence

from hapticd import external


def step(handle_position_m: Sequence[float], offset_m: float = 0.0,
         normal: int = -1) -> List[float]:
    """The tool: the handle's position projected onto free space, normal * (x0 - offset_m) >= 0."""
    tool = [float(x) for x in handle_position_m]
    tool[0] = max(tool[0], offset_m) if normal > 0 else min(tool[0], offset_m)
    return tool


def tool_velocity(handle_position_m: Sequence[float], handle_velocity_mps: Sequence[float],
                  dt_s: float, offset_m: float = 0.0, normal: int = -1) -> List[float]:
    """The tool's velocity, for the daemon's extrapolation until the next update, dt_s on: the
    handle's in free space, but never so fast toward the wall that it would cross it within
    dt_s; in contact, 0 along the normal (the tool rests on the wall)."""
    velocity = [float(v) for v in handle_velocity_mps]
    tool_x = step(handle_position_m, offset_m, normal)[0]
    if tool_x != handle_position_m[0]:
        velocity[0] = 0.0
    elif normal > 0:
        velocity[0] = max(velocity[0], (offset_m - tool_x) / dt_s)
    else:
        velocity[0] = min(velocity[0], (offset_m - tool_x) / dt_s)
    return velocity


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog="external_wall", description=__doc__.splitlines()[0])
    channel = parser.add_mutually_exclusive_group(required=True)
    channel.add_argument("--instance", help="hapticd@NAME's channel, /run/hapticd/NAME.world")
    channel.add_argument("--channel", metavar="PATH",
                         help="a channel's path (SOCKET.world beside a daemon's --socket)")
    parser.add_argument("--offset-m", type=float, default=0.0,
                        help="where the wall is on axis 0 (default 0)")
    parser.add_argument("--normal", type=int, choices=(-1, 1), default=-1,
                        help="the side of free space on axis 0 (default -1: x0 < offset)")
    parser.add_argument("--rate-hz", type=float, default=100.0,
                        help="the world's rate when the channel is free-running (default 100)")
    parser.add_argument("--duration-s", type=float, default=None,
                        help="stop after this long (the daemon's time in lockstep; default: "
                             "until the daemon lets go, or Ctrl-C)")
    arguments = parser.parse_args(argv)
    if not math.isfinite(arguments.offset_m):
        parser.error(f"--offset-m {arguments.offset_m}: a finite number of metres")
    def make_step(world: external.World):
        def tool(now: external.Step, dt_s: float):
            handle = now.handle_position_m[:world.axes]
            return (step(handle, arguments.offset_m, arguments.normal),
                    tool_velocity(handle, now.handle_velocity_mps[:world.axes], dt_s,
                                  arguments.offset_m, arguments.normal))
        return tool

    return external.serve(make_step, name="external_wall", path=arguments.channel,
                          instance=arguments.instance, rate_hz=arguments.rate_hz,
                          duration_s=arguments.duration_s)

if __name__ == "__main__":
    sys.exit(main())
