#!/usr/bin/python3
"""Instructions per servo tick of the unchanged hapticd, counted by valgrind's callgrind (no
hardware counters needed): a number for regression tracking that does not move with the
machine's load (docs/benchmarks.md, "Instructions per tick").

Method: for each shipped scene of config/scenes/ that the sim device can run (a scene's
`axes` up to the sim's 3) and each device axis count from the scene's up to 3, hapticd runs
in lockstep under callgrind for a short and a long duration,

  valgrind --tool=callgrind --separate-threads=yes hapticd --lockstep --duration S
      --config C --no-status --summary J

and instructions per tick = (Ir(long) - Ir(short)) / (ticks(long) - ticks(short)), Ir of
the servo thread (the one that runs ServoLoop::run), which cancels the thread's start and
end. The other threads are left out: the main thread watches the servo every 10 ms of wall
time (src/daemon/run/run_watcher.cpp), so its count follows wall time (300,000 instructions
apart between identical runs under callgrind). The servo thread's own count moved by under 10,000 instructions between
identical runs (it publishes its status once a second of wall time): under 1 instruction a
tick in quick mode, under 0.2 in the default.

C is the sim pen display of config/hapticd.toml (m = 0.1 kg, b = 2 N s/m, 10 um counts,
k_c = 3600 N/m) with every axis held by a stiff grasp (hand 0.3 kg, 500 N/m, 5 N s/m) whose
fixed set-point lies beyond the surface, as bench/daemon/full_stack.cpp's scenarios: the
short run (6 s) ends after the handle has come into contact and the soft start is over, so
the ticks counted are a loaded contact. A plain native run of the long duration with --log
checks that: `force_n` is the median and minimum |f| over the counted ticks.

Usage:
  bench/tick_instructions.py [--hapticd PATH] [--quick] [--json FILE] [--chart FILE]

--quick counts 10,000 ticks a configuration (about 10 s on 2 cores), the default 60,000
(about 25 s). The configurations run side by side, one per CPU (callgrind's counts do not
depend on it).
As a module: measure(hapticd, source_dir, quick) -> dict, draw(data, chart_path).

Data file (--json), "schema": "hapticd-tick-instructions/1":
  schema, date_utc, quick, rate_hz, short_s, long_s (the two --duration values),
  machine {cpu_model, cpus, kernel, load_average_1_5_15}, build {hapticd, version,
  build_type, source_commit}, tools {valgrind, hapticd},
  configs [{scene (file name), scene_name, scene_axes, axes (the device's), hold (the
            set-point, m), ticks_short, ticks_long, instructions_short, instructions_long,
            instructions_per_tick, force_n {median, min} over the counted ticks}]

Exit status: 0 done; 1 a run failed (its command and message are printed); 2 bad usage or
valgrind missing.
"""

import argparse
import concurrent.futures
import csv
import datetime
import glob
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import tomllib

BENCH_DIR = os.path.dirname(os.path.abspath(__file__))
SOURCE_DIR = os.path.dirname(BENCH_DIR)
sys.path.insert(0, BENCH_DIR)
import run_info  # noqa: E402

RATE_HZ = 1000.0
SIM_MAX_AXES = 3
SHORT_S = 6.0  # into contact, soft start over (full_stack.hpp warms up 5,000 ticks)
COUNTED_S = {"quick": 10.0, "full": 60.0}
DEFAULT_HAPTICD = os.path.join(SOURCE_DIR, "build", "release", "bin", "hapticd")

# Set-points (m, x y z) that hold the handle in each scene's contact, as in
# bench/daemon/full_stack.cpp; components beyond the device's axes are dropped. A scene not
# listed here is held at the origin (its JSON "hold" says so).
HOLDS_M = {
    "demo-wall.toml": ((0.005, 0.0, 0.0), (-0.002, 0.0, 0.0)),       # 5 mm into the wall
    "box-16-planes.toml": ((0.06, 0.06, 0.0425), (0.0, 0.0, 0.0)),   # past a chamfered corner
    "god-object-sphere.toml": ((0.05, 0.0, 0.0), (0.0, 0.0, 0.0)),   # 7.6 mm into the ball
    "virtual-mass.toml": ((0.0, 0.0, -0.05), (0.0, 0.0, 0.0)),       # the puck onto the floor
    "detent-friction.toml": ((0.0037, 0.002, 0.0), (0.0, 0.0, 0.0)),  # on a detent's slope,
                                                                      # friction stuck
}


