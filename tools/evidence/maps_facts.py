"""The stability maps' numbers (maps.py's data) that docs/RESULTS.md quotes."""

from fact_text import n_per_m, run_info


def growth(verdict):
    rate = verdict["rise_growth_per_s"] if not verdict["stable"] and \
        verdict["rise_growth_per_s"] > 0 else verdict["growth_per_s"]
    return f"{'stable' if verdict['stable'] else 'UNSTABLE'} ({rate:+.1f}/s)"


def design(data, name, key="operators"):
    return next(d for d in data["stability-maps"][key]["designs"] if d["design"] == name)


def wall_row(data, name):
    return next(r for r in data["stability-maps"]["walls"]["rows"] if r["design"] == name)


def operator_label(data, name):
    return next(r["label"] for r in data["stability-maps"]["operators"]["rows"]
                if r["operator"] == name)


def design_table(data, key="operators"):
    """Each model's own gains against every operator: the verdict and the fitted growth."""
    block = data["stability-maps"][key]
    names = [r["operator"] for r in block["rows"]]
    lines = ["| model | k_c | holds for | " + " | ".join(
        r["label"] for r in block["rows"]) + " |",
        "|---|---|---|" + "---|" * len(names)]
    for d in block["designs"]:
        cells = " | ".join(growth(d["verdicts"][name]) for name in names)
        lines.append(f"| {d['design']} | {n_per_m(d['stiffness_n_per_m'])} | "
                     f"{d['holds_for']} | {cells} |")
    return "\n".join(lines)


def operator_limits_table(data):
    block = data["stability-maps"]["operators"]
    lines = ["| operator | in the pen-grip class | stiffest stable k_c measured (on the grid) |",
             "|---|---|---|"]
    for r in block["rows"]:
        lines.append(f"| {r['description']} | {'yes' if r['in_pen_grip_class'] else 'no'} | "
                     f"{n_per_m(r['stiffest_stable_n_per_m'])} |")
    return "\n".join(lines)


def wall_table(data):
    block = data["stability-maps"]["walls"]
    lines = ["| design | stiffest stable wall measured (on the grid) |", "|---|---|"]
    for r in block["rows"]:
        lines.append(f"| {r['description']} | {n_per_m(r['stiffest_stable_wall_n_per_m'])} |")
    return "\n".join(lines)


def delay_table(data):
    block = data["stability-maps"]["delay"]
    lines = ["| delay (periods) | paper | encoder | passive | stiffest stable measured |",
             "|---|---|---|---|---|"]
    for r in block["rows"]:
        p = r["predicted_n_per_m"]
        lines.append(f"| {r['delay_periods']:g} | {n_per_m(p['paper'])} | "
                     f"{n_per_m(p['encoder'])} | {n_per_m(p['passive'])} | "
                     f"{n_per_m(r['stiffest_stable_n_per_m'])} |")
    return "\n".join(lines)


def unstable_for(data, name, key="operators"):
    names = design(data, name, key)["unstable_for"]
    return ", ".join(operator_label(data, n) for n in names) if names else "no operator"


def first_unstable(data, operator_name):
    """The smallest k_c on the operators map's grid at which `operator_name` was unstable."""
    block = data["stability-maps"]["operators"]
    row = next(r for r in block["rows"] if r["operator"] == operator_name)
    for k, verdict in zip(block["stiffness_n_per_m"], row["verdicts"]):
        if not verdict["stable"]:
            return n_per_m(k)
    return "nowhere on the grid"


def delays_where_optimistic(data, model):
    """The delays (in periods) at which `model`'s limit is at or above a k_c measured
    unstable there: a run inside what the model accepts grew."""
    block = data["stability-maps"]["delay"]
    picked = []
    for row in block["rows"]:
        unstable = [k for k, v in zip(block["stiffness_n_per_m"], row["verdicts"])
                    if not v["stable"]]
        if unstable and row["predicted_n_per_m"][model] >= min(unstable):
            picked.append(row["delay_periods"])
    return ", ".join(f"{p:g}" for p in picked) if picked else "none"


def class_members_among(data, name, key):
    """How many of the operators `name`'s gains were unstable for are in the pen-grip class."""
    rows = {r["operator"]: r for r in data["stability-maps"][key]["rows"]}
    unstable = design(data, name, key)["unstable_for"]
    members = sum(1 for n in unstable if rows[n]["in_pen_grip_class"])
    return f"{members} of them in the class"


def delayed_kc(data, name):
    return n_per_m(design(data, name, "operators_delayed")["stiffness_n_per_m"])


FACTS = {
    "maps.run": lambda d: run_info(d, "stability-maps"),
    "maps.device": lambda d: d["stability-maps"]["device"],
    "maps.design_table": design_table,
    "maps.delayed_design_table": lambda d: design_table(d, "operators_delayed"),
    "maps.delayed_passive_kc": lambda d: delayed_kc(d, "passive"),
    "maps.delayed_class_kc": lambda d: delayed_kc(d, "class"),
    "maps.delayed_paper_unstable_for": lambda d: unstable_for(d, "paper", "operators_delayed"),
    "maps.delayed_encoder_unstable_for": lambda d: unstable_for(d, "encoder",
                                                                "operators_delayed"),
    "maps.delayed_passive_unstable_for": lambda d: unstable_for(d, "passive",
                                                                "operators_delayed"),
    "maps.delayed_class_unstable_for": lambda d: unstable_for(d, "class", "operators_delayed"),
    "maps.delayed_class_members": lambda d: class_members_among(d, "class", "operators_delayed"),
    "maps.class_members": lambda d: class_members_among(d, "class", "operators"),
    "maps.operator_limits_table": operator_limits_table,
    "maps.wall_table": wall_table,
    "maps.delay_table": delay_table,
    "maps.paper_kc": lambda d: n_per_m(design(d, "paper")["stiffness_n_per_m"]),
    "maps.encoder_kc": lambda d: n_per_m(design(d, "encoder")["stiffness_n_per_m"]),
    "maps.passive_kc": lambda d: n_per_m(design(d, "passive")["stiffness_n_per_m"]),
    "maps.class_kc": lambda d: n_per_m(design(d, "class")["stiffness_n_per_m"]),
    "maps.paper_unstable_for": lambda d: unstable_for(d, "paper"),
    "maps.encoder_unstable_for": lambda d: unstable_for(d, "encoder"),
    "maps.passive_unstable_for": lambda d: unstable_for(d, "passive"),
    "maps.class_unstable_for": lambda d: unstable_for(d, "class"),
    "maps.no_coupling_wall": lambda d: n_per_m(wall_row(d, "none")["stiffest_stable_wall_n_per_m"]),
    "maps.passive_wall": lambda d: n_per_m(wall_row(d, "passive")["stiffest_stable_wall_n_per_m"]),
    "maps.colgate": lambda d: n_per_m(d["stability-maps"]["walls"]["colgate_bound_n_per_m"]),
    "maps.nyquist_grip_first_unstable": lambda d: first_unstable(d, "nyquist-grip"),
    "maps.hands_off_first_unstable": lambda d: first_unstable(d, "hands-off"),
    "maps.paper_optimistic_delays": lambda d: delays_where_optimistic(d, "paper"),
    "maps.passive_optimistic_delays": lambda d: delays_where_optimistic(d, "passive"),
    "maps.encoder_optimistic_delays": lambda d: delays_where_optimistic(d, "encoder"),
}
