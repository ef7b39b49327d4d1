"""The numbers and tables docs/RESULTS.md quotes, each computed from the data files the
evidence wrote (never typed by hand): results_doc.py puts them into the template, and the
suite checks that RESULTS.md is the template rendered from docs/results/.

Each fact is a function of the loaded data ({section: its JSON}) returning text.
"""


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


def ident_sweep(data):
    return data["identification"]["sweep"]


def ident_cell(data, length, amplitude):
    return next(c for c in ident_sweep(data)["cells"]
                if c["length_s"] == length and c["amplitude_rms_n"] == amplitude)


def ident_amplitude(data, amplitude):
    coulomb = ident_sweep(data)["device"]["coulomb"]
    return f"{amplitude:g} N RMS ({amplitude / coulomb:g} F_c)"


def ident_percent(value):
    """A relative error in percent, two significant digits."""
    return f"{100.0 * abs(value):.2g}"


def ident_time(seconds):
    ms = 1e3 * seconds
    if ms < 10.0:
        return f"{ms:.1f} ms"
    return f"{ms:.0f} ms" if ms < 1000.0 else f"{seconds:.2f} s"


def ident_errors(cell):
    return " / ".join(ident_percent(cell[f"median_abs_{p}_error"])
                      for p in ("mass", "damping", "coulomb")) + " %"