class BenchError(Exception):
    def __init__(self, message, exit_code=1):
        super().__init__(message)
        self.exit_code = exit_code


def shipped_scenes(source_dir):
    """(file name, scene name, axes) of every scene in config/scenes/ the sim can run."""
    scenes = []
    for path in sorted(glob.glob(os.path.join(source_dir, "config", "scenes", "*.toml"))):
        with open(path, "rb") as text:
            table = tomllib.load(text).get("scene", {})
        axes = int(table.get("axes", 0))
        if 1 <= axes <= SIM_MAX_AXES:
            scenes.append((os.path.basename(path), table.get("name", ""), axes))
    if not scenes:
        raise BenchError(f"no scenes found under {source_dir}/config/scenes", 2)
    return scenes


def toml_vector(values):
    return "[" + ", ".join(repr(float(v)) for v in values) + "]"


def config_text(source_dir, scene_file, axes):
    set_point_m, initial_m = HOLDS_M.get(scene_file, ((0.0,) * 3, (0.0,) * 3))
    humans = "".join(
        "\n[[device.sim.human]]\nmodel = \"stiff-grasp\"\nhand_mass = 0.3\n"
        f"hand_stiffness = 500.0\nhand_damping = 5.0\nset_point = {set_point_m[axis]!r}\n"
        for axis in range(axes))
    scene_path = os.path.join(source_dir, "config", "scenes", scene_file)
    return f"""# bench/tick_instructions.py: {scene_file} on a {axes}-axis sim pen display, held in contact
[servo]
rate_hz = {RATE_HZ}
[device]
plugin = "sim"
axes = {axes}
[device.model]
mass = 0.1
damping = 2.0
[coupling]
stiffness = 3600.0
damping = 0.0
[scene]
file = {json.dumps(scene_path)}
[safety]
max_force = 20.0
max_speed = 1.0
[device.sim]
mass = 0.1
damping = 2.0
counts_per_meter = 1e5
force_limit = 20.0
clock = "lockstep"
initial_position = {toml_vector(initial_m[:axes])}
{humans}"""


def run(command, what):
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        tail = "\n".join((done.stderr or done.stdout).strip().splitlines()[-8:])
        raise BenchError(f"{what} exited with status {done.returncode}: "
                         f"{' '.join(command)}\n{tail}")
    return done


SERVO_RUN = re.compile(r"ServoLoop<.*>::run\(")


def servo_thread_instructions(path):
    """Ir of one thread's callgrind file when it is the servo thread (it runs
    ServoLoop::run), else None. Names are compressed: "fn=(id) name" once, "fn=(id)" after."""
    run_ids, runs_here, total = set(), False, None
    with open(path, encoding="utf-8", errors="replace") as text:
        for line in text:
            if line.startswith(("fn=(", "cfn=(")):
                ident, _, name = line.split("=", 1)[1].partition(")")
                if name and SERVO_RUN.search(name):
                    run_ids.add(ident)
                if line.startswith("fn=(") and ident in run_ids:
                    runs_here = True
            elif line.startswith(("totals:", "summary:")):
                total = int(line.split()[1])
    return total if runs_here else None


def callgrind_instructions(hapticd, config, seconds, work, tag):
    """(Ir of the servo thread, ticks) of one lockstep run under callgrind."""
    base, summary = os.path.join(work, f"{tag}.callgrind"), os.path.join(work, f"{tag}.json")
    run(["valgrind", "--tool=callgrind", "-q", "--separate-threads=yes",
         f"--callgrind-out-file={base}", hapticd, "--lockstep", "--duration", f"{seconds:g}",
         "--config", config, "--no-status", "--summary", summary],
        f"callgrind of hapticd --duration {seconds:g}")
    counts = [count for count in (servo_thread_instructions(path)
                                  for path in sorted(glob.glob(base + "-*"))) if count is not None]
    if len(counts) != 1:
        raise BenchError(f"{base}-*: {len(counts)} threads run ServoLoop::run, not one "
                         "(renamed, or callgrind's output format changed?)")
    with open(summary, encoding="utf-8") as text:
        report = json.load(text)
    if report.get("faults"):
        raise BenchError(f"hapticd faulted under {config}: {report['faults']}")
    return counts[0], int(report["ticks"])


