#!/usr/bin/python3
"""Wake-up latency of hapticd's servo loop against cyclictest (Debian rt-tests), back to back
on the same CPU at the same SCHED_FIFO priority, on the idle machine and under
`stress-ng --cpu N` (N = the machine's CPUs), in one run (docs/benchmarks.md, "Wake-up
latency"; docs/architecture.md §2.11).

Both programs sleep to an absolute 1 ms deadline with clock_nanosleep(CLOCK_MONOTONIC,
TIMER_ABSTIME) in a SCHED_FIFO 80 thread pinned to CPU `--cpu`, with mlockall and
/dev/cpu_dma_latency = 0, and measure wake - deadline:

  cyclictest -m -p80 -i1000 -l N -q --affinity=CPU -h 10000 --histfile=F
      1 us buckets up to 10 ms; later wake-ups are its overflows.
  hapticd --config C --duration S --no-status --log L --summary J
      C is config/hapticd.toml (the embedded default: sim device, demo wall, real time) with
      [servo] priority = 80, cpu = CPU (the servo thread pinned, hapticd's other threads kept
      off that CPU, so the log writer does not share it) and realtime = "enforce" (no run
      without SCHED_FIFO, mlockall, the affinity and cpu_dma_latency). The histogram is made
      from the per-tick `wake_latency_us` column of the log L (on /dev/shm), in the same
      1 us buckets (floor, as cyclictest truncates); the summary's own percentiles (a
      log-linear histogram, within 1.6 %) are kept beside it as a cross-check. The log is
      not free: on this VM hapticd with --log had 21 overruns in 22 runs of 3 s where as
      many runs without it, taken in turn, had 3 (docs/benchmarks.md): its tail here is
      that of a logging hapticd, an upper bound for the embedded default's.

Turns: each program's S seconds of a load are split into R turns (--rounds, default 5), the
two programs taking turns and the first of a turn alternating, so that the machine's drift
over the minute (on this VM the median wake-up of one program moved from 19 to 34 us between
3 s runs minutes apart) hits both alike; the turns' histograms are summed. The stressed
load's stress-ng runs through all its turns.

Both histograms give the percentiles the same way: quantile q is the smallest bucket whose
cumulative count reaches ceil(q n), n including the overflows (None when that is an
overflow). Worst cases on a VM that the host stalls are not meaningful: the data file and
the table carry `max` for completeness only; read the medians, p99, p99.9 and the ratios.

Usage (as root: SCHED_FIFO and mlockall need it):
  bench/jitter.py [--seconds S] [--hapticd PATH] [--loads idle,stress] [--rounds R]
                  [--cpu N] [--json FILE] [--chart FILE.png|.svg|.pdf]

--cpu defaults to the last CPU. Run time: about 4 S + 3 s (10 s: 45 s).
As a module (the evidence driver): measure(hapticd, seconds, loads[, cpu, rounds]) -> dict,
draw(data, path).

Data file (--json), "schema": "hapticd-jitter/1":
  schema, date_utc, seconds (per program and load), rounds (turns), period_us (1000),
  priority (80), cpu,
  machine      {cpu_model, cpus, kernel, load_average_1_5_15 (at the start)},
  build        {hapticd (path), version, build_type, source_commit},
  tools        {cyclictest, stress-ng, hapticd: their version lines},
  loads        {"idle" | "stress": {
      load       "none" or the stress-ng command,
      programs   {"cyclictest" | "hapticd": {
          command          [argv],
          wake_ups         number of wake-ups measured,
          wake_latency_us  {p50, p99, p999, max} (us; a percentile is null when it falls
                           in the overflow; max is not meaningful on this VM),
          histogram        {bin_width_us: 1, overflow_above_us: 10000,
                            bins_us: [lower edge of each non-empty bin], counts: [...],
                            overflows: wake-ups later than overflow_above_us},
          hapticd only:    summary_wake_latency_us [{p50, p99, p999, max} of each turn:
                           hapticd's own], overruns, missed_periods (summed over the
                           turns), realtime (the last summary's)}},
      ratios_hapticd_over_cyclictest {p50, p99, p999} (null when undefined)}}

Exit status: 0 done; 1 a program failed (its exit status and message are printed); 2 bad
usage, a missing tool (named), or not root.
"""

import argparse
import contextlib
import csv
import datetime
import json
import math
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

BENCH_DIR = os.path.dirname(os.path.abspath(__file__))
SOURCE_DIR = os.path.dirname(BENCH_DIR)
sys.path.insert(0, BENCH_DIR)
import run_info  # noqa: E402

