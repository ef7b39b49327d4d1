"""The admittance display's numbers (admittance.py's data) that docs/RESULTS.md quotes."""

from fact_text import run_info


def kg(value):
    return f"{value:,.1f} kg"


def admittance_table(data):
    lines = ["| k_p | (37) encoder m_c | (37) paper m_c | the exact loop's limit | (37)/exact | "
             "(37)'s best pair (m_c, b_c) in the exact loop |", "|---|---|---|---|---|---|"]
    for r in data["admittance"]["rows"]:
        pair = r["encoder_pair"]
        verdict = pair["verdict"]
        said = ("stable" if verdict["stable"] else
                f"UNSTABLE, \\|z\\| = {verdict['worst_spectral_radius']:.5f} per tick at "
                f"{verdict['worst_frequency_hz']:.0f} Hz")
        lines.append(f"| {r['kp_n_s_per_m']:g} N s/m | {kg(r['encoder_mass_kg'])} | "
                     f"{kg(r['paper_mass_kg'])} | {kg(r['exact_limit_kg'])} | "
                     f"{r['encoder_mass_kg'] / r['exact_limit_kg']:.2f} | "
                     f"{kg(pair['coupling_mass_kg'])}, {pair['coupling_damping_n_s_per_m']:,.0f} "
                     f"N s/m: {said} |")
    return "\n".join(lines)


def ratio_range(data):
    ratios = [r["encoder_mass_kg"] / r["exact_limit_kg"] for r in data["admittance"]["rows"]]
    return f"{min(ratios):.2f} to {max(ratios):.2f}"


def pairs_unstable(data):
    rows = data["admittance"]["rows"]
    unstable = sum(1 for r in rows if not r["encoder_pair"]["verdict"]["stable"])
    return f"{unstable} of {len(rows)}"


FACTS = {
    "admittance.run": lambda d: run_info(d, "admittance"),
    "admittance.device": lambda d: d["admittance"]["device"],
    "admittance.table": admittance_table,
    "admittance.ratio_range": ratio_range,
    "admittance.pairs_unstable": pairs_unstable,
}
