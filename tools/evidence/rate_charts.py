"""The rate chart (rate.py's data): the stiffest stable stiffness against the servo rate,
measured and predicted, above what each rate costs the host."""

import chart_style

MODEL_STYLE = {"paper": ("tab:blue", "--"), "encoder": ("tab:red", "-."),
               "passive": ("tab:green", ":")}


def measured(ax, rows, key, low_key, high_key, color, marker, label, shift):
    """The bisected limit: a marker at the stiffest stable value, a bar up to the first
    unstable one (the bisection's bracket); drawn at `shift` times the rate so that two
    series at one rate both show."""
    rates, lows, highs = [], [], []
    for row in rows:
        block = row[key]
        if block[low_key] is None:
            continue
        rates.append(row["rate_hz"] * shift)
        lows.append(block[low_key])
        highs.append(block[high_key])
    ax.errorbar(rates, lows, yerr=[[0.0] * len(lows), [h - lo for h, lo in zip(highs, lows)]],
                color=color, marker=marker, markersize=7, linestyle="none", capsize=3,
                label=label)


def draw_rate(plt, data, figure):
    rows = data["rows"]
    ax, ax_cpu = figure.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1.2]})
    rates = [r["rate_hz"] for r in rows]
    for model, (color, style) in MODEL_STYLE.items():
        ax.plot(rates, [r["predicted_n_per_m"][model] for r in rows], color=color,
                linestyle=style, linewidth=1.6, label=f"{model} model's k_c limit")
    measured(ax, rows, "coupling", "stiffest_stable_n_per_m", "first_unstable_n_per_m",
             "black", "o", "measured: the stiffest stable coupling k_c (a "
                            f"{data['stiff_wall_n_per_m']:.0e} N/m wall)", 0.96)
    measured(ax, rows, "no_coupling", "stiffest_stable_wall_n_per_m",
             "first_unstable_wall_n_per_m", "tab:orange", "s",
             "measured: the stiffest stable wall without a coupling", 1.04)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylabel("stiffness (N/m)")
    chart_style.grid(ax)
    ax_cpu.plot(rates, [100.0 * r["host_cpu_fraction"] for r in rows], color="0.2",
                marker="o", label="the tick's compute (median) times the rate")
    ax_cpu.set_yscale("log")
    ax_cpu.set_ylabel("host CPU (%)")
    ax_cpu.set_xlabel("servo rate 1/T (Hz)")
    chart_style.grid(ax_cpu)
    return [ax, ax_cpu]


def draw(data, out_dir, caption):
    written = []
    what = (f"The servo rate against the stiffest stable stiffness, {data['operator']}, "
            "measured (bisected, bars to the first unstable run) and predicted, and the host "
            "CPU each rate costs")
    for extension in ("png", "pdf"):
        plt, _ = chart_style.pyplot()
        figure = chart_style.new_figure(plt, (7.0, 5.6))
        axes = draw_rate(plt, data, figure)
        chart_style.save(figure, str(out_dir / f"rate.{extension}"), f"{what}. {caption}",
                         legend_from=axes)
        plt.close(figure)
        written.append(f"rate.{extension}")
    return written
