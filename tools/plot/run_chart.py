"""The chart of a recorded run (haptic-tune plot-run), from the numbers haptic-tune read
and computed:

  run: "axis", "position", "tool" (optional), "force", "coupling_energy" (optional, with
       "coupling_stiffness_n_per_m"), "observer_energy" (optional): each
       {"t_s": [...], "value": [...]}; "faults": [{"t_s", "fault"}], "marks": {flag: [t_s]},
       "judgement": {"from_s", "window_s", "growth_per_s", "verdict"}

Panels: position (the handle x_d and the tool x_e, mm), force (N) with the ticks the safety
layer acted on, energy (mJ): the coupling's spring and the passivity observer. Faults are
red lines through every panel.
"""

MARK_STYLE = {
    "saturated": ("tab:orange", "force saturated"),
    "overspeed": ("tab:purple", "velocity limit"),
    "passivity_control": ("tab:green", "passivity controller"),
    "overrun": ("tab:brown", "overrun"),
    "no_sample": ("0.4", "no sample"),
}


def series(np, chart, key):
    data = chart.get(key)
    if data is None:
        return None
    return np.asarray(data["t_s"], dtype=float), np.asarray(data["value"], dtype=float)


def draw_run(plt, np, chart, figure):
    energies = [k for k in ("coupling_energy", "observer_energy") if chart.get(k) is not None]
    rows = 3 if energies else 2
    panels = figure.subplots(rows, 1, sharex=True,
                             gridspec_kw={"height_ratios": [2, 1.3, 1.3][:rows]})
    ax_x, ax_f = panels[0], panels[1]
    axis = chart["axis"]

    t, x = series(np, chart, "position")
    ax_x.plot(t, 1e3 * x, color="black", linewidth=1.0, label=f"handle x{axis} (x_d)")
    tool = series(np, chart, "tool")
    if tool is not None:
        ax_x.plot(tool[0], 1e3 * tool[1], color="tab:blue", linewidth=0.9, alpha=0.8,
                  label=f"tool xe{axis} (x_e)")
    judgement = chart.get("judgement") or {}
    if "from_s" in judgement:
        ax_x.axvspan(t[0], judgement["from_s"], color="0.9", zorder=0,
                     label="not judged (start-up)")
    ax_x.set_ylabel("position (mm)")

    t, f = series(np, chart, "force")
    ax_f.plot(t, f, color="tab:red", linewidth=0.9, label=f"force f{axis} on the handle")
    low, high = (float(f.min()), float(f.max())) if f.size else (0.0, 1.0)
    for index, (flag, times) in enumerate((chart.get("marks") or {}).items()):
        color, label = MARK_STYLE.get(flag, ("0.3", flag))
        level = high + (index + 1) * 0.06 * max(high - low, 1e-9)
        ax_f.plot(times, [level] * len(times), linestyle="none", marker="|", markersize=6,
                  color=color, label=f"{label} ({len(times)} ticks shown)")
    ax_f.set_ylabel("force (N)")

    if energies:
        ax_e = panels[2]
        coupling = series(np, chart, "coupling_energy")
        if coupling is not None:
            ax_e.plot(coupling[0], 1e3 * coupling[1], color="tab:blue", linewidth=0.9,
                      label="coupling spring \u00bd k_c (x_d \u2212 x_e)\u00b2, k_c = "
                            f"{chart['coupling_stiffness_n_per_m']:.4g} N/m")
        observer = series(np, chart, "observer_energy")
        if observer is not None:
            ax_e.plot(observer[0], 1e3 * observer[1], color="tab:green", linewidth=0.9,
                      label="passivity observer (energy into the handle)")
        ax_e.axhline(0.0, color="black", linewidth=0.6)
        ax_e.set_ylabel("energy (mJ)")

    for fault in chart.get("faults", []):
        for ax in panels:
            ax.axvline(fault["t_s"], color="tab:red", linewidth=1.2, linestyle="--")
        ax_x.annotate(fault["fault"], xy=(fault["t_s"], 1.0), xycoords=("data", "axes fraction"),
                      rotation=90, ha="right", va="top", fontsize="x-small", color="tab:red")
    for ax in panels:
        ax.grid(True, alpha=0.35)
    panels[-1].set_xlabel("time t (s)")
    return list(panels)


DRAW = {"run": draw_run}