PERIOD_US = 1000
PRIORITY = 80
HIST_LIMIT_US = 10000  # cyclictest's histogram range; later wake-ups are overflows
PERCENTILES = (("p50", 0.50), ("p99", 0.99), ("p999", 0.999))
LOADS = ("idle", "stress")
STRESS_SETTLE_S = 1.0  # stress-ng's workers running before the first measurement
DEFAULT_ROUNDS = 5
MIN_ROUND_S = 0.1
DEFAULT_HAPTICD = os.path.join(SOURCE_DIR, "build", "release", "bin", "hapticd")


class BenchError(Exception):
    """A failure to report in one line; `exit_code` 2 for usage and set-up, 1 for a run."""

    def __init__(self, message, exit_code=1):
        super().__init__(message)
        self.exit_code = exit_code


def stress_command():
    return ["stress-ng", "--cpu", str(os.cpu_count() or 1), "--quiet"]


def check_setup(hapticd, loads):
    for load in loads:
        if load not in LOADS:
            raise BenchError(f"unknown load {load!r} (allowed: {', '.join(LOADS)})", 2)
    tools = {"cyclictest": "rt-tests"}
    if "stress" in loads:
        tools["stress-ng"] = "stress-ng"
    missing = [f"{tool} (Debian package {package})" for tool, package in tools.items()
               if shutil.which(tool) is None]
    if missing:
        raise BenchError(f"not found on PATH: {', '.join(missing)}; scripts/install-deps "
                         "installs them", 2)
    if not (os.path.isfile(hapticd) and os.access(hapticd, os.X_OK)):
        raise BenchError(f"hapticd not found or not executable: {hapticd} (--hapticd PATH)", 2)
    if os.geteuid() != 0:
        raise BenchError(f"must run as root (euid {os.geteuid()}): cyclictest -p{PRIORITY} and "
                         f"hapticd's [servo] realtime = \"enforce\" need SCHED_FIFO and mlockall",
                         2)


def run(command, what, **kwargs):
    done = subprocess.run(command, capture_output=True, text=True, **kwargs)
    if done.returncode != 0:
        tail = "\n".join((done.stderr or done.stdout).strip().splitlines()[-8:])
        raise BenchError(f"{what} exited with status {done.returncode}: "
                         f"{' '.join(command)}\n{tail}")
    return done


def quantile_bucket(counts, overflows, q):
    """Smallest bucket whose cumulative count reaches ceil(q n); None in the overflow."""
    n = sum(counts) + overflows
    if n == 0:
        return None
    need = math.ceil(q * n)
    cumulative = 0
    for bucket, count in enumerate(counts):
        cumulative += count
        if cumulative >= need:
            return float(bucket)
    return None


class Tally:
    """One program's wake-ups over the rounds of one load: 1 us buckets, overflows, max."""

    def __init__(self):
        self.counts = [0] * HIST_LIMIT_US
        self.overflows = 0
        self.max_us = None

    def add_bucket(self, bucket_us, count):
        if bucket_us < HIST_LIMIT_US:
            self.counts[bucket_us] += count
        else:
            self.overflows += count

    def add_latency_us(self, latency_us):
        self.add_bucket(max(0, int(math.floor(latency_us))), 1)
        self.note_max_us(latency_us)

    def note_max_us(self, max_us):
        self.max_us = max_us if self.max_us is None else max(self.max_us, max_us)

    def record(self):
        bins = [b for b, c in enumerate(self.counts) if c]
        latency = {name: quantile_bucket(self.counts, self.overflows, q)
                   for name, q in PERCENTILES}
        latency["max"] = self.max_us
        return {
            "wake_ups": sum(self.counts) + self.overflows,
            "wake_latency_us": latency,
            "histogram": {"bin_width_us": 1, "overflow_above_us": HIST_LIMIT_US,
                          "bins_us": bins, "counts": [self.counts[b] for b in bins],
                          "overflows": self.overflows},
        }


def run_cyclictest(seconds, cpu, work, tally):
    """One cyclictest run into `tally`; returns its command."""
    histfile = os.path.join(work, "cyclictest.hist")
    command = ["cyclictest", "-m", f"-p{PRIORITY}", f"-i{PERIOD_US}",
               f"-l{int(round(seconds * 1e6 / PERIOD_US))}", "-q", f"--affinity={cpu}",
               f"-h{HIST_LIMIT_US}", f"--histfile={histfile}"]
    run(command, "cyclictest")
    with open(histfile, encoding="utf-8") as text:
        for line in text:
            fields = line.split()
            if fields and fields[0].isdigit() and len(fields) >= 2:
                tally.add_bucket(int(fields[0]), int(fields[1]))
            elif line.startswith("# Histogram Overflows:"):
                tally.add_bucket(HIST_LIMIT_US, int(fields[-1]))
            elif line.startswith("# Max Latencies:"):
                tally.note_max_us(float(fields[-1]))
    return command


