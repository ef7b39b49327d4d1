"""Timing: the servo's wake-up latency against cyclictest's, idle and under stress-ng
(bench/jitter.py), the instructions a tick costs per shipped scene and axis count
(bench/tick_instructions.py, callgrind: independent of the machine's noise), and the tick's
compute per scene (bench/daemon/daemon_bench.cpp, google-benchmark, the median of its
repetitions). The benches are the ones docs/benchmarks.md runs by hand; this section runs
them on the build and keeps their data."""

import importlib.util
import pathlib

from context import EvidenceError

BENCH_DIR = pathlib.Path(__file__).resolve().parents[2] / "bench"


def bench_module(name):
    """bench/NAME.py as a module (bench/ is not a package)."""
    path = BENCH_DIR / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"bench_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def servo_tick_benchmarks(ctx):
    """BM_ServoTick per scene: the median CPU time of its repetitions, ns."""
    args = [ctx.program("daemon_bench"), "--benchmark_filter=BM_ServoTick",
            "--benchmark_format=json"]
    if ctx.quick:
        args += ["--benchmark_min_time=0.01"]
    else:
        args += ["--benchmark_repetitions=5", "--benchmark_report_aggregates_only=true"]
    report = ctx.run_json(args, "daemon_bench")
    ticks = {}
    for entry in report["benchmarks"]:
        if ctx.quick or entry.get("aggregate_name") == "median":
            scene = entry["run_name"].split("/", 1)[1]
            ticks[scene] = {"cpu_time_ns": entry["cpu_time"], "real_time_ns": entry["real_time"]}
    return ticks


def run(ctx):
    jitter = bench_module("jitter")
    instructions = bench_module("tick_instructions")
    hapticd = ctx.program("hapticd")
    try:
        wake = jitter.measure(hapticd=hapticd, seconds=1.0 if ctx.quick else 10.0,
                              loads=jitter.LOADS, rounds=1 if ctx.quick else 5)
        # Quick: the demo wall on 1, 2 and 3 axes (what the quick test asserts); valgrind is
        # slow enough that every scene would double the quick run.
        counted = instructions.measure(hapticd=hapticd, source_dir=str(ctx.source_dir),
                                       quick=ctx.quick,
                                       scene_names=["demo-wall"] if ctx.quick else None)
    except (jitter.BenchError, instructions.BenchError) as error:
        raise EvidenceError(f"timing: {error}") from error
    return {"device": "the embedded default (sim pen display, demo wall) and the shipped scenes",
            "wake_latency": wake, "instructions": counted,
            "servo_tick": servo_tick_benchmarks(ctx)}


def draw(data, out_dir, caption):
    """The benches' own charts (their captions name the run, the machine and the build)."""
    del caption
    jitter = bench_module("jitter")
    instructions = bench_module("tick_instructions")
    written = []
    for extension in ("png", "pdf"):
        jitter.draw(data["wake_latency"], str(out_dir / f"wake-latency.{extension}"))
        instructions.draw(data["instructions"], str(out_dir / f"tick-instructions.{extension}"))
        written += [f"wake-latency.{extension}", f"tick-instructions.{extension}"]
    return written
