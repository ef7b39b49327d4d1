"""Tuner and exact-model effort against bound error and solve time (bench/tune/effort_sweep:
the check of (21) against its grid's density, and the exact model's operator sweep against
its size, with and without the adversaries synthesised for the design)."""

import json

import chart_style

MARGIN_FLOOR = 1e-17   # a margin error of 0 drawn on a log axis


def run(ctx):
    out = ctx.scratch("effort") / "effort.json"
    args = [ctx.program("effort_sweep"), "--out", str(out)]
    if ctx.quick:
        args.append("--quick")
    ctx.run(args, "effort_sweep")
    table = json.loads(out.read_text())
    device = table["device"]
    table["device"] = (f"the pen display m = {device['mass_kg']:g} kg, "
                       f"b = {device['damping_n_s_per_m']:g} N s/m, {device['rate_hz']:g} Hz")
    return table


def draw(data, out_dir, caption):
    what = ("The check of (21) against its grid's density (the worst point refined), and the "
            "exact model's operator sweep against its size")
    written = []
    for extension in ("png", "pdf"):
        plt, _ = chart_style.pyplot()
        figure = chart_style.new_figure(plt, (7.0, 6.4))
        (ax_grid, ax_grid_time), (ax_sweep, ax_sweep_time) = figure.subplots(2, 2)
        for study in data["grid"]:
            rows = study["rows"]
            reference = rows[-1]["worst_margin"]
            points = [r["grid_points"] for r in rows]
            ax_grid.plot(points, [max(abs(r["worst_margin"] - reference), MARGIN_FLOOR)
                                  for r in rows], "o-", label=f"(21): {study['design']}")
            ax_grid_time.plot(points, [1e3 * r["seconds"] for r in rows], "o-")
        for ax in (ax_grid, ax_grid_time):
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("grid points up to Nyquist")
            chart_style.grid(ax)
        ax_grid.set_ylabel("|worst margin - densest grid's|")
        ax_grid_time.set_ylabel("check time (ms)")
        for study, color in zip(data["sweep"], ("tab:red", "tab:purple")):
            rows = [r for r in study["rows"] if r["sweep"].startswith("default sweep, one")]
            operators = [r["operators"] for r in rows]
            line, = ax_sweep.plot(operators, [r["worst_spectral_radius"] - 1.0 for r in rows],
                                  "s-", color=color, label=f"exact model: {study['design']}")
            for r in rows:
                if not r["stable"]:
                    ax_sweep.plot([r["operators"]], [r["worst_spectral_radius"] - 1.0], "X",
                                  color=line.get_color(), markersize=10)
            full = study["rows"][-1]
            ax_sweep.plot([full["operators"] * 1.12], [full["worst_spectral_radius"] - 1.0], "*",
                          color=line.get_color(), markersize=12)
            ax_sweep_time.plot(operators, [r["seconds"] for r in rows], "o-",
                               color=line.get_color())
        ax_sweep.plot([], [], "X", color="0.4", label="found unstable")
        ax_sweep.plot([], [], "*", color="0.4", label="with the synthesised adversaries")
        ax_sweep.axhline(0.0, color="black", linewidth=0.8)
        ax_sweep.set_yscale("symlog", linthresh=1e-6)
        ax_sweep.set_ylabel("worst |z| - 1 per tick")
        ax_sweep_time.set_yscale("log")
        ax_sweep_time.set_ylabel("check time (s)")
        for ax in (ax_sweep, ax_sweep_time):
            ax.set_xscale("log")
            ax.set_xlabel("operators checked")
            chart_style.grid(ax)
        chart_style.save(figure, str(out_dir / f"effort.{extension}"), f"{what}. {caption}",
                         legend_from=[ax_grid, ax_sweep])
        plt.close(figure)
        written.append(f"effort.{extension}")
    return written