def servo_config_text(cpu):
    """config/hapticd.toml with [servo] realtime, priority and cpu set, paths made absolute."""
    path = os.path.join(SOURCE_DIR, "config", "hapticd.toml")
    with open(path, encoding="utf-8") as text:
        lines = text.read().splitlines()
    overrides = {"servo": {"realtime": '"enforce"', "priority": str(PRIORITY), "cpu": str(cpu)},
                 "scene": {"file": json.dumps(os.path.join(SOURCE_DIR, "config", "scenes",
                                                           "demo-wall.toml"))}}
    out, table, seen = [], None, set()
    for line in lines:
        stripped = line.strip()
        if stripped.startswith("["):
            table = stripped[1:stripped.index("]")].strip("[] ")
            out.append(line)
            if not stripped.startswith("[[") and table in overrides:
                seen.add(table)
                out.extend(f"{key} = {value}" for key, value in overrides[table].items())
            continue
        key = stripped.split("=", 1)[0].strip() if "=" in stripped else None
        if key and not stripped.startswith("#") and key in overrides.get(table, {}):
            continue
        out.append(line)
    if seen != set(overrides):
        raise BenchError(f"{path}: no [{'], ['.join(sorted(set(overrides) - seen))}] table to set")
    return "\n".join(out) + "\n"


def run_hapticd(hapticd, seconds, cpu, work, tally):
    """One hapticd run into `tally` (from its log); returns its command and summary."""
    config, log, summary = (os.path.join(work, name) for name in
                            ("hapticd.toml", "hapticd.csv", "hapticd.json"))
    with open(config, "w", encoding="utf-8") as text:
        text.write(servo_config_text(cpu))
    command = [hapticd, "--config", config, "--duration", f"{seconds:g}", "--no-status",
               "--log", log, "--summary", summary]
    run(command, "hapticd")
    with open(summary, encoding="utf-8") as text:
        report = json.load(text)
    realtime = report.get("realtime", {})
    if not (realtime.get("sched_fifo") and realtime.get("cpu") == cpu):
        raise BenchError(f"hapticd ran without SCHED_FIFO on cpu {cpu}: realtime {realtime}")
    with open(log, encoding="utf-8", newline="") as text:
        rows = csv.reader(line for line in text if not line.startswith("#"))
        column = next(rows).index("wake_latency_us")
        for row in rows:
            tally.add_latency_us(float(row[column]))
    return command, report


class Stress:
    """stress-ng on every CPU for the duration of a `with` block (its own process group)."""

    def __enter__(self):
        self.process = subprocess.Popen(stress_command(), stdout=subprocess.DEVNULL,
                                        stderr=subprocess.PIPE, start_new_session=True)
        time.sleep(STRESS_SETTLE_S)
        self.check()
        return self

    def check(self):
        if self.process.poll() is not None:
            message = self.process.stderr.read().decode(errors="replace").strip()
            raise BenchError(f"stress-ng exited early with status {self.process.returncode}: "
                             f"{message}")

    def __exit__(self, *exc):
        if self.process.poll() is None:
            os.killpg(self.process.pid, signal.SIGTERM)
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(self.process.pid, signal.SIGKILL)
            self.process.wait()
        self.process.stderr.close()
        return False


def ratios(programs):
    out = {}
    for name, _ in PERCENTILES:
        ours = programs["hapticd"]["wake_latency_us"][name]
        theirs = programs["cyclictest"]["wake_latency_us"][name]
        out[name] = round(ours / theirs, 3) if ours is not None and theirs else None
    return out


def scratch_dir():
    """tmpfs when there is one: hapticd's log is written every 100 ms, and no block I/O."""
    return "/dev/shm" if os.path.isdir("/dev/shm") and os.access("/dev/shm", os.W_OK) else None


