"""The admittance display (27)-(43): its stability map against the exact sampled-data loop
(bench/tune/admittance_map), beside the coupling mass each model sizes. hapticd drives
impedance-type devices and its simulated device has no force sensor or velocity loop, so this
map holds the admittance display against its exact model, not the daemon in the loop."""

import json

import chart_style
import maps_charts

MODEL_STYLE = {"encoder_mass_kg": ("tab:red", "(37), encoder hold"),
               "paper_mass_kg": ("tab:blue", "(37), the paper's hold (13)"),
               "exact_limit_kg": ("tab:olive", "the exact loop's lightest stable m_c")}


def run(ctx):
    out = ctx.scratch("admittance") / "admittance.json"
    args = [ctx.program("admittance_map"), "--out", str(out)]
    if ctx.quick:
        args.append("--quick")
    ctx.run(args, "admittance_map", timeout_s=1800)
    table = json.loads(out.read_text())
    device = table["device"]
    table["device"] = (f"the arm of docs/stability-models.md, m = {device['mass_kg']:g} kg, "
                       f"b = {device['damping_n_s_per_m']:g} N s/m, {device['rate_hz']:g} Hz, "
                       "an admittance display with a force sensor and a PI velocity loop "
                       "(k_i = 0), a pure-mass coupling (32)")
    table["rate_hz"] = device["rate_hz"]
    return table


def as_verdict(point, rate_hz):
    """A grid point in the maps' form: growth per second from |z| per tick."""
    growth = (point["worst_spectral_radius"] - 1.0) * rate_hz
    return {"stable": point["stable"], "growth_per_s": growth, "rise_growth_per_s": 0.0}


def draw(data, out_dir, caption):
    what = ("The admittance display's exact sampled-data loop against the coupling mass m_c, "
            "for each PI gain k_p (colour: the worst case's growth), and the m_c each model "
            "sizes; crosses off the rows: (37)'s best (m_c, b_c) pair")
    written = []
    for extension in ("png", "pdf"):
        plt, _ = chart_style.pyplot()
        figure = chart_style.new_figure(plt, (7.0, 4.6))
        ax = figure.subplots()
        rows = data["rows"]
        xs = [p["coupling_mass_kg"] for p in rows[0]["grid"]]
        colors = maps_charts.verdict_grid(
            plt, ax, xs, [[as_verdict(p, data["rate_hz"]) for p in r["grid"]] for r in rows],
            [f"k_p = {r['kp_n_s_per_m']:g} N s/m" for r in rows],
            judge="the exact loop's eigenvalues over its sweep")
        for key, (color, label) in MODEL_STYLE.items():
            ax.plot([r[key] for r in rows], range(len(rows)), color=color, marker="|",
                    markersize=16, markeredgewidth=2.0, linewidth=1.2, label=label)
        for i, r in enumerate(rows):
            pair = r["encoder_pair"]
            ax.plot([pair["coupling_mass_kg"]], [i + 0.3], marker="X", markersize=9,
                    color="tab:red" if not pair["verdict"]["stable"] else "tab:green",
                    linestyle="none")
        ax.plot([], [], "X", color="tab:red", label="(37)'s best pair (with its b_c), unstable "
                                                    "in the exact loop")
        ax.set_xlabel("coupling mass m_c (kg), a pure mass")
        maps_charts.colorbar(figure, ax, colors)
        chart_style.save(figure, str(out_dir / f"admittance-map.{extension}"),
                         f"{what}. {caption}", legend_from=[ax])
        plt.close(figure)
        written.append(f"admittance-map.{extension}")
    return written
