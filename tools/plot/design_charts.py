"""The design charts of haptic-tune plot and zwidth, drawn from the numbers haptic-tune
computed (hapticd_chart.py reads them and calls these):

  design-procedure: "frequency_hz", "coupling_conductance", "nyquist_hz", "design",
                    models[name] = {"bound": [...], "margin": [...],
                                    "worst_margin", "worst_frequency_hz",
                                    "marker": {"frequency_hz", "bound", "conductance"}}
  zwidth:           "frequency_hz", "display": "impedance" | "admittance", "nyquist_hz",
                    "delay_s", models[name] = {"zmin_magnitude": [...],
                                               "zmax_magnitude": [...]}
"""

import math


class BadChart(ValueError):
    """The chart's data is not what this kind needs."""


MODEL_STYLE = {
    "paper": {"color": "tab:blue", "label": "paper: ZOH (13) as printed"},
    "encoder": {"color": "tab:red", "label": "encoder: exact ZOH and backward difference"},
    "passive": {"color": "tab:green", "label": r"passive: hold $e^{-j\theta}$, the port condition"},
}
FALLBACK_COLORS = ["tab:green", "tab:purple", "tab:brown"]


def style_for(name, index):
    style = MODEL_STYLE.get(name)
    if style is not None:
        return style
    return {"color": FALLBACK_COLORS[index % len(FALLBACK_COLORS)], "label": name}


def as_array(np, values, what):
    if not isinstance(values, list):
        raise BadChart(f"{what} must be an array")
    # JSON null stands for a non-finite number; a log axis cannot show it.
    return np.array([math.nan if v is None else float(v) for v in values], dtype=float)


def positive(np, values):
    """The values with everything a log axis cannot show (<= 0, non-finite) masked."""
    return np.where(np.isfinite(values) & (values > 0.0), values, np.nan)


def format_hz(frequency):
    return f"{frequency:.4g} Hz"


def finish_axes(ax, frequency, nyquist, label_nyquist=True):
    """Log axes from just left of the lowest frequency (a marker there shows whole) to just
    right of Nyquist."""
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(frequency[0] / 1.2, nyquist * 1.15)
    ax.axvline(nyquist, color="0.4", linestyle=":", linewidth=1.0)
    if label_nyquist:
        ax.annotate(f"Nyquist {format_hz(nyquist)}", xy=(nyquist, 0.5),
                    xycoords=("data", "axes fraction"), rotation=90, ha="right", va="center",
                    fontsize="x-small", color="0.3", xytext=(-3, 0), textcoords="offset points")
    ax.set_xlabel("frequency f (Hz)")
    ax.grid(True, which="major", alpha=0.45)
    ax.grid(True, which="minor", alpha=0.15)


def binding_text(name, model):
    """'passive: binds at 12.3 Hz, margin +1e-11, (21) holds with equality'."""
    worst_hz = float(model["worst_frequency_hz"])
    where = format_hz(worst_hz) if worst_hz > 0.0 else "f \u2192 0"
    worst = float(model["worst_margin"])
    return f"{name}: binds at {where}, margin {worst:+.3g}, {verdict_text(worst)}"


def y_limits(np, curves, low_band_mask=None):
    """A y range that shows every curve over most of the band: curves that dive towards
    zero (the paper bound at Nyquist) or shoot to infinity (Tustin's warping) leave the
    frame instead of squeezing everything else into a sliver."""
    pooled = []
    for values in curves:
        shown = values if low_band_mask is None else values[low_band_mask]
        shown = shown[np.isfinite(shown) & (shown > 0.0)]
        if shown.size:
            pooled.append(shown)
    if not pooled:
        return None
    pooled = np.concatenate(pooled)
    top = float(pooled.max())
    bottom = max(float(pooled.min()), top * 1e-12)
    return bottom / 2.0, top * 2.0


def verdict_text(margin):
    # Margins within rounding of zero mean (21) holds with equality: a design sized to
    # the bound lands there, on either side of zero by a few ulps.
    if abs(margin) < 1e-9:
        return "(21) holds with equality"
    return "(21) holds" if margin > 0.0 else "(21) FAILS"


