"""The Z-width numbers docs/RESULTS.md quotes (facts.py's FACTS holds them), each computed
from zwidth.py's data: what the hand felt in HIL beside (24), (25) and the physics."""

from fact_text import run_info


def block(data):
    return data["zwidth"]


def delay_words(row):
    return "none" if row["delay_periods"] == 0 else f"{row['delay_periods']:g} period"


def contact_rows(data):
    """(delay row, rigid-wall contact block) for every delay and coupling."""
    return [(row, c) for row in block(data)["delays"] for c in row["contact"]]


def percent(fraction):
    return f"{100.0 * fraction:.2g} %"


def sci(value):
    """1e7 for 1e+07."""
    mantissa, exponent = f"{value:.0e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def stiffness_table(data):
    z = block(data)
    lines = [f"| loop delay | k_c | felt on the {sci(z['rigid_wall_n_per_m'])} N/m wall | "
             f"k_c K/(k_c + K) | felt on the {z['soft_wall_n_per_m']:,.0f} N/m wall | "
             "k_c K/(k_c + K) |", "|---|---|---|---|---|---|"]
    for row in z["delays"]:
        for rigid, soft in zip(row["contact"], row["soft_wall"]):
            lines.append(
                f"| {delay_words(row)} | {rigid['coupling_stiffness_n_per_m']:,.0f} N/m | "
                f"{rigid['static_stiffness_n_per_m']:,.1f} N/m | "
                f"{rigid['expected']['series_stiffness_n_per_m']:,.1f} N/m | "
                f"{soft['static_stiffness_n_per_m']:,.1f} N/m | "
                f"{soft['series_stiffness_n_per_m']:,.1f} N/m |")
    return "\n".join(lines)


def resonance_table(data):
    lines = ["| loop delay | k_c | felt damping (fit) | b + b_c - k_c (T/2 + D) | "
             "the paper's b + b_c - k_c D | resonance (least passive \\|Z_max\\|) | "
             "felt \\|Z\\| there | passive (25) | encoder (25) | paper (25) |", "|---|---|---|---|---|---|---|---|---|---|"]
    for row, c in contact_rows(data):
        dip = c["dip"]
        theory = dip["zmax_magnitude_n_s_per_m"]
        lines.append(
            f"| {delay_words(row)} | {c['coupling_stiffness_n_per_m']:,.0f} N/m | "
            f"{c['fit']['damping_n_s_per_m']:.3f} N s/m | "
            f"{c['expected']['damping_n_s_per_m']:.3f} N s/m | "
            f"{c['expected']['paper_damping_n_s_per_m']:.3f} N s/m | "
            f"{dip['frequency_hz']:.1f} Hz | {dip['felt_magnitude_n_s_per_m']:.3f} N s/m | "
            f"{theory['passive']:.3f} N s/m | {theory['encoder']:.3f} N s/m | "
            f"{theory['paper']:.3f} N s/m |")
    return "\n".join(lines)


def free_fit(data):
    fits = [row["free"]["fit"] for row in block(data)["delays"]]
    masses = sorted({f"{f['mass_kg']:.4f}" for f in fits})
    dampings = sorted({f"{f['damping_n_s_per_m']:.4f}" for f in fits})
    return (f"m = {' and '.join(masses)} kg and b = {' and '.join(dampings)} N s/m")


def free_deviation(data):
    return percent(max(abs(d) for row in block(data)["delays"]
                       for d in row["free"]["deviation_from_zmin"]["passive"]))


def stiffness_error(data):
    errors = [c["static_stiffness_n_per_m"] / c["expected"]["series_stiffness_n_per_m"] - 1.0
              for _, c in contact_rows(data)]
    errors += [s["static_stiffness_n_per_m"] / s["series_stiffness_n_per_m"] - 1.0
               for row in block(data)["delays"] for s in row["soft_wall"]]
    return f"a relative {max(abs(e) for e in errors):.1e}"


def damping_error(data):
    worst = max(abs(c["fit"]["damping_n_s_per_m"] - c["expected"]["damping_n_s_per_m"])
                for _, c in contact_rows(data))
    return f"{worst:.3f} N s/m"


def band_deviation(data):
    """Per model, the largest |felt/(25) - 1| over the band's points (the resonances apart)."""
    models = block(data)["models"]
    parts = []
    for model in ("encoder", "passive", "paper"):
        if model in models:
            worst = max(abs(d) for _, c in contact_rows(data)
                        for d in c["deviation_from_zmax"][model])
            parts.append(f"{model} {percent(worst)}")
    return ", ".join(parts)


def delayed_stiffest(data):
    row = block(data)["delays"][-1]
    return row, row["contact"][-1]


def stiffest_kc(data):
    return f"{delayed_stiffest(data)[1]['coupling_stiffness_n_per_m']:,.0f} N/m"


def passive_kc_delay(data):
    return f"{delayed_stiffest(data)[0]['passive_stiffness_n_per_m']:,.0f} N/m"


def stiffest_damping(data):
    return f"{delayed_stiffest(data)[1]['fit']['damping_n_s_per_m']:+.3f} N s/m"


def paper_dip(data):
    dip = delayed_stiffest(data)[1]["dip"]
    theory = dip["zmax_magnitude_n_s_per_m"]
    return (f"{theory['paper']:.2f} N s/m at {dip['frequency_hz']:.1f} Hz where the hand "
            f"feels {dip['felt_magnitude_n_s_per_m']:.2f} N s/m "
            f"({theory['paper'] / dip['felt_magnitude_n_s_per_m']:.1f} times as much)")


FACTS = {
    "zwidth.run": lambda d: run_info(d, "zwidth"),
    "zwidth.device": lambda d: block(d)["device"],
    "zwidth.hand": lambda d: block(d)["hand"],
    "zwidth.stiffness_table": stiffness_table,
    "zwidth.resonance_table": resonance_table,
    "zwidth.free_fit": free_fit,
    "zwidth.free_deviation": free_deviation,
    "zwidth.stiffness_error": stiffness_error,
    "zwidth.damping_error": damping_error,
    "zwidth.band_deviation": band_deviation,
    "zwidth.stiffest_kc": stiffest_kc,
    "zwidth.passive_kc_delay": passive_kc_delay,
    "zwidth.stiffest_damping": stiffest_damping,
    "zwidth.paper_dip": paper_dip,
}
