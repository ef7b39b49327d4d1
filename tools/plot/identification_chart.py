#!/usr/bin/python3
"""Draws the speed-against-accuracy charts of haptic-tune identify from the tables that
bench/tune/identify_sweep writes (docs/identification.md has the commands):

  identification_chart.py TABLE.json OUT.png|OUT.svg

TABLE.json is one of
  "identification-sweep":    error of m, b and F_c and solve time against log length, one
                             line per excitation amplitude (identify_sweep);
  "identification-segments": spread of the estimates and calibration of the standard errors
                             against the shooting-segment length (identify_sweep --segments).

The C++ computes every number; this script only draws them (matplotlib, Agg backend).
Exit codes: 0 drawn; 2 bad input; 3 matplotlib cannot be imported.
"""

import json
import math
import sys

EXIT_BAD_INPUT = 2
EXIT_NO_MATPLOTLIB = 3
COLORS = ["tab:purple", "tab:red", "tab:orange", "tab:green", "tab:blue", "tab:brown"]


def fail(message, code=EXIT_BAD_INPUT):
    print(f"identification_chart.py: {message}", file=sys.stderr)
    sys.exit(code)


def value(v):
    return math.nan if v is None else float(v)


def percent(v):
    return 100.0 * abs(value(v))


def draw_sweep(plt, table, out_path):
    device = table["device"]
    lengths = table["lengths_s"]
    amplitudes = table["amplitudes_rms_n"]
    seeds = table["seeds"]
    cells = {(c["length_s"], c["amplitude_rms_n"]): c for c in table["cells"]}
    fig, axes = plt.subplots(2, 2, figsize=(11, 8.5), constrained_layout=True)
    panels = [
        (axes[0][0], "median_abs_mass_error", "|m error| (%)", 2.0, "requirement 2 %"),
        (axes[0][1], "median_abs_damping_error", "|b error| (%)", 2.0, "requirement 2 %"),
        (axes[1][0], "median_abs_coulomb_error", "|F_c error| (%)", 10.0, "requirement 10 %"),
    ]
    for ax, key, label, limit, limit_label in panels:
        for i, amplitude in enumerate(amplitudes):
            color = COLORS[i % len(COLORS)]
            xs, ys, refused_x, refused_y = [], [], [], []
            for length in lengths:
                cell = cells.get((length, amplitude))
                if cell is None or cell[key] is None:
                    continue
                y = percent(cell[key])
                xs.append(length)
                ys.append(y)
                if 2 * cell["refused_by_default"] > seeds:  # most seeds refused
                    refused_x.append(length)
                    refused_y.append(y)
            ax.plot(xs, ys, "o-", color=color, markersize=4,
                    label=f"{amplitude:g} N RMS ({amplitude / device['coulomb']:g} F_c)")
            ax.plot(refused_x, refused_y, "o", markersize=9, markerfacecolor="none",
                    markeredgecolor=color, markeredgewidth=1.2)
        ax.axhline(limit, color="0.3", linestyle="--", linewidth=1.0)
        ax.annotate(limit_label, xy=(lengths[0], limit), xytext=(2, 3), textcoords="offset points",
                    fontsize=8, color="0.3")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("log length (s)")
        ax.set_ylabel(label + f", median of {seeds} seeds")
        ax.grid(True, which="major", alpha=0.45)
        ax.grid(True, which="minor", alpha=0.15)
    axes[0][0].legend(fontsize=8, title="excitation (multisine)", title_fontsize=8)

    ax = axes[1][1]
    for i, amplitude in enumerate(amplitudes):
        color = COLORS[i % len(COLORS)]
        xs, cpu, wall = [], [], []
        for length in lengths:
            cell = cells.get((length, amplitude))
            if cell is None or cell["median_cpu_time_s"] is None:
                continue
            xs.append(length)
            cpu.append(1e3 * value(cell["median_cpu_time_s"]))
            wall.append(1e3 * value(cell["median_solve_time_s"]))
        ax.plot(xs, cpu, "o-", color=color, markersize=4, label=f"{amplitude:g} N RMS")
    ax.axhline(1000.0, color="0.3", linestyle="--", linewidth=1.0)
    ax.annotate("1 s", xy=(lengths[0], 1000.0), xytext=(2, 3), textcoords="offset points",
                fontsize=8, color="0.3")
    rate = device["rate_hz"]
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(f"log length (s) at {rate:g} Hz")
    ax.set_ylabel(f"solve time (ms, thread CPU), median of {seeds} seeds")
    ax.grid(True, which="major", alpha=0.45)
    ax.grid(True, which="minor", alpha=0.15)
    fig.suptitle(
        "haptic-tune identify: error and solve time against log length and excitation\n"
        f"simulated device m = {device['mass']:g} kg, b = {device['damping']:g} N s/m, "
        f"F_c = {device['coulomb']:g} N, F_0 = {device['offset']:g} N; "
        f"{1e6 / device['counts_per_meter']:g} µm counts, force noise "
        f"{device['force_noise_n']:g} N; hollow rings: refused by the default options",
        fontsize=10)
    fig.savefig(out_path)