def measure_load(hapticd, seconds, rounds, cpu, load):
    """`rounds` rounds of seconds / rounds each, cyclictest and hapticd in turn (the first
    to run alternating), so that a drift of the machine in between hits both alike."""
    tallies = {"cyclictest": Tally(), "hapticd": Tally()}
    commands, summaries = {}, []
    round_s = seconds / rounds
    with tempfile.TemporaryDirectory(prefix="jitter-", dir=scratch_dir()) as work, \
            (Stress() if load == "stress" else contextlib.nullcontext()) as stress:
        for round_index in range(rounds):
            order = ["cyclictest", "hapticd"][::1 if round_index % 2 == 0 else -1]
            for program in order:
                if program == "cyclictest":
                    commands[program] = run_cyclictest(round_s, cpu, work, tallies[program])
                else:
                    commands[program], report = run_hapticd(hapticd, round_s, cpu, work,
                                                            tallies[program])
                    summaries.append(report)
            if stress:
                stress.check()
    programs = {program: dict(tally.record(), command=commands[program])
                for program, tally in tallies.items()}
    programs["hapticd"].update({
        "summary_wake_latency_us": [report.get("wake_latency_us") for report in summaries],
        "overruns": sum(report.get("overruns", 0) for report in summaries),
        "missed_periods": sum(report.get("missed_periods", 0) for report in summaries),
        "realtime": summaries[-1].get("realtime"),
    })
    return {"load": " ".join(stress_command()) if load == "stress" else "none",
            "programs": programs, "ratios_hapticd_over_cyclictest": ratios(programs)}


def measure(hapticd=DEFAULT_HAPTICD, seconds=10.0, loads=LOADS, cpu=None, rounds=DEFAULT_ROUNDS):
    """Runs both programs for `seconds` each (in `rounds` turns) under every load of `loads`
    ("idle", "stress") and returns the data file's dict. Raises BenchError."""
    loads = list(loads)
    check_setup(hapticd, loads)
    if not (isinstance(rounds, int) and rounds >= 1):
        raise BenchError(f"--rounds {rounds} must be a whole number >= 1", 2)
    if not seconds / rounds >= MIN_ROUND_S:
        raise BenchError(f"--seconds {seconds:g} over --rounds {rounds} is "
                         f"{seconds / rounds:g} s a round: allowed >= {MIN_ROUND_S} s", 2)
    cpu = (os.cpu_count() or 1) - 1 if cpu is None else cpu
    if cpu not in os.sched_getaffinity(0):
        raise BenchError(f"--cpu {cpu} is not one this process may use "
                         f"({sorted(os.sched_getaffinity(0))})", 2)
    data = {
        "schema": "hapticd-jitter/1",
        "date_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "seconds": seconds, "rounds": rounds, "period_us": PERIOD_US, "priority": PRIORITY,
        "cpu": cpu,
        "machine": run_info.machine(),
        "build": run_info.build(hapticd),
        "tools": {"cyclictest": run_info.tool_version(["cyclictest", "--help"]),
                  "stress-ng": run_info.tool_version(["stress-ng", "--version"])
                  if "stress" in loads else None,
                  "hapticd": run_info.tool_version([hapticd, "--version"])},
        "loads": {},
    }
    for load in loads:
        data["loads"][load] = measure_load(hapticd, seconds, rounds, cpu, load)
    return data


def format_us(value):
    return f"> {HIST_LIMIT_US}" if value is None else f"{value:.0f}"


def print_table(data, out=sys.stdout):
    machine = data["machine"]
    print(f"jitter.py: {data['date_utc']}, {machine['cpu_model']}, {machine['cpus']} cpus, "
          f"kernel {machine['kernel']}, load {' '.join(map(str, machine['load_average_1_5_15']))}"
          f"; {data['seconds']:g} s each in {data['rounds']} turns, SCHED_FIFO {data['priority']} "
          f"on cpu {data['cpu']}",
          file=out)
    for load, result in data["loads"].items():
        c, h = result["programs"]["cyclictest"], result["programs"]["hapticd"]
        r = result["ratios_hapticd_over_cyclictest"]
        print(f"\n{load} (load: {result['load']})", file=out)
        print(f"{'wake-up latency':24} {'cyclictest':>11} {'hapticd':>11} {'ratio':>7}", file=out)
        print(f"{'wake-ups':24} {c['wake_ups']:>11} {h['wake_ups']:>11}", file=out)
        for name, label in (("p50", "p50 (us)"), ("p99", "p99 (us)"), ("p999", "p99.9 (us)")):
            ratio = "-" if r[name] is None else f"{r[name]:.2f}"
            print(f"{label:24} {format_us(c['wake_latency_us'][name]):>11} "
                  f"{format_us(h['wake_latency_us'][name]):>11} {ratio:>7}", file=out)
        print(f"{'max (us, not meaningful)':24} {c['wake_latency_us']['max']:>11.0f} "
              f"{h['wake_latency_us']['max']:>11.0f}", file=out)
        own = ", ".join(f"{s['p50']:.1f}/{s['p99']:.1f}/{s['p999']:.1f}"
                        for s in h["summary_wake_latency_us"])
        print(f"hapticd's own summaries, p50/p99/p99.9 us per turn: {own}; overruns "
              f"{h['overruns']} ({h['missed_periods']} periods missed)", file=out)