def contact_force_n(hapticd, config, short_ticks, long_s, work):
    """Median and minimum |f| (N) over the counted ticks, from a native run with --log."""
    log = os.path.join(work, "contact.csv")
    run([hapticd, "--lockstep", "--duration", f"{long_s:g}", "--config", config, "--no-status",
         "--log", log], "hapticd (the contact check)")
    forces = []
    with open(log, encoding="utf-8", newline="") as text:
        rows = csv.reader(line for line in text if not line.startswith("#"))
        header = next(rows)
        tick = header.index("tick")
        columns = [i for i, name in enumerate(header) if name.startswith("f") and
                   name.endswith("_n") and name[1:-2].isdigit()]
        for row in rows:
            if int(row[tick]) >= short_ticks:
                forces.append(math.sqrt(sum(float(row[i]) ** 2 for i in columns)))
    forces.sort()
    if not forces:
        raise BenchError(f"{log}: no ticks after {short_ticks}")
    return {"median": round(forces[len(forces) // 2], 4), "min": round(forces[0], 4)}


def measure_config(hapticd, source_dir, scene, axes, short_s, long_s):
    scene_file, scene_name, scene_axes = scene
    with tempfile.TemporaryDirectory(prefix="tick-instructions-") as work:
        config = os.path.join(work, "hapticd.toml")
        with open(config, "w", encoding="utf-8") as text:
            text.write(config_text(source_dir, scene_file, axes))
        ir_short, ticks_short = callgrind_instructions(hapticd, config, short_s, work, "short")
        ir_long, ticks_long = callgrind_instructions(hapticd, config, long_s, work, "long")
        force = contact_force_n(hapticd, config, ticks_short, long_s, work)
    set_point_m = HOLDS_M.get(scene_file, ((0.0,) * 3,))[0][:axes]
    return {
        "scene": scene_file, "scene_name": scene_name, "scene_axes": scene_axes, "axes": axes,
        "hold": {"set_point_m": list(set_point_m),
                 "listed": scene_file in HOLDS_M},
        "ticks_short": ticks_short, "ticks_long": ticks_long,
        "instructions_short": ir_short, "instructions_long": ir_long,
        "instructions_per_tick": round((ir_long - ir_short) / (ticks_long - ticks_short), 1),
        "force_n": force,
    }


def measure(hapticd=DEFAULT_HAPTICD, source_dir=SOURCE_DIR, quick=False, scene_names=None):
    """Counts every (scene, axes) configuration, one per CPU at a time (only the scenes named
    in `scene_names`, by their [scene] name, when it is given); returns the data file's dict.
    Raises BenchError."""
    valgrind = run_info.tool_version(["valgrind", "--version"])
    if valgrind is None:
        raise BenchError("valgrind not found on PATH (Debian package valgrind: "
                         "scripts/install-deps installs it)", 2)
    if not (os.path.isfile(hapticd) and os.access(hapticd, os.X_OK)):
        raise BenchError(f"hapticd not found or not executable: {hapticd} (--hapticd PATH)", 2)
    short_s = SHORT_S
    long_s = SHORT_S + COUNTED_S["quick" if quick else "full"]
    scenes = sorted(shipped_scenes(source_dir), key=lambda scene: (scene[2], scene[1]))
    if scene_names is not None:
        scenes = [scene for scene in scenes if scene[1] in scene_names]
        if not scenes:
            raise BenchError(f"no shipped scene is named {', '.join(scene_names)}", 2)
    jobs = [(scene, axes) for scene in scenes
            for axes in range(scene[2], SIM_MAX_AXES + 1)]
    data = {
        "schema": "hapticd-tick-instructions/1",
        "date_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "quick": bool(quick), "rate_hz": RATE_HZ, "short_s": short_s, "long_s": long_s,
        "machine": run_info.machine(),
        "build": run_info.build(hapticd),
        "tools": {"valgrind": valgrind, "hapticd": run_info.tool_version([hapticd, "--version"])},
    }
    pool = concurrent.futures.ThreadPoolExecutor(max_workers=os.cpu_count() or 1)
    try:
        futures = [pool.submit(measure_config, hapticd, source_dir, scene, axes, short_s, long_s)
                   for scene, axes in jobs]
        data["configs"] = [future.result() for future in futures]
    finally:
        pool.shutdown(wait=True, cancel_futures=True)  # after a failure, start no more
    return data


def print_table(data, out=sys.stdout):
    print(f"tick_instructions.py: {data['date_utc']}, {data['tools']['valgrind']}, "
          f"{data['build']['version']} {data['build']['build_type']}; "
          f"--duration {data['short_s']:g} and {data['long_s']:g} s in lockstep", file=out)
    print(f"{'scene':24} {'axes':>4} {'instructions/tick':>18} {'|f| median (N)':>15}", file=out)
    for c in data["configs"]:
        print(f"{c['scene_name']:24} {c['axes']:>4} {c['instructions_per_tick']:>18,.1f} "
              f"{c['force_n']['median']:>15.2f}", file=out)


def draw(data, chart_path):
    """Bar chart: instructions per tick, one group per scene, one bar per device axis count."""
    sys.path.insert(0, os.path.join(SOURCE_DIR, "tools", "plot"))
    import chart_style
    plt, np = chart_style.pyplot(font_size_pt=9)
    figure = chart_style.new_figure(plt, (7.0, 3.8))
    ax = figure.add_subplot(1, 1, 1)
    scenes = []
    for c in data["configs"]:
        if c["scene_name"] not in scenes:
            scenes.append(c["scene_name"])
    colors = {1: "tab:blue", 2: "tab:orange", 3: "tab:green"}
    width = 0.27
    top = max(c["instructions_per_tick"] for c in data["configs"])
    for axes in sorted({c["axes"] for c in data["configs"]}):
        rows = [c for c in data["configs"] if c["axes"] == axes]
        xs = [scenes.index(c["scene_name"]) + (axes - 2) * width for c in rows]
        ys = [c["instructions_per_tick"] for c in rows]
        bars = ax.bar(xs, ys, width * 0.92, color=colors.get(axes, "0.5"),
                      label=f"{axes}-axis device")
        ax.bar_label(bars, labels=[f"{y:,.0f}" for y in ys], padding=1.5, fontsize="x-small",
                     rotation=90)
    ax.set_xticks(range(len(scenes)))
    ax.set_xticklabels(scenes)
    ax.set_xlim(-0.6, len(scenes) - 0.4)
    ax.set_ylim(0, top * 1.3)
    ax.set_ylabel("instructions per servo tick")
    ax.set_xlabel("scene (config/scenes/), the handle held in it by a stiff grasp")
    ax.grid(True, axis="y", alpha=0.45)
    ax.set_axisbelow(True)
    ax.legend(loc="upper left", ncols=3)
    caption = (f"Instructions per tick (callgrind Ir, servo thread): hapticd --lockstep, "
               f"(Ir({data['long_s']:g} s) - Ir({data['short_s']:g} s)) / ticks, sim pen "
               f"display, stiff grasp, {data['rate_hz']:g} Hz\n"
               f"{run_info.caption_machine(data['machine'])}; "
               f"{run_info.caption_build(data['build'])}; {data['tools']['valgrind']}")
    chart_style.save(figure, chart_path, caption)
    plt.close(figure)


def main(argv=None):
    parser = argparse.ArgumentParser(
        description="Instructions per servo tick of hapticd under callgrind, per shipped scene "
                    "and device axis count (docs/benchmarks.md).")
    parser.add_argument("--hapticd", default=DEFAULT_HAPTICD,
                        help="the daemon binary (default build/release/bin/hapticd)")
    parser.add_argument("--quick", action="store_true",
                        help="count 10,000 ticks a configuration instead of 60,000")
    parser.add_argument("--json", help="write the data file here")
    parser.add_argument("--chart", help="draw the bar chart here (.png, .svg or .pdf)")
    args = parser.parse_args(argv)
    try:
        if args.chart:
            sys.path.insert(0, os.path.join(SOURCE_DIR, "tools", "plot"))
            import chart_style
            chart_style.image_format(args.chart)  # refuse a bad extension before measuring
        data = measure(args.hapticd, SOURCE_DIR, args.quick)
    except BenchError as error:
        print(f"tick_instructions.py: {error}", file=sys.stderr)
        return error.exit_code
    except ValueError as error:
        print(f"tick_instructions.py: --chart {error}", file=sys.stderr)
        return 2
    print_table(data)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as out:
            json.dump(data, out, indent=1)
            out.write("\n")
    if args.chart:
        draw(data, args.chart)
    return 0


if __name__ == "__main__":
    sys.exit(main())
