#!/usr/bin/python3
"""Largest coupling stiffness each stability model allows, for a few coupling dampings.

paper, encoder and passive come from `haptic-tune size`; exact is a bisection on
`haptic-tune check --model exact` (the closed-loop eigenvalues over the sweep and the
adversaries synthesised for each design). Prints a Markdown table for
docs/stability-models.md.

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


def exact_limit(tool, device, b_c, hi):
    lo = 0.0
    while hi - lo > 1e-4 * hi:
        mid = 0.5 * (lo + hi)
        r = run(tool, ["check"] + device + ["--stiffness", str(mid), "--coupling-damping",
                                            str(b_c), "--model", "exact"])
        if r.returncode == 0:
            lo = mid
        elif r.returncode == 1:
            hi = mid
        else:
            raise SystemExit(r.stderr)
    return lo


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
    print("| b_c (N s/m) | paper k_c (N/m) | encoder k_c (N/m) | passive k_c (N/m) | exact k_c (N/m) |")
    print("|---|---|---|---|---|")
    for b_c in a.dampings:
        found = {m: sized(a.tool, device, m, b_c) for m in ("paper", "encoder", "passive")}
        hi = 2.0 * max(v for v in list(found.values()) + [1.0] if v is not None)
        exact = exact_limit(a.tool, device, b_c, hi)
        fmt = lambda v: "infeasible" if v is None else f"{v:.0f}"
        print(f"| {b_c:g} | {fmt(found['paper'])} | {fmt(found['encoder'])} | "
              f"{fmt(found['passive'])} | {exact:.0f} |", flush=True)


if __name__ == "__main__":
    main()