def draw(data, chart_path):
    """Histogram chart of `data` (measure()'s dict): one panel per load, both programs,
    log-spaced bins (20 per decade) on a log latency axis, log count axis."""
    sys.path.insert(0, os.path.join(SOURCE_DIR, "tools", "plot"))
    import chart_style
    plt, np = chart_style.pyplot(font_size_pt=9)
    figure = chart_style.new_figure(plt, (7.0, 3.7))
    loads = list(data["loads"])
    axes = figure.subplots(1, len(loads), sharey=True, squeeze=False)[0]
    edges = np.logspace(0, math.log10(HIST_LIMIT_US), 4 * 20 + 1)
    styles = {"cyclictest": ("tab:blue", "-"), "hapticd": ("tab:red", "--")}
    top = 1
    for ax, load in zip(axes, loads):
        result = data["loads"][load]
        for program, (color, line) in styles.items():
            record = result["programs"][program]
            histogram = record["histogram"]
            # A 1 us bucket [b, b + 1) goes to the log bin holding b + 0.5 (bucket 0 to the first).
            centres = np.maximum(np.asarray(histogram["bins_us"], dtype=float) + 0.5, 1.0)
            counts, _ = np.histogram(centres, bins=edges, weights=histogram["counts"])
            top = max(top, counts.max(initial=0))
            latency = record["wake_latency_us"]
            label = (f"{program}: p50 {format_us(latency['p50'])}, "
                     f"p99 {format_us(latency['p99'])}, p99.9 {format_us(latency['p999'])} us")
            if histogram["overflows"]:
                label += f", {histogram['overflows']} > {HIST_LIMIT_US // 1000} ms"
            ax.stairs(np.where(counts > 0, counts, 0.5), edges, color=color, linestyle=line,
                      linewidth=1.3, baseline=0.5, label=label)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(1, HIST_LIMIT_US)
        ax.set_title("idle" if load == "idle" else result["load"].replace(" --quiet", ""))
        ax.set_xlabel("wake-up latency (us)")
        chart_style.grid(ax)
        ax.legend(loc="upper right", fontsize="x-small")
    axes[0].set_ylabel("wake-ups per bin (20 bins per decade)")
    axes[0].set_ylim(0.7, top * 30)  # empty bins (drawn at 0.5) stay below the axis
    machine = data["machine"]
    caption = (f"Wake-up latency (wake - absolute {data['period_us']} us deadline), cyclictest "
               f"and hapticd in turn, {data['seconds']:g} s each in {data['rounds']} turns, "
               f"SCHED_FIFO {data['priority']} on CPU {data['cpu']}\n"
               f"{run_info.caption_machine(machine)}; {run_info.caption_build(data['build'])}; "
               f"{data['tools']['cyclictest']}")
    chart_style.save(figure, chart_path, caption)
    plt.close(figure)


def main(argv=None):
    parser = argparse.ArgumentParser(
        description="Wake-up latency of hapticd against cyclictest, back to back on one CPU, "
                    "idle and under stress-ng (docs/benchmarks.md).")
    parser.add_argument("--seconds", type=float, default=10.0,
                        help="length of each program's run per load (default 10: 10,000 wake-ups)")
    parser.add_argument("--hapticd", default=DEFAULT_HAPTICD,
                        help="the daemon binary (default build/release/bin/hapticd)")
    parser.add_argument("--loads", default="idle,stress",
                        help="comma-separated: idle, stress (default both)")
    parser.add_argument("--rounds", type=int, default=DEFAULT_ROUNDS,
                        help="turns each program's time is split into, the two programs "
                             f"alternating (default {DEFAULT_ROUNDS})")
    parser.add_argument("--cpu", type=int, default=None,
                        help="the CPU both programs are pinned to (default the last one)")
    parser.add_argument("--json", help="write the data file here")
    parser.add_argument("--chart", help="draw the histogram chart here (.png, .svg or .pdf)")
    args = parser.parse_args(argv)
    try:
        if args.chart:
            sys.path.insert(0, os.path.join(SOURCE_DIR, "tools", "plot"))
            import chart_style
            chart_style.image_format(args.chart)  # refuse a bad extension before measuring
        loads = [load.strip() for load in args.loads.split(",") if load.strip()]
        data = measure(args.hapticd, args.seconds, loads, args.cpu, args.rounds)
    except BenchError as error:
        print(f"jitter.py: {error}", file=sys.stderr)
        return error.exit_code
    except ValueError as error:
        print(f"jitter.py: --chart {error}", file=sys.stderr)
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
