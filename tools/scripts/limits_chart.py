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
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


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
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
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
    figure, axes = plt.subplots(1, len(delays), figsize=(6 * len(delays), 4.5), sharey=True)
    if len(delays) == 1:
        axes = [axes]
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
        axis.grid(True, alpha=0.3)
    axes[0].set_ylabel("largest stable k_c (N/m)")
    axes[0].legend(fontsize=8)
    figure.suptitle(f"Limits by assumption: m = {args.mass:g} kg, b = {args.damping:g} N s/m, "
                    f"{args.rate:g} Hz; class {args.operator_class}, scene {args.scene}",
                    fontsize=9)
    figure.tight_layout()
    figure.savefig(args.out, dpi=110)


if __name__ == "__main__":
    main()
