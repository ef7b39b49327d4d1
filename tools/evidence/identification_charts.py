"""The identification charts (identification.py's data; bench/tune/identify_sweep's tables),
in the look of every hapticd chart (chart_style.py). The one way to draw them:
tools/plot/identification_chart.py draws a table from the command line with these functions.

  identification-error-time  the sweep: median |error| of m, b and F_c and the solve time
                             against the log's length, one line per excitation amplitude;
  identification-segments    the segment study: spread of the estimates, calibration of
                             their standard errors and the residual against the shooting
                             segment's length, one colour per force noise.
"""

import math

import chart_style

COLORS = ["tab:purple", "tab:red", "tab:orange", "tab:green", "tab:blue", "tab:brown"]
NOISE_COLORS = ["tab:blue", "tab:orange", "tab:red", "tab:green", "tab:purple"]
PARAMETERS = [("mass", "m (mass)", "o", "-"), ("damping", "b (damping)", "s", "--"),
              ("coulomb", "F_c (Coulomb friction)", "^", ":")]
REQUIREMENT = {"mass": 2.0, "damping": 2.0, "coulomb": 10.0}  # %, the issue's


def value(v):
    return math.nan if v is None else float(v)


def percent(v):
    return 100.0 * abs(value(v))


def ticks_at(ax, values):
    """Major ticks on a log axis at the grid's own values, as plain numbers (1, 2, 5, 10)."""
    from matplotlib.ticker import FixedLocator, FuncFormatter
    ax.xaxis.set_major_locator(FixedLocator(sorted(set(values))))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda x, _: f"{x:g}"))


def amplitude_label(amplitude, device, default_amplitude):
    label = f"{amplitude:g} N RMS ({amplitude / device['coulomb']:g} F_c)"
    return label + ", the tests' default" if amplitude == default_amplitude else label


def draw_sweep(plt, table, figure, default_amplitude=None):
    """Median |error| of m, b and F_c (%) and the solve time (ms) against the log's length,
    one line per amplitude; a ring where the default options refused most seeds."""
    from matplotlib.lines import Line2D
    device = table["device"]
    lengths = table["lengths_s"]
    seeds = table["seeds"]
    cells = {(c["length_s"], c["amplitude_rms_n"]): c for c in table["cells"]}
    grid = figure.subplots(2, 2, sharex=True)
    panels = [(grid[0][0], "mass", "m", "mass m"), (grid[0][1], "damping", "b", "damping b"),
              (grid[1][0], "coulomb", "F_c", "Coulomb friction F_c")]
    for ax, name, symbol, title in panels:
        for i, amplitude in enumerate(table["amplitudes_rms_n"]):
            color = COLORS[i % len(COLORS)]
            xs, ys, refused_x, refused_y = [], [], [], []
            for length in lengths:
                cell = cells.get((length, amplitude))
                if cell is None or cell[f"median_abs_{name}_error"] is None:
                    continue
                xs.append(length)
                ys.append(percent(cell[f"median_abs_{name}_error"]))
                if 2 * cell["refused_by_default"] > seeds:
                    refused_x.append(length)
                    refused_y.append(ys[-1])
            ax.plot(xs, ys, "o-", color=color, markersize=3.5, linewidth=1.2,
                    label=amplitude_label(amplitude, device, default_amplitude)
                    if name == "mass" else "_")
            ax.plot(refused_x, refused_y, "o", markersize=8.5, markerfacecolor="none",
                    markeredgecolor=color, markeredgewidth=1.1, label="_")
        ax.axhline(REQUIREMENT[name], color="0.25", linestyle="--", linewidth=1.0, label="_")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylabel(f"median |{symbol} error| (%)")
        ax.set_title(f"{title}: requirement {REQUIREMENT[name]:g} % (dashed)")
        chart_style.grid(ax)
    ax = grid[1][1]
    for i, amplitude in enumerate(table["amplitudes_rms_n"]):
        xs, cpu = [], []
        for length in lengths:
            cell = cells.get((length, amplitude))
            if cell is None or cell["median_cpu_time_s"] is None:
                continue
            xs.append(length)
            cpu.append(1e3 * value(cell["median_cpu_time_s"]))
        ax.plot(xs, cpu, "o-", color=COLORS[i % len(COLORS)], markersize=3.5, linewidth=1.2,
                label="_")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylabel("solve time, thread CPU (ms)")
    ax.set_title("solve time (identify_axis)")
    chart_style.grid(ax)
    for ax in grid[1]:
        ax.set_xlabel(f"log length (s) at {device['rate_hz']:g} Hz")
        ticks_at(ax, lengths)
    legend_ax = grid[0][0]
    legend_ax.add_line(Line2D([], [], color="0.25", linestyle="--", linewidth=1.0,
                              label="the requirement: 2 % for m and b, 10 % for F_c"))
    legend_ax.add_line(Line2D([], [], marker="o", markersize=8.5, markerfacecolor="none",
                              markeredgecolor="0.25", linestyle="none",
                              label="ring: the default options refuse most seeds "
                                    "(the error is the fit's with the checks off)"))
    return [legend_ax]


