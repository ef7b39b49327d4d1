#!/usr/bin/python3
"""The largest stable coupling stiffness against b_c and the loop delay, under each
assumption a verdict can rest on (docs/stability-models.md, "Operator classes" and "Scenes"):

  unconditional  every passive operator, every passive environment  (size --model passive)
  scene          every passive operator, the scene's objects        (size --scene FILE)
  class          the operator class, every passive environment      (size --model exact
                                                                      --operator-class FILE)
  class + scene  the operator class, the scene's objects

Each point is one `haptic-tune size --json` run. Writes a PNG and prints the table.

    /usr/bin/python3 tools/scripts/limits_chart.py build/release/bin/haptic-tune \\
        --mass 0.1 --damping 2 --rate 1000 \\
        --operator-class config/operators/pen-grip.toml \\
        --scene config/scenes/god-object-sphere.toml \\
        --out docs/charts/limits-by-assumption.png
"""
import argparse
import json
import pathlib
import subprocess
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "plot"))
import chart_style  # noqa: E402


def size(tool, args, damping, delay, extra):
    command = [tool, "size", "--mass", str(args.mass), "--damping", str(args.damping),
               "--rate", str(args.rate), "--coupling-damping", str(damping),
               "--delay", str(delay), "--json"] + extra
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode not in (0, 1):
        sys.exit(f"{' '.join(command)}: exit {result.returncode}: {result.stderr}")
    return json.loads(result.stdout)["stiffness"]


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("haptic_tune")
    parser.add_argument("--mass", type=float, required=True)
    parser.add_argument("--damping", type=float, required=True)
    parser.add_argument("--rate", type=float, required=True)
    parser.add_argument("--operator-class", required=True)
    parser.add_argument("--scene", required=True)
    parser.add_argument("--dampings", default="0,0.25,0.5,0.75,1,1.25,1.5")
    parser.add_argument("--delays", default="0,0.5,1", help="in periods")
    parser.add_argument("--out", required=True, help="the chart: .png, .svg or .pdf")
    args = parser.parse_args()
    plt, _ = chart_style.pyplot()
    dampings = [float(v) for v in args.dampings.split(",")]
    delays = [float(v) for v in args.delays.split(",")]
    assumptions = {
        "unconditional (every operator, every environment)": [],
        "scene (every operator, its objects)": ["--scene", args.scene],
        "class (its hands, every environment)":
            ["--model", "exact", "--operator-class", args.operator_class],
        "class + scene": ["--model", "exact", "--operator-class", args.operator_class,
                          "--scene", args.scene],
    }
    figure = chart_style.new_figure(plt, (3.3 * len(delays), 4.2))
    axes = figure.subplots(1, len(delays), sharey=True, squeeze=False)[0]
    for axis, delay_periods in zip(axes, delays):
        delay_s = delay_periods / args.rate
        print(f"delay {delay_periods:g} periods ({delay_s * 1e3:g} ms)")
        print("  b_c (N s/m) | " + " | ".join(assumptions))
        table = {name: [] for name in assumptions}
        for damping in dampings:
            row = []
            for name, extra in assumptions.items():
                k = size(args.haptic_tune, args, damping, delay_s, extra)
                table[name].append(k)
                row.append(f"{k:.0f}")
            print(f"  {damping:g} | " + " | ".join(row))
        for name, values in table.items():
            axis.plot(dampings, values, marker="o", label=name)
        axis.set_title(f"loop delay {delay_periods:g} period(s)")
        axis.set_xlabel("coupling damping b_c (N s/m)")
        chart_style.grid(axis)
    axes[0].set_ylabel("largest stable k_c (N/m)")
    # One legend (the same lines in every panel) below the axes.
    for axis in axes[1:]:
        for line in axis.get_lines():
            line.set_label("_" + line.get_label())
    chart_style.save(figure, args.out,
                     f"Limits by assumption, haptic-tune size: m = {args.mass:g} kg, "
                     f"b = {args.damping:g} N s/m, {args.rate:g} Hz; class {args.operator_class}, "
                     f"scene {args.scene}", legend_from=list(axes))


if __name__ == "__main__":
    main()
