"""The timing benches' numbers (timing.py's data) that docs/RESULTS.md quotes."""

from fact_text import run_info, us


def wake_table(data):
    wake = data["timing"]["wake_latency"]
    lines = ["| load | program | p50 | p99 | p99.9 | max (not meaningful on a VM) |",
             "|---|---|---|---|---|---|"]
    for load, block in wake["loads"].items():
        for program, numbers in block["programs"].items():
            q = numbers["wake_latency_us"]
            lines.append(f"| {load} | {program} | {us(q['p50'])} | {us(q['p99'])} | "
                         f"{us(q['p999'])} | {us(q['max'])} |")
        r = block["ratios_hapticd_over_cyclictest"]
        cells = " | ".join("n/a" if r[k] is None else f"{r[k]:.2f}" for k in ("p50", "p99", "p999"))
        lines.append(f"| {load} | ratio hapticd / cyclictest | {cells} | |")
    return "\n".join(lines)


def instructions_table(data):
    lines = ["| scene | device axes | instructions per tick |", "|---|---|---|"]
    for c in data["timing"]["instructions"]["configs"]:
        lines.append(f"| {c['scene_name']} | {c['axes']} | {c['instructions_per_tick']:,.0f} |")
    return "\n".join(lines)


def servo_tick_table(data):
    lines = ["| scene (BM_ServoTick) | CPU time per tick (median) |", "|---|---|"]
    for scene, t in data["timing"]["servo_tick"].items():
        lines.append(f"| {scene} | {t['cpu_time_ns']:,.0f} ns |")
    return "\n".join(lines)


def timing_run(data):
    wake = data["timing"]["wake_latency"]
    load = wake["machine"]["load_average_1_5_15"]
    return (f"{run_info(data, 'timing')}; wake-ups {wake['seconds']:g} s per program and load "
            f"in {wake['rounds']} turns, on CPU {wake['cpu']}; the load average at the start "
            f"{load[0]:.2f}")


FACTS = {
    "timing.run": timing_run,
    "timing.wake_table": wake_table,
    "timing.instructions_table": instructions_table,
    "timing.servo_tick_table": servo_tick_table,
}
