"""The tuner's effort numbers (effort.py's data) that docs/RESULTS.md quotes."""

from fact_text import run_info


def effort_grid_enough(data):
    """The sparsest grid whose worst margin matches the densest's within 1e-12, for every
    design, and what the default (4096) costs against it."""
    studies = data["effort"]["grid"]
    points = sorted({r["grid_points"] for s in studies for r in s["rows"]})
    for p in points:
        if all(abs(next(r for r in s["rows"] if r["grid_points"] == p)["worst_margin"]
                   - s["rows"][-1]["worst_margin"]) < 1e-12 for s in studies):
            return str(p)
    return "none of them"


def effort_grid_time(data, points):
    """The slowest design's check time on a grid of `points` (None: the default grid)."""
    if points is None:
        times = [s["default_grid_seconds"] for s in data["effort"]["grid"]]
    else:
        times = [r["seconds"] for s in data["effort"]["grid"] for r in s["rows"]
                 if r["grid_points"] == points]
    return f"{1e3 * max(times):.3f} ms" if times else "not run"


def effort_grid_sparsest_time(data):
    return effort_grid_time(data, int(effort_grid_enough(data)))


def effort_densest(data):
    return f"{max(r['grid_points'] for s in data['effort']['grid'] for r in s['rows']):,}"


def effort_designs(data):
    return "; ".join(s["design"] for s in data["effort"]["grid"])


def effort_thinned(data):
    rows = [r["sweep"] for r in data["effort"]["sweep"][0]["rows"] if ", one operator in " in r["sweep"]]
    strides = [r.rsplit(" ", 1)[1] for r in rows if not r.endswith(" 1")]
    return ", ".join(f"1 in {s}" for s in strides)


def effort_sweep_missed(data):
    """The sweeps of the default operators that called the encoder model's k_c stable."""
    study = data["effort"]["sweep"][0]
    missed = [r for r in study["rows"] if r["stable"]]
    found = [r for r in study["rows"] if not r["stable"]]
    worst = max(r["worst_spectral_radius"] for r in found) if found else None
    whole = study["rows"][-1]["operators"]
    text = ", ".join(f"{r['operators']} operators" for r in missed) or "no sweep"
    return (f"{text} of {whole} called it stable; the sweeps that kept the lossless grips tuned to "
            f"Nyquist found it growing by |z| - 1 = {worst - 1.0:.2g} per tick"
            if worst else text)


def effort_full_time(data):
    study = data["effort"]["sweep"][0]
    full = study["rows"][-1]
    return f"{full['seconds']:.2f} s for {full['cases']:,} cases"


def tolerance_table(data):
    lines = ["| rate | the passive model's k_c | the exact model's worst \\|z\\| - 1 | "
             "the same case at 0.99 k_c | eigenvalues in its cluster | the exact model's verdict |", "|---|---|---|---|---|---|"]
    for r in data["effort"]["rates"]:
        over = r["worst_excess_per_tick"] > r["tolerance_per_tick"]
        verdict = ("REFUSED" if not r["stable"] else
                   "marginal: the excess does not move with the gains" if over else "accepted")
        lines.append(f"| {r['rate_hz']:,.0f} Hz | {r['stiffness_n_per_m']:,.0f} N/m | "
                     f"{r['worst_excess_per_tick']:.3g} | "
                     f"{r['excess_at_99_percent_per_tick']:.3g} | {r['cluster_eigenvalues']} | "
                     f"{verdict} |")
    return "\n".join(lines)


def tolerance_refused(data):
    """The rates whose excess the fixed tolerance alone would refuse."""
    refused = [r for r in data["effort"]["rates"]
               if r["worst_excess_per_tick"] > r["tolerance_per_tick"]]
    return ("no rate" if not refused else
            ", ".join(f"{r['rate_hz']:,.0f} Hz" for r in refused))


def verdict_now(data):
    rows = data["effort"]["rates"]
    accepted = sum(1 for r in rows if r["stable"])
    return f"{accepted} of {len(rows)}"


def tolerance_moved(data):
    """The largest relative change of the worst excess when k_c drops by 1 %."""
    change = max(abs(r["excess_at_99_percent_per_tick"] - r["worst_excess_per_tick"]) /
                 abs(r["worst_excess_per_tick"]) for r in data["effort"]["rates"])
    return f"{100.0 * change:.2g} %"


FACTS = {
    "effort.run": lambda d: run_info(d, "effort"),
    "effort.device": lambda d: d["effort"]["device"],
    "effort.grid_enough": effort_grid_enough,
    "effort.grid_time_sparsest": effort_grid_sparsest_time,
    "effort.grid_time_default": lambda d: effort_grid_time(d, None),
    "effort.densest": effort_densest,
    "effort.designs": effort_designs,
    "effort.thinned": effort_thinned,
    "effort.sweep_missed": effort_sweep_missed,
    "effort.full_time": effort_full_time,
    "effort.tolerance_table": tolerance_table,
    "effort.tolerance_refused": tolerance_refused,
    "effort.tolerance_moved": tolerance_moved,
    "effort.verdict_now": verdict_now,
}
