#!/usr/bin/python3
"""Largest coupling stiffness each stability model allows, for a few coupling dampings.

paper, encoder and passive come from `haptic-tune size`. The exact model sizes no further
than the passive proof (docs/stability-models.md); its column is the operator its search
finds unstable 3 % past that limit (`haptic-tune size --model exact`'s witness), the growth per
tick, or "none found". Prints a Markdown table for docs/stability-models.md.

usage: tools/scripts/compare_models.py HAPTIC_TUNE --mass M --damping B --rate HZ
           [--delay S] [--velocity-filter HZ] BC...
"""
import argparse
import json
import subprocess


def run(tool, args):
    return subprocess.run([tool] + args, capture_output=True, text=True)


def sized(tool, device, model, b_c):
    r = run(tool, ["size"] + device + ["--model", model, "--coupling-damping", str(b_c),
                                       "--json", "--no-exact-check"])
    return json.loads(r.stdout)["stiffness"] if r.returncode == 0 else None


def exact_witness(tool, device, b_c):
    r = run(tool, ["size"] + device + ["--model", "exact", "--coupling-damping", str(b_c),
                                       "--json"])
    if r.returncode != 0:
        return "infeasible"
    w = json.loads(r.stdout)["witness"]
    if not w["found"]:
        return "none found"
    s = w["search"]
    return f"\\|z\\| - 1 = {s['worst_spectral_radius'] - 1:.2g}, {s['worst_operator'].split(' (')[0]}"


def main():
    p = argparse.ArgumentParser()
    p.add_argument("tool")
    p.add_argument("--mass", required=True)
    p.add_argument("--damping", required=True)
    p.add_argument("--rate", required=True)
    p.add_argument("--delay", default="0")
    p.add_argument("--velocity-filter", default="0", help="the damper's velocity filter, Hz")
    p.add_argument("dampings", nargs="+", type=float)
    a = p.parse_args()
    device = ["--mass", a.mass, "--damping", a.damping, "--rate", a.rate, "--delay", a.delay,
              "--velocity-filter", a.velocity_filter]
    print("| b_c (N s/m) | paper k_c (N/m) | encoder k_c (N/m) | passive k_c (N/m) | "
          "exact: unstable at 1.03 x passive |")
    print("|---|---|---|---|---|")
    for b_c in a.dampings:
        found = {m: sized(a.tool, device, m, b_c) for m in ("paper", "encoder", "passive")}
        exact = exact_witness(a.tool, device, b_c)
        fmt = lambda v: "infeasible" if v is None else f"{v:.0f}"
        print(f"| {b_c:g} | {fmt(found['paper'])} | {fmt(found['encoder'])} | "
              f"{fmt(found['passive'])} | {exact} |", flush=True)


if __name__ == "__main__":
    main()