def what_sweep(table):
    excitation = table.get("excitation", {})
    seeds = table["seeds"]
    over = f"median of {seeds} seeds" if seeds > 1 else "one seed"
    return ("haptic-tune identify: error and solve time against the log's length and the "
            f"excitation's amplitude ({excitation.get('kind', 'multisine')}, "
            f"{excitation.get('lines', '?')} lines from {excitation.get('low_hz', 0):g} to "
            f"{excitation.get('high_hz', 0):g} Hz), {over}, {table.get('segment_s', 0.02):g} s "
            "segments")


def draw_segments(plt, table, figure, default_segment_s=0.02):
    """Against the shooting segment's length: the RMS error of m, b and F_c (%), the RMS of
    their z = (estimate - truth) / standard error, and the residual (encoder counts)."""
    from matplotlib.lines import Line2D
    rows = table["rows"]
    noises = sorted({r["force_noise_n"] for r in rows})
    spread, calibration, residual = figure.subplots(3, 1, sharex=True,
                                                    gridspec_kw={"height_ratios": [3, 3, 2]})
    for i, noise in enumerate(noises):
        color = NOISE_COLORS[i % len(NOISE_COLORS)]
        subset = sorted((r for r in rows if r["force_noise_n"] == noise),
                        key=lambda r: r["segment_s"])
        xs = [r["segment_s"] for r in subset]
        for name, _, marker, style in PARAMETERS:
            spread.plot(xs, [percent(r[f"rms_{name}_error"]) for r in subset], color=color,
                        marker=marker, linestyle=style, markersize=3.5, linewidth=1.1, label="_")
            calibration.plot(xs, [value(r[f"rms_z_{name}"]) for r in subset], color=color,
                             marker=marker, linestyle=style, markersize=3.5, linewidth=1.1,
                             label="_")
        residual.plot(xs, [value(r["median_residual_rms_counts"]) for r in subset], color=color,
                      marker="o", markersize=3.5, linewidth=1.1, label="_")
    for ax in (spread, calibration, residual):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.axvline(default_segment_s, color="0.3", linestyle=":", linewidth=1.2, label="_")
        chart_style.grid(ax)
    spread.set_ylabel("RMS error (%)")
    spread.set_title(f"spread of the estimates over {table['seeds']} seeds of the "
                     f"{table['duration_s']:g} s run")
    calibration.axhline(1.0, color="0.25", linestyle="--", linewidth=1.0, label="_")
    calibration.set_ylabel("RMS z (1)")
    calibration.set_title("calibration of the standard errors: "
                          "z = (estimate \u2212 truth) / standard error")
    residual.axhline(1.0 / math.sqrt(12.0), color="0.25", linestyle="-.", linewidth=1.0,
                     label="_")
    residual.set_ylabel("residual RMS (counts)")
    residual.set_title("the fit's residual, median over the seeds")
    residual.set_xlabel("shooting segment length (s)")
    ticks_at(residual, [r["segment_s"] for r in rows])
    for i, noise in enumerate(noises):
        spread.add_line(Line2D([], [], color=NOISE_COLORS[i % len(NOISE_COLORS)], linewidth=2.0,
                               label=f"force noise {noise:g} N"))
    for _, symbol, marker, style in PARAMETERS:
        spread.add_line(Line2D([], [], color="0.2", marker=marker, linestyle=style,
                               markersize=3.5, label=f"{symbol}"))
    spread.add_line(Line2D([], [], color="0.3", linestyle=":", linewidth=1.2,
                           label=f"the default segment, {default_segment_s:g} s"))
    spread.add_line(Line2D([], [], color="0.25", linestyle="--", linewidth=1.0,
                           label="RMS z = 1: standard errors that cover the spread"))
    spread.add_line(Line2D([], [], color="0.25", linestyle="-.", linewidth=1.0,
                           label="1/\u221a12 counts: the encoder's quantisation"))
    return [spread]


def what_segments(table):
    return ("haptic-tune identify: the shooting segment's length against the spread of the "
            "estimates, the calibration of their standard errors and the residual, with and "
            f"without force noise ({table['seeds']} seeds of the {table['duration_s']:g} s "
            "run)")


def draw_one(path, draw, table, caption, size_in, font_size_pt=chart_style.DEFAULT_FONT_SIZE_PT,
             **options):
    """One chart of `table` into `path` (PNG, SVG or PDF by its extension)."""
    plt, _ = chart_style.pyplot(font_size_pt)
    figure = chart_style.new_figure(plt, size_in)
    try:
        axes = draw(plt, table, figure, **options)
        chart_style.save(figure, str(path), caption, legend_from=axes)
    finally:
        plt.close(figure)


SWEEP_SIZE_IN = (7.0, 6.6)
SEGMENTS_SIZE_IN = (7.0, 7.6)


def draw(data, out_dir, caption):
    """Both charts as PNG (for the docs) and PDF; returns their names. The caption line says
    what the chart shows, then `caption` (the run, the device, the machine)."""
    charts = [("identification-error-time", draw_sweep, data["sweep"], what_sweep,
               SWEEP_SIZE_IN, {"default_amplitude": data["default_amplitude_rms_n"]}),
              ("identification-segments", draw_segments, data["segments"], what_segments,
               SEGMENTS_SIZE_IN, {"default_segment_s": data["default_segment_s"]})]
    written = []
    for name, draw_chart, table, what, size_in, options in charts:
        for extension in ("png", "pdf"):
            draw_one(out_dir / f"{name}.{extension}", draw_chart, table,
                     f"{what(table)}. {caption}", size_in, **options)
            written.append(f"{name}.{extension}")
    return written
