"""Speed against accuracy: the servo rate, 250 Hz to 20 kHz, against the stiffest stable
stiffness, from theory and from the unchanged daemon in closed loop (hil.py), with what each
rate costs the host (the tick's compute time, median, times the rate).

At each rate, bisected on a log scale between a stable and an unstable run:
  no coupling   the stiffest wall K the handle holds with the wall on it directly
                (Colgate and Schenkel: 2b/T);
  coupling      the stiffest coupling k_c against a 1e7 N/m wall (b_c = 0): the stiffness
                the hand feels in contact, k_c K / (k_c + K) ~ k_c. Each model's limit
                beside it: paper 8b/T, encoder and passive 2b/T (haptic-tune size).
Hands-off: the operator every bound at b_c = 0 binds on.
"""

import designs as design_models
import hil

STIFF_WALL = 1e7   # N/m, the scenes' upper limit


def plan(quick):
    if quick:
        return {"rates": [500.0, 2000.0, 8000.0], "steps": 4, "duration_s": 2.0}
    return {"rates": [250.0, 500.0, 1000.0, 2000.0, 5000.0, 10000.0, 20000.0], "steps": 7,
            "duration_s": 4.0}


def bisect(ctx, tag, make_point, low, high, steps):
    """The stiffest stable value between `low` (stable) and `high` (unstable), bisected in
    the logarithm `steps` times; returns (stable value, unstable value, runs)."""
    runs = []
    for limit in (low, high):
        runs.append({"value": limit, **hil.run_point(ctx, make_point(limit), f"{tag}-end-{limit:g}")})
    if not runs[0]["stable"] or runs[1]["stable"]:
        return None, None, runs  # the bracket does not hold: said in the data
    for step in range(steps):
        middle = (low * high) ** 0.5
        verdict = hil.run_point(ctx, make_point(middle), f"{tag}-{step}")
        runs.append({"value": middle, **verdict})
        if verdict["stable"]:
            low = middle
        else:
            high = middle
    return low, high, runs


def one_rate(ctx, steps, rate_hz):
    device = hil.Device(rate_hz=rate_hz)
    hands_off = hil.OPERATORS[0]
    bound = 2.0 * device.damping_n_s_per_m * rate_hz  # 2b/T
    wall_low, wall_high, wall_runs = bisect(
        ctx, f"rate-{rate_hz:g}-wall",
        lambda k: hil.Point(device, hands_off, None, k, steps["duration_s"]),
        bound / 8.0, bound * 8.0, steps["steps"])
    kc_low, kc_high, kc_runs = bisect(
        ctx, f"rate-{rate_hz:g}-coupling",
        lambda k: hil.Point(device, hands_off, (k, 0.0), STIFF_WALL, steps["duration_s"]),
        bound / 8.0, bound * 8.0, steps["steps"])
    predicted = {}
    for name, options in (("paper", ("--model", "paper", "--no-exact-check")),
                          ("encoder", ("--model", "encoder", "--no-exact-check"))):
        predicted[name] = design_models.sized_stiffness(
            ctx, device, design_models.Design(name, "", "", options), 0.0)
    # The passive model's answer, held against the exact sampled-data model (size's own
    # cross-check): at the bound by construction, so the exact model sees |z| = 1 up to its
    # tolerance; where its eigenvalues' error passes the tolerance, it refuses the proof.
    passive = design_models.size(ctx, device, design_models.Design("passive", "", "", ()), 0.0)
    predicted["passive"] = passive["stiffness"]
    exact = passive["exact_check"]
    compute = sorted(r["tick_compute_us_p50"] for r in kc_runs)[len(kc_runs) // 2]
    return {"rate_hz": rate_hz, "predicted_n_per_m": predicted,
            "no_coupling": {"stiffest_stable_wall_n_per_m": wall_low,
                            "first_unstable_wall_n_per_m": wall_high, "runs": wall_runs},
            "coupling": {"stiffest_stable_n_per_m": kc_low, "first_unstable_n_per_m": kc_high,
                         "runs": kc_runs},
            "exact_cross_check": {"stable": exact["stable"], "marginal": exact["marginal"],
                                  "worst_spectral_radius": exact["worst_spectral_radius"],
                                  "tolerance": exact["marginal_tolerance"],
                                  "worst_frequency_hz": exact["worst_frequency_hz"]},
            "tick_compute_us_p50": compute,
            "host_cpu_fraction": compute * 1e-6 * rate_hz}


def run(ctx):
    steps = plan(ctx.quick)
    rows = ctx.parallel(lambda rate: one_rate(ctx, steps, rate), steps["rates"])
    return {"device": hil.Device().describe().replace("1000 Hz, ", ""),
            "operator": "hands-off", "stiff_wall_n_per_m": STIFF_WALL,
            "duration_s": steps["duration_s"], "bisection_steps": steps["steps"], "rows": rows}
