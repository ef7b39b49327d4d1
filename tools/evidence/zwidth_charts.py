"""The Z-width chart (zwidth.py's data): |Z| against frequency from theory, (24) and (25) per
model, with the impedance the hand felt in HIL, without and with a period of loop delay
(top: the whole band; middle: around the contact resonance, where the models' hold terms
part); bottom, the static stiffness the hand was held with against the coupling's, beside
the series k_c K/(k_c + K) of the coupling and the wall."""

import chart_style

COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:red")
MODEL_STYLE = {"passive": ("-", 1.5), "encoder": ("--", 1.1), "paper": (":", 1.5)}
Y_LIMITS = (0.1, 1e4)        # N s/m: the paper's (25) goes to infinity at Nyquist
ZOOM_HZ = (7.0, 40.0)        # the contact resonances sqrt(k_c/m)/(2 pi) of the couplings
ZOOM_Y = (0.1, 40.0)
ZOOM_TICKS_HZ = (8, 10, 15, 20, 30, 40)
DELAY_MARKERS = ("o", "s")   # no delay, one period


def sci(value):
    """1e7 for 1e+07."""
    mantissa, exponent = f"{value:.0e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def delay_words(row):
    delay = row["delay_periods"]
    if delay == 0:
        return "no loop delay"
    return f"loop delay {delay:g} period{'s' if delay != 1 else ''} ({row['delay_s'] * 1e3:g} ms)"


def impedance_panel(ax, data, row, x_limits, y_limits):
    grid = row["theory_frequency_hz"]
    ax.plot(grid, row["theory_zmin_n_s_per_m"]["passive"], color="0.25", linewidth=1.5,
            label="(24) |Z_min| = |m j\u03c9 + b| (encoder and passive models)")
    for color, block in zip(COLORS, row["contact"]):
        for model in data["models"]:
            style, width = MODEL_STYLE[model]
            ax.plot(grid, block["theory_zmax_n_s_per_m"][model], color=color, linestyle=style,
                    linewidth=width)
        points = sorted(zip(block["frequency_hz"] + [block["dip"]["frequency_hz"]],
                            block["felt_magnitude_n_s_per_m"] +
                            [block["dip"]["felt_magnitude_n_s_per_m"]]))
        ax.plot([p[0] for p in points], [p[1] for p in points], color=color, marker="o",
                markersize=5, linestyle="none",
                label=f"HIL in contact, k_c = {block['coupling_stiffness_n_per_m']:,.0f} N/m "
                      "(its (25) in its colour)")
    free = row["free"]
    ax.plot(free["frequency_hz"], free["felt_magnitude_n_s_per_m"], color="black", marker="s",
            markerfacecolor="white", markersize=5, linestyle="none",
            label="HIL in free motion")
    for model in data["models"]:
        style, width = MODEL_STYLE[model]
        ax.plot([], [], color="0.25", linestyle=style, linewidth=width,
                label=f"(25) |Z_max| with the {model} model's hold term")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(*x_limits)
    ax.set_ylim(*y_limits)
    chart_style.grid(ax)


def stiffness_panel(ax, data):
    couplings = data["couplings_n_per_m"]
    low, high = 0.8 * couplings[0], 1.1 * couplings[-1]
    span = [low + (high - low) * i / 50.0 for i in range(51)]
    walls = ((data["rigid_wall_n_per_m"], "contact", "tab:purple"),
             (data["soft_wall_n_per_m"], "soft_wall", "tab:brown"))
    for wall, key, color in walls:
        ax.plot(span, [k * wall / (k + wall) for k in span], color=color, linewidth=1.4,
                label=f"k_c K/(k_c + K), wall K = {wall:,.0f} N/m")
        for marker, row in zip(DELAY_MARKERS, data["delays"]):
            blocks = row[key]
            ax.plot([b["coupling_stiffness_n_per_m"] for b in blocks],
                    [b["static_stiffness_n_per_m"] for b in blocks], color=color, marker=marker,
                    linestyle="none", markersize=9 if marker == "s" else 5,
                    markerfacecolor="none" if marker == "s" else color)
    for marker, row in zip(DELAY_MARKERS, data["delays"]):
        ax.plot([], [], color="0.25", marker=marker, linestyle="none",
                markersize=9 if marker == "s" else 5,
                markerfacecolor="none" if marker == "s" else "0.25",
                label=f"HIL, {delay_words(row)}: -\u0394f/\u0394x between two rests")
    ax.set_xlabel("coupling stiffness k_c (N/m)")
    ax.set_ylabel("felt static\nstiffness (N/m)")
    chart_style.grid(ax)


def draw_zwidth(plt, data, figure):
    from matplotlib import ticker
    layout = figure.add_gridspec(3, 2, height_ratios=[3, 2.2, 1.6])
    whole = [figure.add_subplot(layout[0, 0])]
    whole.append(figure.add_subplot(layout[0, 1], sharey=whole[0]))
    zoom = [figure.add_subplot(layout[1, 0])]
    zoom.append(figure.add_subplot(layout[1, 1], sharey=zoom[0]))
    for column, row in enumerate(data["delays"]):
        grid = row["theory_frequency_hz"]
        impedance_panel(whole[column], data, row, (grid[0], grid[-1]), Y_LIMITS)
        impedance_panel(zoom[column], data, row, ZOOM_HZ, ZOOM_Y)
        whole[column].set_title(delay_words(row))
        zoom[column].set_xlabel("frequency (Hz)")
        zoom[column].xaxis.set_major_locator(ticker.FixedLocator(ZOOM_TICKS_HZ))
        zoom[column].xaxis.set_major_formatter(ticker.FormatStrFormatter("%g"))
        zoom[column].xaxis.set_minor_formatter(ticker.NullFormatter())
        zoom[column].set_title("around the contact resonances", fontsize="small")
    for ax in (whole[1], zoom[1]):
        ax.tick_params(labelleft=False)
        for line in ax.get_lines():
            line.set_label("_" + line.get_label())
    for ax in zoom:
        for line in ax.get_lines():
            line.set_label("_" + line.get_label())
    whole[0].set_ylabel("|Z| (N s/m)")
    zoom[0].set_ylabel("|Z| (N s/m)")
    bottom = figure.add_subplot(layout[2, :])
    stiffness_panel(bottom, data)
    return [whole[0], bottom]


def draw(data, out_dir, caption):
    written = []
    what = (f"Z-width: (24) and (25) from haptic-tune zwidth (b_c = "
            f"{data['coupling_damping_n_s_per_m']:g} N s/m, a rigid wall) beside the impedance "
            f"the hand ({data['hand']}) felt in HIL, its force over the handle's velocity, in "
            f"contact with a {sci(data['rigid_wall_n_per_m'])} N/m wall and in free motion; "
            "below, the static stiffness it was held with")
    for extension in ("png", "pdf"):
        plt, _ = chart_style.pyplot()
        figure = chart_style.new_figure(plt, (7.0, 10.0))
        axes = draw_zwidth(plt, data, figure)
        chart_style.save(figure, str(out_dir / f"zwidth.{extension}"), f"{what}. {caption}",
                         legend_from=axes)
        plt.close(figure)
        written.append(f"zwidth.{extension}")
    return written