def ident_table(data):
    """Per log length (rows) and amplitude (columns): the median |error| of m / b / F_c and the
    solve time, and how many seeds the default options refuse."""
    sweep = ident_sweep(data)
    seeds = sweep["seeds"]
    amplitudes = sweep["amplitudes_rms_n"]
    lines = ["| log length | " + " | ".join(ident_amplitude(data, a) for a in amplitudes) + " |",
             "|---|" + "---|" * len(amplitudes)]
    for length in sweep["lengths_s"]:
        cells = []
        for amplitude in amplitudes:
            cell = ident_cell(data, length, amplitude)
            refused = cell["refused_by_default"]
            if cell["median_abs_mass_error"] is None:
                cells.append(f"refused {refused}/{seeds} (no fit)")
            elif refused == seeds:
                cells.append(f"refused {refused}/{seeds} ({ident_errors(cell)})")
            else:
                text = f"{ident_errors(cell)}, {ident_time(cell['median_cpu_time_s'])}"
                cells.append(text + (f" (refused {refused}/{seeds})" if refused else ""))
        lines.append(f"| {length:g} s | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def ident_meets(data, cell):
    """Every seed accepted by the default options and within the requirement."""
    requirement = data["identification"]["requirement"]
    if cell["refused_by_default"] or cell["max_abs_mass_error"] is None:
        return False
    return all(cell[f"max_abs_{p}_error"] <= limit for p, limit in requirement.items())


def ident_shortest_meeting(data, amplitude):
    """The shortest log from which every longer one meets the requirement; None if the
    longest does not."""
    shortest = None
    for length in reversed(ident_sweep(data)["lengths_s"]):
        if not ident_meets(data, ident_cell(data, length, amplitude)):
            break
        shortest = length
    return shortest


def ident_meets_from(data):
    sweep = ident_sweep(data)
    held, never = [], []
    for amplitude in sweep["amplitudes_rms_n"]:
        length = ident_shortest_meeting(data, amplitude)
        if length is None:
            never.append(amplitude)
        else:
            held.append(f"{length:g} s at {ident_amplitude(data, amplitude)}")
    text = ", ".join(held) if held else "no log at any amplitude"
    if never:
        text += (f"; at {' and '.join(f'{a:g}' for a in never)} N RMS no log up to "
                 f"{sweep['lengths_s'][-1]:g} s meets it")
    return text


def ident_default_cell(data, which):
    amplitude = data["identification"]["default_amplitude_rms_n"]
    if which == "shortest":
        length = ident_shortest_meeting(data, amplitude)
        if length is None:
            return None
    else:
        length = ident_sweep(data)["lengths_s"][-1]
    return ident_cell(data, length, amplitude)


def ident_default_at(data, which):
    cell = ident_default_cell(data, which)
    if cell is None:
        return "none (no log meets the requirement there)"
    return (f"{cell['length_s']:g} s ({ident_errors(cell)}, "
            f"{ident_time(cell['median_cpu_time_s'])})")


def ident_time_ratio(data):
    short, long = ident_default_cell(data, "shortest"), ident_default_cell(data, "longest")
    if short is None:
        return "no log meets the requirement, so nothing to compare"
    return f"{long['median_cpu_time_s'] / short['median_cpu_time_s']:.0f} times"


def ident_mass_se(data, cell):
    """The median of the standard error of m the fit reported, relative to the truth."""
    mass = ident_sweep(data)["device"]["mass"]
    values = sorted(r["mass_std_error"] / mass for r in cell["runs"]
                    if r.get("mass_std_error") is not None)
    if not values:
        return None
    n = len(values)
    return values[n // 2] if n % 2 else 0.5 * (values[n // 2 - 1] + values[n // 2])


def ident_floor(data):
    """Where a longer log buys no accuracy in m: the shortest length from which the standard
    error the fit reports is below the error left at the longest log (that error is then
    bias, which no length shrinks), at the amplitude where it comes first."""
    sweep = ident_sweep(data)
    lengths = sweep["lengths_s"]
    best = None
    for amplitude in sweep["amplitudes_rms_n"]:
        last = ident_cell(data, lengths[-1], amplitude)
        if not ident_meets(data, last):
            continue
        floor = last["median_abs_mass_error"]
        start = None
        for length in reversed(lengths):
            se = ident_mass_se(data, ident_cell(data, length, amplitude))
            if se is None or se >= floor:
                break
            start = length
        if start is not None and (best is None or start < best[0]):
            best = (start, amplitude, floor)
    if best is None:
        return ("At every amplitude the standard error of m stays above the error left at the "
                f"{lengths[-1]:g} s log: each longer log still bought accuracy.")
    start, amplitude, floor = best
    se = ident_mass_se(data, ident_cell(data, start, amplitude))
    return (f"At {ident_amplitude(data, amplitude)} a log longer than {start:g} s buys no "
            f"accuracy in m at all: from {start:g} s on the standard error the fit reports "
            f"({100 * se:.2g} % there) is below the error left at {lengths[-1]:g} s, "
            f"{100 * floor:.2g} %, which is then bias, not noise (docs/identification.md "
            "traces it to the sim's own friction, whose stops it resolves to T/32).")


def ident_segment_row(data, segment_s, noise_n):
    return next(r for r in data["identification"]["segments"]["rows"]
                if r["segment_s"] == segment_s and r["force_noise_n"] == noise_n)


def ident_z(row):
    return " / ".join(f"{row[f'rms_z_{p}']:.2f}" for p in ("mass", "damping", "coulomb"))


def ident_segment_default(data):
    block = data["identification"]
    noise = block["sweep"]["device"]["force_noise_n"]
    row = ident_segment_row(data, block["default_segment_s"], noise)
    return (f"at {noise:g} N of force noise the residual is "
            f"{row['median_residual_rms_counts']:.2f} counts against 1/\u221a12 = "
            f"{1.0 / 12.0 ** 0.5:.2f}, and the RMS z of m / b / F_c is {ident_z(row)}")


def ident_segment_longest(data):
    block = data["identification"]
    noise = block["sweep"]["device"]["force_noise_n"]
    longest = max(r["segment_s"] for r in block["segments"]["rows"])
    row = ident_segment_row(data, longest, noise)
    return (f"{longest:g} s segments the residual is "
            f"{row['median_residual_rms_counts']:.2g} counts and RMS z {ident_z(row)}")


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
    "ident.run": lambda d: (f"{run_info(d, 'identification')}; the load average at the start "
                            f"{d['identification']['load_average_1_5_15'][0]:.2f}"),
    "ident.device": lambda d: d["identification"]["device"],
    "ident.excitation": lambda d: "{kind} of {lines} lines from {low_hz:g} to {high_hz:g} Hz".format(
        **ident_sweep(d)["excitation"]),
    "ident.seeds": lambda d: str(ident_sweep(d)["seeds"]),
    "ident.segment_seeds": lambda d: str(d["identification"]["segments"]["seeds"]),
    "ident.segment_run": lambda d: f"{d['identification']['segments']['duration_s']:g} s",
    "ident.segment_s": lambda d: f"{d['identification']['default_segment_s']:g} s",
    "ident.table": ident_table,
    "ident.meets_from": ident_meets_from,
    "ident.default_amplitude": lambda d: ident_amplitude(
        d, d["identification"]["default_amplitude_rms_n"]),
    "ident.default_shortest": lambda d: ident_default_at(d, "shortest"),
    "ident.default_longest": lambda d: ident_default_at(d, "longest"),
    "ident.time_ratio": ident_time_ratio,
    "ident.floor": ident_floor,
    "ident.segment_default": ident_segment_default,
    "ident.segment_longest": ident_segment_longest,
    "timing.run": timing_run,
    "timing.wake_table": wake_table,
    "timing.instructions_table": instructions_table,
    "timing.servo_tick_table": servo_tick_table,
}
