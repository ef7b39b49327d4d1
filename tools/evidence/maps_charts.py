"""The stability maps' charts (maps.py's data): each point a measured verdict, its colour the
fitted growth of the oscillation (blue dies out, red grows), a cross where the trajectory
judge found it unstable; each model's prediction on the same axes."""

import chart_style

GROWTH_SCALE_PER_S = 10.0   # the colour scale's ends, 1/s
DESIGN_COLORS = {"paper": "tab:blue", "encoder": "tab:red", "passive": "tab:green",
                 "exact": "tab:olive", "class": "tab:purple", "scene": "tab:brown"}


def growth_shown(verdict):
    """The growth a point is coloured by: the rise's when it rose (an unstable loop grows
    from the floor to its limit cycle, which flattens a fit over every window)."""
    if not verdict["stable"] and verdict["rise_growth_per_s"] > 0:
        return verdict["rise_growth_per_s"]
    return verdict["growth_per_s"]


def verdict_grid(plt, ax, xs, rows, row_labels, judge="the trajectory judge"):
    """Markers at (x, row) for rows[i] = verdicts along xs (`judge` says what decided them);
    returns the colour mapping."""
    import matplotlib
    norm = matplotlib.colors.TwoSlopeNorm(vmin=-GROWTH_SCALE_PER_S, vcenter=0.0,
                                          vmax=GROWTH_SCALE_PER_S)
    cmap = plt.get_cmap("coolwarm")
    for i, verdicts in enumerate(rows):
        for x, verdict in zip(xs, verdicts):
            color = cmap(norm(max(-GROWTH_SCALE_PER_S,
                                  min(GROWTH_SCALE_PER_S, growth_shown(verdict)))))
            marker = "o" if verdict["stable"] else "X"
            ax.plot([x], [i], marker=marker, markersize=8 if verdict["stable"] else 9,
                    markerfacecolor=color, markeredgecolor="0.25", markeredgewidth=0.5,
                    linestyle="none")
    ax.plot([], [], "o", color="0.6", label=f"stable ({judge})")
    ax.plot([], [], "X", color="0.6", label=f"unstable: it grows ({judge})")
    ax.set_yticks(range(len(row_labels)))
    ax.set_yticklabels(row_labels)
    ax.set_ylim(len(row_labels) - 0.5, -0.5)
    ax.set_xscale("log")
    chart_style.grid(ax)
    colors = matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap)
    return colors


def colorbar(figure, ax, colors):
    bar = figure.colorbar(colors, ax=ax, pad=0.01, fraction=0.04)
    bar.set_label("growth (1/s)")


def draw_operators(plt, data, figure, key="operators"):
    block = data[key]
    ax = figure.subplots()
    colors = verdict_grid(plt, ax, block["stiffness_n_per_m"], [r["verdicts"] for r in block["rows"]],
                          [r["label"] + (" *" if r["in_pen_grip_class"] else "")
                           for r in block["rows"]])
    for design in block["designs"]:
        color = DESIGN_COLORS.get(design["design"], "0.3")
        # exact sizes the passive proof itself: dotted and wider, so that both show
        exact = design["design"] == "exact"
        ax.axvline(design["stiffness_n_per_m"], color=color, linewidth=2.6 if exact else 1.6,
                   linestyle=":" if exact else "--",
                   label=f"{design['label']}: k_c = {design['stiffness_n_per_m']:.4g} N/m "
                         f"(holds for {design['holds_for']})")
    ax.set_xlabel("coupling stiffness k_c (N/m)")
    colorbar(figure, ax, colors)
    return [ax]


def what_operators(data, key="operators"):
    block = data[key]
    delay = block.get("delay_periods", 0.0)
    delayed = f", {delay:g} period of loop delay" if delay > 0 else ""
    return ("Stability of the virtual coupling against the operator, measured "
            f"(b_c = {block['coupling_damping_n_s_per_m']:g} N s/m, a "
            f"{block['wall_n_per_m']:.0e} N/m wall{delayed}) and each model's k_c (* in the "
            "pen-grip class)")


def draw_operators_delayed(plt, data, figure):
    return draw_operators(plt, data, figure, "operators_delayed")


def what_operators_delayed(data):
    return what_operators(data, "operators_delayed")


def draw_walls(plt, data, figure):
    block = data["walls"]
    ax = figure.subplots()
    colors = verdict_grid(plt, ax, block["walls_n_per_m"], [r["verdicts"] for r in block["rows"]],
                          [r["label"] for r in block["rows"]])
    ax.axvline(block["colgate_bound_n_per_m"], color="black", linestyle=":", linewidth=1.4,
               label=f"2b/T = {block['colgate_bound_n_per_m']:.4g} N/m: the stiffest wall the "
                     "handle holds without a coupling (Colgate and Schenkel)")
    ax.set_xlabel("wall stiffness K (N/m)")
    colorbar(figure, ax, colors)
    return [ax]


def what_walls(data):
    return ("The stiffest stable wall, without and with the virtual coupling "
            f"({data['walls']['operator']})")


def draw_delay(plt, data, figure):
    block = data["delay"]
    ax = figure.subplots()
    rows = block["rows"]
    colors = verdict_grid(plt, ax, block["stiffness_n_per_m"], [r["verdicts"] for r in rows],
                          [f"{r['delay_periods']:g} T" for r in rows])
    for model in ("paper", "encoder", "passive"):
        ax.plot([r["predicted_n_per_m"][model] for r in rows], range(len(rows)),
                color=DESIGN_COLORS[model], marker="|", markersize=14, linewidth=1.4,
                label=f"{model} model's limit with the delay")
    ax.set_xlabel("coupling stiffness k_c (N/m)")
    ax.set_ylabel("loop delay beyond the hold")
    colorbar(figure, ax, colors)
    return [ax]


def what_delay(data):
    block = data["delay"]
    return ("Stability against the loop delay, whole and fractional periods, measured "
            f"({block['operator']}, b_c = 0, a {block['wall_n_per_m']:.0e} N/m wall) and "
            "each model's limit")


CHARTS = [("stability-map-operators", draw_operators, what_operators, (7.5, 6.0)),
          ("stability-map-operators-delayed", draw_operators_delayed, what_operators_delayed,
           (7.5, 6.0)),
          ("stability-map-walls", draw_walls, what_walls, (7.5, 4.2)),
          ("stability-map-delay", draw_delay, what_delay, (7.5, 5.2))]


def draw(data, out_dir, caption):
    """Writes each chart as PNG (for the docs) and PDF; returns their names. The caption
    line says what the chart shows, then `caption` (the run, the device, the machine)."""
    written = []
    for name, draw_one, what, size_in in CHARTS:
        for extension in ("png", "pdf"):
            plt, _ = chart_style.pyplot()
            figure = chart_style.new_figure(plt, size_in)
            axes = draw_one(plt, data, figure)
            chart_style.save(figure, str(out_dir / f"{name}.{extension}"),
                             f"{what(data)}. {caption}", legend_from=axes)
            plt.close(figure)
            written.append(f"{name}.{extension}")
    return written
