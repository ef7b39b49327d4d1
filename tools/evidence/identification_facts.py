"""The identification's numbers (identification.py's data) that docs/RESULTS.md quotes."""

from fact_text import run_info


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
}
