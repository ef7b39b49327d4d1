"""The servo rate's numbers (rate.py's data) that docs/RESULTS.md quotes."""

from fact_text import n_per_m, run_info, bracket


def rate_table(data):
    lines = ["| rate | paper | encoder | passive | the exact model on passive's k_c | "
             "no coupling: stiffest stable wall | "
             "coupling: stiffest stable k_c | tick compute (median) | host CPU |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in data["rate"]["rows"]:
        p = r["predicted_n_per_m"]
        lines.append(
            f"| {r['rate_hz']:,.0f} Hz | {n_per_m(p['paper'])} | {n_per_m(p['encoder'])} | "
            f"{n_per_m(p['passive'])} | {exact_verdict(r['exact_cross_check'])} | "
            f"{bracket(r['no_coupling']['stiffest_stable_wall_n_per_m'], r['no_coupling']['first_unstable_wall_n_per_m'])} | "
            f"{bracket(r['coupling']['stiffest_stable_n_per_m'], r['coupling']['first_unstable_n_per_m'])} | "
            f"{r['tick_compute_us_p50']:.2f} us | {100 * r['host_cpu_fraction']:.3g} % |")
    return "\n".join(lines)


def rate_within_passive(data):
    """How many rates' measured coupling limit brackets the passive model's k_c (the stable
    end at most 1 % below it, the unstable end above it)."""
    rows = data["rate"]["rows"]
    held = sum(1 for r in rows if r["coupling"]["stiffest_stable_n_per_m"] is not None
               and r["coupling"]["stiffest_stable_n_per_m"] >= 0.99 * r["predicted_n_per_m"]["passive"]
               and r["coupling"]["first_unstable_n_per_m"] > r["predicted_n_per_m"]["passive"])
    return f"{held} of {len(rows)}"


def exact_verdict(check):
    excess = check["worst_spectral_radius"] - 1.0
    if check["stable"] and not check["marginal"]:
        return "stable"
    word = "marginal" if check["stable"] else "REFUSED"
    return f"{word}, \\|z\\| - 1 = {excess:.2g}"


def rate_exact_finding(data):
    """What the exact model's cross-check says of the passive answer across the rates."""
    rows = data["rate"]["rows"]
    refused = [r for r in rows if not r["exact_cross_check"]["stable"]]
    growth = rate_exact_worst_growth(data)
    if not refused:
        return (f"The exact model accepts the proof's k_c at every rate here; its worst case "
                f"grows by at most {growth}.")
    return ("The exact model refuses the proof's k_c at " +
            ", ".join(f"{r['rate_hz']:,.0f} Hz" for r in refused) +
            f": its worst case grows by {growth}.")


def rate_exact_worst_growth(data):
    """The largest excess of the exact cross-check's spectral radius, per tick and per second."""
    row = max(data["rate"]["rows"], key=lambda r: r["exact_cross_check"]["worst_spectral_radius"])
    excess = row["exact_cross_check"]["worst_spectral_radius"] - 1.0
    return (f"|z| - 1 = {excess:.2g} per tick at {row['rate_hz']:,.0f} Hz, "
            f"{excess * row['rate_hz']:.2g}/s (an e-fold in {1.0 / max(excess * row['rate_hz'], 1e-300) / 60.0:,.0f} min)")


def rate_paper_unstable(data):
    """How many rates' first unstable k_c the paper's limit is at or above."""
    rows = data["rate"]["rows"]
    above = sum(1 for r in rows if r["coupling"]["first_unstable_n_per_m"] is not None
                and r["predicted_n_per_m"]["paper"] >= r["coupling"]["first_unstable_n_per_m"])
    return f"{above} of {len(rows)}"


FACTS = {
    "rate.run": lambda d: run_info(d, "rate"),
    "rate.device": lambda d: d["rate"]["device"],
    "rate.table": rate_table,
    "rate.steps": lambda d: str(d["rate"]["bisection_steps"]),
    "rate.within_passive": rate_within_passive,
    "rate.paper_unstable": rate_paper_unstable,
    "rate.exact_finding": rate_exact_finding,
}