def draw_segments(plt, table, out_path):
    rows = table["rows"]
    noises = sorted({r["force_noise_n"] for r in rows})
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5), constrained_layout=True)
    styles = {"mass": "o-", "damping": "s--", "coulomb": "^:"}
    for i, noise in enumerate(noises):
        color = COLORS[(i + 2) % len(COLORS)]
        subset = sorted((r for r in rows if r["force_noise_n"] == noise),
                        key=lambda r: r["segment_s"])
        xs = [r["segment_s"] for r in subset]
        for name, style in styles.items():
            left.plot(xs, [percent(r[f"rms_{name}_error"]) for r in subset], style, color=color,
                      markersize=4, label=f"{name}, noise {noise:g} N")
            right.plot(xs, [value(r[f"rms_z_{name}"]) for r in subset], style, color=color,
                       markersize=4, label=f"{name}, noise {noise:g} N")
    for ax in (left, right):
        ax.set_xscale("log")
        ax.set_xlabel("shooting segment length (s)")
        ax.axvline(0.02, color="0.3", linestyle=":", linewidth=1.0)
        ax.grid(True, which="major", alpha=0.45)
        ax.grid(True, which="minor", alpha=0.15)
    left.set_yscale("log")
    left.set_ylabel(f"RMS error over {table['seeds']} seeds (%)")
    left.set_title("spread of the estimates", fontsize=10)
    right.set_yscale("log")
    right.axhline(1.0, color="0.3", linestyle="--", linewidth=1.0)
    right.set_ylabel("RMS of (estimate - truth) / standard error")
    right.set_title("calibration of the standard errors (1 = right)", fontsize=10)
    right.legend(fontsize=7, ncol=1)
    fig.suptitle(f"haptic-tune identify: shooting-segment length ({table['duration_s']:g} s logs; "
                 "dotted line: the default, 0.02 s)", fontsize=10)
    fig.savefig(out_path)


def main():
    if len(sys.argv) != 3:
        fail("usage: identification_chart.py TABLE.json OUT.png|OUT.svg")
    table_path, out_path = sys.argv[1], sys.argv[2]
    if not out_path.lower().endswith((".png", ".svg")):
        fail(f"{out_path}: the chart must be a .png or .svg file")
    try:
        with open(table_path, encoding="utf-8") as f:
            table = json.load(f)
    except (OSError, ValueError) as e:
        fail(f"cannot read {table_path}: {e}")
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as e:
        fail(f"cannot import matplotlib ({e}); install python3-matplotlib", EXIT_NO_MATPLOTLIB)
    kind = table.get("kind") if isinstance(table, dict) else None
    try:
        if kind == "identification-sweep":
            draw_sweep(plt, table, out_path)
        elif kind == "identification-segments":
            draw_segments(plt, table, out_path)
        else:
            fail(f"{table_path}: unknown table kind {kind!r}")
    except (KeyError, TypeError, ValueError) as e:
        fail(f"{table_path}: malformed table ({e!r})")


if __name__ == "__main__":
    main()
