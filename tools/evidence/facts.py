"""The numbers and tables docs/RESULTS.md quotes, each computed from the data files the
evidence wrote (never typed by hand): results_doc.py puts them into the template, and the
suite checks that RESULTS.md is the template rendered from docs/results/.

Each fact is a function of the loaded data ({section: its JSON}) returning text.
"""

import zwidth_facts


def n_per_m(value):
    return "none" if value is None else f"{value:,.0f} N/m"


def growth(verdict):
    rate = verdict["rise_growth_per_s"] if not verdict["stable"] and \
        verdict["rise_growth_per_s"] > 0 else verdict["growth_per_s"]
    return f"{'stable' if verdict['stable'] else 'UNSTABLE'} ({rate:+.1f}/s)"


def design(data, name):
    return next(d for d in data["stability-maps"]["operators"]["designs"] if d["design"] == name)


def wall_row(data, name):
    return next(r for r in data["stability-maps"]["walls"]["rows"] if r["design"] == name)


def operator_label(data, name):
    return next(r["label"] for r in data["stability-maps"]["operators"]["rows"]
                if r["operator"] == name)


def design_table(data):
    """Each model's own gains against every operator: the verdict and the fitted growth."""
    block = data["stability-maps"]["operators"]
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


def unstable_for(data, name):
    names = design(data, name)["unstable_for"]
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


def run_info(data, section):
    block = data[section]
    return (f"{block['date']}, {block['seconds']:.0f} s, hapticd {block['hapticd']}, "
            f"{block['machine']['cpu']} ({block['machine']['cores']} cores, Linux "
            f"{block['machine']['kernel']})")


def bracket(low, high):
    return "no bracket" if low is None else f"{low:,.0f} to {high:,.0f} N/m"


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


def us(value):
    return "overflow" if value is None else f"{value:,.0f} us"


def wake_table(data):
    wake = data["timing"]["wake_latency"]
    lines = ["| load | program | p50 | p99 | p99.9 | max (not meaningful on a VM) |",
             "|---|---|---|---|---|---|"]
    for load, block in wake["loads"].items():
        for program, numbers in block["programs"].items():
            q = numbers["wake_latency_us"]
            lines.append(f"| {load} | {program} | {us(q['p50'])} | {us(q['p99'])} | "
                         f"{us(q['p999'])} | {us(q['max'])} |")
        r = block["ratios_hapticd_over_cyclictest"]
        cells = " | ".join("n/a" if r[k] is None else f"{r[k]:.2f}" for k in ("p50", "p99", "p999"))
        lines.append(f"| {load} | ratio hapticd / cyclictest | {cells} | |")
    return "\n".join(lines)


def instructions_table(data):
    lines = ["| scene | device axes | instructions per tick |", "|---|---|---|"]
    for c in data["timing"]["instructions"]["configs"]:
        lines.append(f"| {c['scene_name']} | {c['axes']} | {c['instructions_per_tick']:,.0f} |")
    return "\n".join(lines)


def servo_tick_table(data):
    lines = ["| scene (BM_ServoTick) | CPU time per tick (median) |", "|---|---|"]
    for scene, t in data["timing"]["servo_tick"].items():
        lines.append(f"| {scene} | {t['cpu_time_ns']:,.0f} ns |")
    return "\n".join(lines)


def timing_run(data):
    wake = data["timing"]["wake_latency"]
    load = wake["machine"]["load_average_1_5_15"]
    return (f"{run_info(data, 'timing')}; wake-ups {wake['seconds']:g} s per program and load "
            f"in {wake['rounds']} turns, on CPU {wake['cpu']}; the load average at the start "
            f"{load[0]:.2f}")


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


def mm(value_m):
    return f"{1e3 * value_m:.2f} mm"


def scene_row(data, planes):
    return next(r for r in data["scene-detail"]["rows"] if r["planes"] == planes)


def scene_table(data):
    lines = ["| model of the cavity | surface error (worst direction) | handle depth (mean) | "
             "tick compute (median) |", "|---|---|---|---|"]
    for r in data["scene-detail"]["rows"]:
        name = "the sphere primitive" if r["planes"] == 0 else f"{r['planes']} tangent planes"
        lines.append(f"| {name} | {mm(r['surface_error_max_m'])} | "
                     f"{mm(r['handle_depth_mean_m'])} | {r['tick_compute_us_p50']:.2f} us |")
    return "\n".join(lines)


def scene_enough(data):
    import scene_detail
    planes = scene_detail.enough_planes(data["scene-detail"])
    if planes is None:
        return "no plane count on the grid"
    row = scene_row(data, planes)
    return (f"{planes} planes (the facets err by {mm(row['surface_error_max_m'])}, the tick "
            f"costs {row['tick_compute_us_p50']:.2f} us)")


def effort_grid_enough(data):
    """The sparsest grid whose worst margin matches the densest's within 1e-12, for every
    design, and what the default (4096) costs against it."""
    studies = data["effort"]["grid"]
    points = sorted({r["grid_points"] for s in studies for r in s["rows"]})
    for p in points:
        if all(abs(next(r for r in s["rows"] if r["grid_points"] == p)["worst_margin"]
                   - s["rows"][-1]["worst_margin"]) < 1e-12 for s in studies):
            return str(p)
    return "none of them"


