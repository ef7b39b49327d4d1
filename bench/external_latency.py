#!/usr/bin/python3
"""Latency from a Python world's write to the servo tick that renders it (docs/benchmarks.md,
"An external world's tick, and a Python write's latency"; docs/external-worlds.md).

    PYTHONPATH=python /usr/bin/python3 bench/external_latency.py [--samples 2000] [--rate 200]
        [--hapticd build/release/bin/hapticd] [--json FILE]

Starts the real daemon in real time (not --lockstep) on config/hapticd.toml with its scene
replaced by an [external] scene (free-running: lockstep_every = 0, passivity = "control") and
the sim's push held (hold = 600 s: from 1 s to 2 s the hand's set-point ramps from 1 cm in
front of the wall to 5 mm into it, and stays), with --socket in a temporary directory.
Connects with hapticd.external.connect and renders a god-object wall at x = 0 (free side
x < 0): each update writes tool = min(handle, 0) from the step just read, no velocity. The
world is live well before the handle reaches the wall: a world whose first update comes
when the handle is already in the wall cannot push it out (the passivity controller holds
the tool where the handle took it, which would otherwise spend energy the port never took).
The samples start after WARM_UP_S, the handle in contact.

Each sample, at `--rate` Hz plus a random phase within one servo period (so that the writes
do not keep one phase against the 1 ms ticks): read the daemon's step (its `step` is the
last tick before the write), t_w = time.monotonic_ns(), u = world.write(...), then read
the daemon's block without pause until its update_in_force == u, t_seen = time.monotonic_ns()
once it does. Reported, in microseconds:

  seen - written      t_seen - t_w: an upper bound of write -> tick (it includes the last
                      read, and the write itself)
  bracket low         t_a - t_w, t_a the time just before the last read that did NOT see u:
                      the tick published after t_a, so write -> tick lies in [low, seen]
  midpoint            (low + seen) / 2, the estimate; resolution: seen - low (one read, or
                      longer when this process was preempted between two reads)
  ticks after write   the step of the first block seen with u minus the step read before
                      the write (1: the very next tick took it; 2 can mean a tick between
                      that read and the write, or a read that came late: an upper bound too)

with the median, p90, p99 and max (nearest rank), and the servo's period (1 ms) for
reference. The daemon's summary (wake-up latency, tick compute, the world's updates and stale
episodes) is printed after. A sample whose update is not seen within 100 ms counts as lost;
10 lost in a row, or no live contact after the warm-up (a fault latched: with --socket a
fault holds the force at zero until a reset), end the run with hapticd's output and status 1.
Run it under load as:

    stress-ng --cpu 2 --timeout 60 & S=$!; sleep 1
    PYTHONPATH=python /usr/bin/python3 bench/external_latency.py; kill $S

Needs no root; as root hapticd runs SCHED_FIFO 80 with mlockall (realtime = "warn"), the world
(this process) stays SCHED_OTHER.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
import re
import signal
import subprocess
import sys
import tempfile
import time
from typing import Any, Dict, List, Optional, Sequence

import run_info

try:
    from hapticd import external
except ImportError:
    sys.exit("external_latency.py: run with PYTHONPATH=python (hapticd.external not found)")

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = """[scene]
name = "external-wall"
axes = 1