def draw_design_procedure(plt, np, chart, figure):
    frequency = as_array(np, chart["frequency_hz"], "frequency_hz")
    conductance = as_array(np, chart["coupling_conductance"], "coupling_conductance")
    nyquist = float(chart["nyquist_hz"])
    design = chart.get("design", {})
    models = chart.get("models", {})
    if not models:
        raise BadChart("no models to draw")
    ax, ax_margin = figure.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1.4]})
    below_nyquist = frequency <= 0.9 * nyquist

    curves = [conductance]
    margins = []
    ax.plot(frequency, positive(np, conductance), color="black", linewidth=2.2,
            label="left of (21): Re(1/Z_c), "
                  f"k_c = {design.get('stiffness', float('nan')):.4g} N/m, "
                  f"b_c = {design.get('damping', float('nan')):.4g} N s/m")
    for index, (name, model) in enumerate(models.items()):
        style = style_for(name, index)
        bound = as_array(np, model["bound"], f"models.{name}.bound")
        margin = as_array(np, model["margin"], f"models.{name}.margin")
        curves.append(bound)
        margins.append(margin)
        ax.plot(frequency, positive(np, bound), color=style["color"], linewidth=1.6,
                linestyle="--", label=f"right of (21), {style['label']}")
        # Where the coupling falls short of this model's bound, (21) fails.
        short = np.isfinite(bound) & (conductance < bound * (1.0 - 1e-9))
        if short.any():
            ax.fill_between(frequency, positive(np, conductance), positive(np, bound),
                            where=short, color=style["color"], alpha=0.2, linewidth=0)
        marker = model["marker"]
        worst_hz = float(model["worst_frequency_hz"])
        ax.plot([marker["frequency_hz"]], [marker["bound"]], marker="o", markersize=7,
                markerfacecolor="white", markeredgecolor=style["color"], markeredgewidth=2,
                linestyle="none", zorder=5)
        ax_margin.plot(frequency, margin, color=style["color"], linewidth=1.6,
                       label=binding_text(name, model))
        ax_margin.plot([marker["frequency_hz"]], [float(model["worst_margin"])], marker="o",
                       markersize=6, markerfacecolor="white", markeredgecolor=style["color"],
                       markeredgewidth=2, linestyle="none", zorder=5)
        if worst_hz >= frequency[0]:
            for axes in (ax, ax_margin):
                axes.axvline(worst_hz, color=style["color"], linestyle=":", linewidth=1.0)

    limits = y_limits(np, curves, low_band_mask=below_nyquist)
    if limits:
        ax.set_ylim(*limits)
    finish_axes(ax, frequency, nyquist)
    ax.set_xlabel("")
    ax.set_ylabel("conductance Re(1/Z)\n(m/(N s))")

    # Lower panel: the relative margin Re(1/Z_c)/bound - 1; (21) holds where it is >= 0.
    # Linear near zero, where the verdict is, logarithmic beyond 1 (the margin grows without
    # bound where a model's bound falls to zero). Rings: each model's binding point.
    ax_margin.axhline(0.0, color="black", linewidth=1.0)
    for index, (name, margin) in enumerate(zip(models, margins)):
        failing = np.isfinite(margin) & (margin < -1e-9)
        if failing.any():
            ax_margin.fill_between(frequency, margin, 0.0, where=failing,
                                   color=style_for(name, index)["color"], alpha=0.3,
                                   linewidth=0)
    finish_axes(ax_margin, frequency, nyquist, label_nyquist=False)
    ax_margin.set_yscale("symlog", linthresh=1.0, linscale=1.5)
    shown = np.concatenate([m[below_nyquist & np.isfinite(m)] for m in margins])
    if shown.size:
        ax_margin.set_ylim(min(-0.25, float(shown.min()) * 1.3),
                           max(1.0, float(shown.max()) * 2.0))
    ax_margin.set_ylabel("margin of (21)\nRe(1/Z_c)/bound \u2212 1")
    return [ax, ax_margin]


def delay_text(chart):
    delay_s = float(chart.get("delay_s") or 0.0)
    return f"; loop delay {delay_s * 1e3:.4g} ms in H" if delay_s > 0.0 else ""


def draw_zwidth(plt, np, chart, figure):
    ax = figure.subplots()
    frequency = as_array(np, chart["frequency_hz"], "frequency_hz")
    nyquist = float(chart["nyquist_hz"])
    models = chart.get("models", {})
    if not models:
        raise BadChart("no models to draw")
    admittance = chart.get("display") == "admittance"
    zmin_eq, zmax_eq = ("(42)", "(43)") if admittance else ("(24)", "(25)")

    curves = []
    for index, (name, model) in enumerate(models.items()):
        style = style_for(name, index)
        zmin = as_array(np, model["zmin_magnitude"], f"models.{name}.zmin_magnitude")
        zmax = as_array(np, model["zmax_magnitude"], f"models.{name}.zmax_magnitude")
        curves += [zmin, zmax]
        ax.plot(frequency, positive(np, zmax), color=style["color"], linewidth=1.8,
                label=f"|Z_max| {zmax_eq}, {style['label']}")
        ax.plot(frequency, positive(np, zmin), color=style["color"], linewidth=1.4,
                linestyle="--", label=f"|Z_min| {zmin_eq}, {style['label']}")
        ax.fill_between(frequency, positive(np, zmin), positive(np, zmax),
                        color=style["color"], alpha=0.08, linewidth=0)

    # Tustin's rule (12) sends |Z_dI| to infinity at Nyquist; scale to the band below it.
    limits = y_limits(np, curves, low_band_mask=frequency <= 0.9 * nyquist)
    if limits:
        ax.set_ylim(limits[0], limits[1] * 5.0)
    finish_axes(ax, frequency, nyquist)
    ax.set_ylabel("impedance magnitude |Z| (N s/m)")
    ax.text(0.99, 0.01, "shaded: the Z-width, from |Z_min| to |Z_max|" + delay_text(chart),
            transform=ax.transAxes, ha="right", va="bottom", fontsize="x-small", color="0.3")
    return [ax]


DRAW = {"design-procedure": draw_design_procedure, "zwidth": draw_zwidth}