def effort_grid_time(data, points):
    """The slowest design's check time on a grid of `points` (None: the default grid)."""
    if points is None:
        times = [s["default_grid_seconds"] for s in data["effort"]["grid"]]
    else:
        times = [r["seconds"] for s in data["effort"]["grid"] for r in s["rows"]
                 if r["grid_points"] == points]
    return f"{1e3 * max(times):.3f} ms" if times else "not run"


def effort_grid_sparsest_time(data):
    return effort_grid_time(data, int(effort_grid_enough(data)))


def effort_densest(data):
    return f"{max(r['grid_points'] for s in data['effort']['grid'] for r in s['rows']):,}"


def effort_designs(data):
    return "; ".join(s["design"] for s in data["effort"]["grid"])


def effort_thinned(data):
    rows = [r["sweep"] for r in data["effort"]["sweep"][0]["rows"] if ", one operator in " in r["sweep"]]
    strides = [r.rsplit(" ", 1)[1] for r in rows if not r.endswith(" 1")]
    return ", ".join(f"1 in {s}" for s in strides)


def effort_sweep_missed(data):
    """The sweeps of the default operators that called the encoder model's k_c stable."""
    study = data["effort"]["sweep"][0]
    missed = [r for r in study["rows"] if r["stable"]]
    found = [r for r in study["rows"] if not r["stable"]]
    worst = max(r["worst_spectral_radius"] for r in found) if found else None
    whole = study["rows"][-1]["operators"]
    text = ", ".join(f"{r['operators']} operators" for r in missed) or "no sweep"
    return (f"{text} of {whole} called it stable; the sweeps that kept the lossless grips tuned to "
            f"Nyquist found it growing by |z| - 1 = {worst - 1.0:.2g} per tick"
            if worst else text)


def effort_full_time(data):
    study = data["effort"]["sweep"][0]
    full = study["rows"][-1]
    return f"{full['seconds']:.2f} s for {full['cases']:,} cases"


FACTS = {
    "maps.run": lambda d: run_info(d, "stability-maps"),
    "maps.device": lambda d: d["stability-maps"]["device"],
    "maps.design_table": design_table,
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
    "rate.run": lambda d: run_info(d, "rate"),
    "rate.device": lambda d: d["rate"]["device"],
    "rate.table": rate_table,
    "rate.steps": lambda d: str(d["rate"]["bisection_steps"]),
    "rate.within_passive": rate_within_passive,
    "rate.paper_unstable": rate_paper_unstable,
    "rate.exact_finding": rate_exact_finding,
    "timing.run": timing_run,
    "scene.run": lambda d: run_info(d, "scene-detail"),
    "scene.device": lambda d: d["scene-detail"]["device"],
    "scene.table": scene_table,
    "scene.give": lambda d: mm(d["scene-detail"]["coupling_give_m"]),
    "scene.enough": scene_enough,
    "scene.sphere_compute": lambda d: f"{scene_row(d, 0)['tick_compute_us_p50']:.2f} us",
    "scene.sphere_depth": lambda d: mm(scene_row(d, 0)["handle_depth_mean_m"]),
    "scene.directions": lambda d: str(d["scene-detail"]["directions"]),
    "effort.run": lambda d: run_info(d, "effort"),
    "effort.device": lambda d: d["effort"]["device"],
    "effort.grid_enough": effort_grid_enough,
    "effort.grid_time_sparsest": effort_grid_sparsest_time,
    "effort.grid_time_default": lambda d: effort_grid_time(d, None),
    "effort.densest": effort_densest,
    "effort.designs": effort_designs,
    "effort.thinned": effort_thinned,
    "effort.sweep_missed": effort_sweep_missed,
    "effort.full_time": effort_full_time,
    "fil.run": lambda d: run_info(d, "firmware"),
    "fil.device": lambda d: d["firmware"]["device"],
    "fil.delay_p50": lambda d: f"{d['firmware']['delay']['p50_periods']:.3f}",
    "fil.delay_p99": lambda d: f"{d['firmware']['delay']['p99_periods']:.3f}",
    "fil.sized_delay": lambda d: f"{1e3 * d['firmware']['sized_delay_s']:.2f} ms",
    "fil.measured": lambda d: bracket(d["firmware"]["measured"]["stiffest_stable_n_per_m"],
                                      d["firmware"]["measured"]["first_unstable_n_per_m"]),
    "fil.without_delay": lambda d: fil_verdict_on(d, "passive_without_delay_n_per_m"),
    "fil.with_delay": lambda d: fil_verdict_on(d, "passive_with_delay_n_per_m"),
    "timing.wake_table": wake_table,
    "timing.instructions_table": instructions_table,
    "timing.servo_tick_table": servo_tick_table,
    "zwidth.run": lambda d: run_info(d, "zwidth"),
    **zwidth_facts.FACTS,
}