[external]
between_updates = "extrapolate"
lockstep_every = 0
passivity = "control"
"""
LOST_AFTER_NS = 100_000_000
LOST_IN_A_ROW = 10


class Abort(Exception):
    """The run cannot be measured (the daemon faulted, or never reached the contact)."""
WARM_UP_S = 3.0      # the world live; the push from 1 s to 2 s, then 1 s to settle


def derived_config(scene_path: str) -> str:
    """config/hapticd.toml, its scene the external one, the push held."""
    with open(os.path.join(ROOT, "config", "hapticd.toml"), encoding="utf-8") as source:
        text = source.read()
    replacements = ((r'(?m)^file = "scenes/demo-wall\.toml"', f'file = "{scene_path}"'),
                    (r"(?m)^(push = \{.*hold = )3\.0 \}$", r"\g<1>600.0 }"))
    for pattern, replacement in replacements:
        text, count = re.subn(pattern, replacement, text)
        if count != 1:
            raise SystemExit(f"external_latency.py: config/hapticd.toml has no line matching "
                             f"{pattern!r}: update derived_config()")
    return text


def nearest_rank(values: Sequence[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[max(0, math.ceil(q * len(ordered)) - 1)]


def line(name: str, values_us: Sequence[float]) -> str:
    if not values_us:
        return f"{name:<28} (none)"
    return (f"{name:<28} median {nearest_rank(values_us, 0.5):8.1f}   p90 "
            f"{nearest_rank(values_us, 0.9):8.1f}   p99 {nearest_rank(values_us, 0.99):8.1f}   "
            f"max {max(values_us):8.1f} us")


def wall(step: external.Step) -> List[float]:
    """The world: a god-object wall at x = 0, free side x < 0."""
    return [min(step.handle_position_m[0], 0.0)]


def measure(world: external.World, samples: int, rate_hz: float, period_s: float,
            rng: random.Random) -> List[Dict[str, Any]]:
    results: List[Dict[str, Any]] = []
    # Warm-up: the world live, the handle into its wall.
    end = time.monotonic() + WARM_UP_S
    while time.monotonic() < end:
        world.write(wall(world.read()))
        time.sleep(1.0 / rate_hz)
    first = world.read()
    time.sleep(0.02)
    ready = world.read()
    if (ready.step - first.step < 10 or ready.state != "live"
            or ready.handle_position_m[0] <= 0.0):
        raise Abort(f"after the {WARM_UP_S:g} s warm-up: {ready.step - first.step} steps in "
                    f"20 ms, the world {ready.state}, the handle at "
                    f"{ready.handle_position_m[0] * 1e3:.3f} mm (wanted: steps, live, in "
                    f"contact > 0); a fault?")
    start = time.monotonic()
    lost_in_a_row = 0
    for k in range(samples):
        due = start + k / rate_hz + rng.uniform(0.0, period_s)
        pause = due - time.monotonic()
        if pause > 0.0:
            time.sleep(pause)
        before = world.read()
        written_ns = time.monotonic_ns()
        update = world.write(wall(before))
        last_miss_ns = written_ns     # the write ended after this: the tick cannot be earlier
        while True:
            read_at_ns = time.monotonic_ns()
            step = world.read()
            seen_ns = time.monotonic_ns()
            if step.update_in_force == update:
                break
            last_miss_ns = read_at_ns
            if seen_ns - written_ns > LOST_AFTER_NS:
                step = None
                break
        if step is None:
            results.append({"update": update, "lost": 1})
            lost_in_a_row += 1
            if lost_in_a_row >= LOST_IN_A_ROW:
                raise Abort(f"{lost_in_a_row} updates in a row not rendered within "
                            f"{LOST_AFTER_NS / 1e6:g} ms: the servo stopped rendering (a fault "
                            f"latched?)")
            continue
        lost_in_a_row = 0
        results.append({"update": update, "lost": 0,
                        "written_ns": written_ns, "seen_ns": seen_ns, "low_ns": last_miss_ns,
                        "step_before": before.step, "step_first": step.step,
                        "time_before_s": before.time_s, "time_first_s": step.time_s,
                        "state": step.state, "handle_m": step.handle_position_m[0],
                        "tool_m": step.tool_position_m[0],
                        "force_n": step.coupling_force_n[0]})
    return results


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--hapticd", default=os.path.join(ROOT, "build/release/bin/hapticd"))
    parser.add_argument("--samples", type=int, default=2000)
    parser.add_argument("--rate", type=float, default=200.0, help="writes per second")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--json", help="write every sample and the summary here")
    arguments = parser.parse_args(argv)
    if arguments.samples < 1 or not 0.0 < arguments.rate <= 1000.0:
        parser.error("--samples >= 1 and 0 < --rate <= 1000")

    machine = run_info.machine()
    build = run_info.build(arguments.hapticd)
    with tempfile.TemporaryDirectory(prefix="external_latency.") as scratch:
        scene_path = os.path.join(scratch, "external-wall.toml")
        config_path = os.path.join(scratch, "hapticd.toml")
        socket_path = os.path.join(scratch, "hapticd.sock")
        summary_path = os.path.join(scratch, "summary.json")
        with open(scene_path, "w", encoding="utf-8") as out:
            out.write(SCENE)
        with open(config_path, "w", encoding="utf-8") as out:
            out.write(derived_config(scene_path))
        duration_s = WARM_UP_S + arguments.samples / arguments.rate + 60.0
        command = [arguments.hapticd, "--config", config_path, "--socket", socket_path,
                   "--duration", f"{duration_s:g}", "--no-status", "--summary", summary_path]
        log_path = os.path.join(scratch, "hapticd.log")
        with open(log_path, "w", encoding="utf-8") as log:
            daemon = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT)
        try:
            with external.connect(external.channel_beside(socket_path),
                                  timeout_s=10.0) as world:
                period_s = 1.0 / world.rate_hz
                results = measure(world, arguments.samples, arguments.rate, period_s,
                                  random.Random(arguments.seed))
                last = world.read()
        except BaseException as error:
            daemon.kill()
            daemon.wait()
            with open(log_path, encoding="utf-8") as log:
                sys.stderr.write(log.read())
            if isinstance(error, (Abort, external.WorldError)):
                print(f"external_latency.py: {error}; hapticd's output is above",
                      file=sys.stderr)
                return 1
            raise
        daemon.send_signal(signal.SIGTERM)
        status = daemon.wait(timeout=30)
        with open(log_path, encoding="utf-8") as log:
            daemon_log = log.read()
        try:
            with open(summary_path, encoding="utf-8") as source:
                summary = json.load(source)
        except (OSError, ValueError):
            summary = {}
        if status != 0:
            sys.stderr.write(daemon_log)
            print(f"external_latency.py: hapticd exited {status}", file=sys.stderr)

    kept = [r for r in results if not r["lost"]]
    seen_us = [(r["seen_ns"] - r["written_ns"]) / 1e3 for r in kept]
    low_us = [(r["low_ns"] - r["written_ns"]) / 1e3 for r in kept]
    mid_us = [(s + lo) / 2.0 for s, lo in zip(seen_us, low_us)]
    width_us = [s - lo for s, lo in zip(seen_us, low_us)]
    ticks = [r["step_first"] - r["step_before"] for r in kept]
    not_live = sum(1 for r in kept if r["state"] != "live")
    load = ", ".join(f"{x:g}" for x in os.getloadavg())
    print(f"external_latency.py: {time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime())}, "
          f"{run_info.caption_machine(machine)}, load at start "
          f"{', '.join(f'{x:g}' for x in machine['load_average_1_5_15'])} (now {load}); "
          f"{run_info.caption_build(build)}")
    print(f"samples                      {len(results)} at {arguments.rate:g} Hz + a random "
          f"phase; {len(results) - len(kept)} lost (> 100 ms); {not_live} not live")
    print(f"servo period                 {period_s * 1e6:.0f} us (reference)")
    print(line("seen - written (upper)", seen_us))
    print(line("bracket low", low_us))
    print(line("midpoint (estimate)", mid_us))
    print(line("resolution (seen - low)", width_us))
    if ticks:
        counts = {n: ticks.count(n) for n in sorted(set(ticks))}
        shares = ", ".join(f"{n}: {c} ({100.0 * c / len(ticks):.1f} %)"
                           for n, c in counts.items())
        print(f"ticks after write            {shares}")
    print(f"contact at the end           handle {last.handle_position_m[0] * 1e3:.3f} mm, tool "
          f"{last.tool_position_m[0] * 1e3:.3f} mm (the world wants 0), force on the tool "
          f"{last.coupling_force_n[0]:.2f} N, {last.state}")
    wake = summary.get("wake_latency_us", {})
    compute = summary.get("tick_compute_us", {})
    world_summary = summary.get("external_world", {})
    realtime = summary.get("realtime", {})
    if summary:
        print(f"hapticd wake latency         p50 {wake.get('p50', math.nan):.1f}   p99 "
              f"{wake.get('p99', math.nan):.1f}   max {wake.get('max', math.nan):.1f} us; "
              f"{summary.get('overruns')} overruns, {summary.get('ticks')} ticks; "
              f"sched_fifo {realtime.get('sched_fifo')}")
        print(f"hapticd tick compute         p50 {compute.get('p50', math.nan):.2f}   p99 "
              f"{compute.get('p99', math.nan):.2f}   max {compute.get('max', math.nan):.1f} us")
        print(f"hapticd external world       {world_summary.get('updates')} updates, stale "
              f"{world_summary.get('stale_episodes')} times, "
              f"{world_summary.get('rejected_updates')} refused, removed "
              f"{world_summary.get('energy_removed_j', math.nan):.3g} J; faults "
              f"{summary.get('faults')}; exit {summary.get('exit')}")
    else:
        print("hapticd summary              (none written)")
    if arguments.json:
        with open(arguments.json, "w", encoding="utf-8") as out:
            json.dump({"schema": "hapticd-external-latency/1", "machine": machine,
                       "build": build, "command": command, "rate_hz": arguments.rate,
                       "samples": results, "summary": summary}, out, indent=1)
    return 0 if status == 0 and kept else 1


if __name__ == "__main__":
    sys.exit(main())
