"""The firmware in the loop's numbers (firmware.py's data) that docs/RESULTS.md quotes."""

from fact_text import n_per_m, run_info, bracket


def fil_verdict_on(data, key):
    """Whether the board was stable at the passive model's k_c `key`, from the bisection's
    bracket: at or below its stiffest stable k_c, or at or above its first unstable one."""
    block = data["firmware"]
    k = block[key]
    measured = block["measured"]
    if measured["stiffest_stable_n_per_m"] is None:
        return "not bracketed"
    if k <= measured["stiffest_stable_n_per_m"]:
        return f"{n_per_m(k)}, stable on the board"
    if k >= measured["first_unstable_n_per_m"]:
        return f"{n_per_m(k)}, UNSTABLE on the board"
    return f"{n_per_m(k)}, inside the measured bracket"


FACTS = {
    "fil.run": lambda d: run_info(d, "firmware"),
    "fil.device": lambda d: d["firmware"]["device"],
    "fil.delay_p50": lambda d: f"{d['firmware']['delay']['p50_periods']:.3f}",
    "fil.delay_p99": lambda d: f"{d['firmware']['delay']['p99_periods']:.3f}",
    "fil.sized_delay": lambda d: f"{1e3 * d['firmware']['sized_delay_s']:.2f} ms",
    "fil.measured": lambda d: bracket(d["firmware"]["measured"]["stiffest_stable_n_per_m"],
                                      d["firmware"]["measured"]["first_unstable_n_per_m"]),
    "fil.without_delay": lambda d: fil_verdict_on(d, "passive_without_delay_n_per_m"),
    "fil.with_delay": lambda d: fil_verdict_on(d, "passive_with_delay_n_per_m"),
}
