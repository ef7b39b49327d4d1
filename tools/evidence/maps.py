"""Stability where methods fail: measured verdicts of the unchanged daemon in closed loop
with the simulated pen display (hil.py), beside what each stability model predicts
(designs.py).

  operators  coupling stiffness k_c against operator, b_c = 1 N s/m, a 1e5 N/m wall; each
             model's k_c, and each model's own gains run against every operator; the same
             with a period of loop delay (operators_delayed)
  walls      wall stiffness against design: no coupling (the conventional design) and the
             couplings the passive and paper models size, hands-off
  delay      coupling stiffness against the loop delay (whole and fractional periods),
             b_c = 0, hands-off, with each model's delay-aware limit
"""

import math

import designs as design_models
import hil

COUPLING_DAMPING = 1.0   # N s/m, the operators map: where a class buys stiffness
WALL = 1e5               # N/m, the operators and delay maps' wall


def geometric(low, high, per_octave):
    count = int(round(math.log2(high / low) * per_octave)) + 1
    return [low * (high / low) ** (i / (count - 1)) for i in range(count)]


def plan(quick):
    if quick:
        return {"duration_s": 2.0, "stiffness": geometric(500.0, 32000.0, 1),
                "operators": ["hands-off", "heavy-hand", "nyquist-grip"],
                "walls": geometric(1e3, 1e7, 0.5), "delays": [0.0, 0.5, 1.0],
                "delay_stiffness": geometric(500.0, 16000.0, 1)}
    return {"duration_s": 6.0, "stiffness": geometric(500.0, 32000.0, 4),
            "operators": [op.name for op in hil.OPERATORS],
            "walls": geometric(1e3, 1.024e6, 2) + [1e7],
            "delays": [0.0, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0],
            "delay_stiffness": geometric(250.0, 16000.0, 4)}


def operator(name):
    return next(op for op in hil.OPERATORS if op.name == name)


def run_points(ctx, label, points):
    """Runs the points, `ctx.jobs` at a time; their judgements in order."""
    return ctx.parallel(lambda ip: hil.run_point(ctx, ip[1], f"{label}-{ip[0]}"),
                        list(enumerate(points)))


def stiffest_stable(values, judged):
    """The largest value below the first unstable one (values ascending): the measured limit
    on this grid; None when the first is already unstable."""
    best = None
    for value, verdict in zip(values, judged):
        if not verdict["stable"]:
            break
        best = value
    return best


def operators_map(ctx, steps, device, scene_path, label="operators"):
    """Each model's gains for `device` (its loop delay included) against every operator, and
    the grid of k_c against operator."""
    models = design_models.designs(ctx, scene_path)
    sized = {d.name: design_models.sized_stiffness(ctx, device, d, COUPLING_DAMPING)
             for d in models}
    ops = [operator(name) for name in steps["operators"]]
    grid = [hil.Point(device, op, (k, COUPLING_DAMPING), WALL, steps["duration_s"])
            for op in ops for k in steps["stiffness"]]
    own = [hil.Point(device, op, (sized[d.name], COUPLING_DAMPING), WALL, steps["duration_s"])
           for d in models for op in ops]
    judged = run_points(ctx, label, grid + own)
    n = len(steps["stiffness"])
    rows = []
    for i, op in enumerate(ops):
        cells = judged[i * n:(i + 1) * n]
        rows.append({"operator": op.name, "label": op.label, "description": op.description,
                     "in_pen_grip_class": op.in_pen_grip_class, "verdicts": cells,
                     "stiffest_stable_n_per_m": stiffest_stable(steps["stiffness"], cells)})
    own_judged = judged[len(grid):]
    design_rows = []
    for j, d in enumerate(models):
        cells = own_judged[j * len(ops):(j + 1) * len(ops)]
        design_rows.append({
            "design": d.name, "label": d.label, "holds_for": d.holds_for,
            "stiffness_n_per_m": sized[d.name],
            "verdicts": {op.name: cell for op, cell in zip(ops, cells)},
            "unstable_for": [op.name for op, cell in zip(ops, cells) if not cell["stable"]]})
    return {"coupling_damping_n_s_per_m": COUPLING_DAMPING, "wall_n_per_m": WALL,
            "delay_periods": device.delay_s * device.rate_hz,
            "stiffness_n_per_m": steps["stiffness"], "rows": rows, "designs": design_rows}


def walls_map(ctx, steps, device):
    hands_off = operator("hands-off")
    passive = design_models.sized_stiffness(ctx, device, design_models.Design(
        "passive", "", "", ()), 0.0)
    paper = design_models.sized_stiffness(ctx, device, design_models.Design(
        "paper", "", "", ("--model", "paper", "--no-exact-check")), 0.0)
    couplings = [("none", "no coupling",
                  "no coupling: the wall's force on the handle (the conventional design)", None),
                 ("passive", "passive k_c",
                  f"the coupling the passive model sizes, k_c = {passive:,.0f} N/m",
                  (passive, 0.0)),
                 ("paper", "paper k_c",
                  f"the coupling the paper's model sizes, k_c = {paper:,.0f} N/m",
                  (paper, 0.0))]
    if ctx.quick:
        couplings = couplings[:2]
    points = [hil.Point(device, hands_off, coupling, wall, steps["duration_s"])
              for _, _, _, coupling in couplings for wall in steps["walls"]]
    judged = run_points(ctx, "walls", points)
    n = len(steps["walls"])
    rows = []
    for i, (name, label, description, coupling) in enumerate(couplings):
        cells = judged[i * n:(i + 1) * n]
        rows.append({"design": name, "label": label, "description": description,
                     "stiffness_n_per_m": None if coupling is None else coupling[0],
                     "verdicts": cells,
                     "stiffest_stable_wall_n_per_m": stiffest_stable(steps["walls"], cells)})
    # Colgate and Schenkel: a penalty wall K on the handle, sampled, is passive for K < 2b/T.
    return {"operator": hands_off.name, "walls_n_per_m": steps["walls"], "rows": rows,
            "colgate_bound_n_per_m": 2.0 * device.damping_n_s_per_m * device.rate_hz}


def delay_map(ctx, steps, device):
    hands_off = operator("hands-off")
    rows = []
    points = []
    for periods in steps["delays"]:
        delayed = hil.Device(device.mass_kg, device.damping_n_s_per_m, device.rate_hz,
                             periods / device.rate_hz, device.counts_per_meter)
        predicted = {}
        for name, options in (("paper", ("--model", "paper", "--no-exact-check")),
                              ("encoder", ("--model", "encoder", "--no-exact-check")),
                              ("passive", ())):
            predicted[name] = design_models.sized_stiffness(
                ctx, delayed, design_models.Design(name, "", "", options), 0.0)
        rows.append({"delay_periods": periods, "predicted_n_per_m": predicted})
        points += [hil.Point(delayed, hands_off, (k, 0.0), WALL, steps["duration_s"])
                   for k in steps["delay_stiffness"]]
    judged = run_points(ctx, "delay", points)
    n = len(steps["delay_stiffness"])
    for i, row in enumerate(rows):
        row["verdicts"] = judged[i * n:(i + 1) * n]
        row["stiffest_stable_n_per_m"] = stiffest_stable(steps["delay_stiffness"],
                                                          row["verdicts"])
    return {"operator": hands_off.name, "coupling_damping_n_s_per_m": 0.0, "wall_n_per_m": WALL,
            "stiffness_n_per_m": steps["delay_stiffness"], "rows": rows}


def run(ctx):
    steps = plan(ctx.quick)
    device = hil.Device()
    scene_path = ctx.scratch("maps") / "wall.toml"
    scene_path.write_text(hil.wall_scene(WALL))
    return {"device": device.describe(), "duration_s": steps["duration_s"],
            "judge": {"from_s": hil.JUDGE_FROM_S, "window_s": hil.WINDOW_S,
                      "floor_m": hil.FLOOR_M, "growth_limit_per_s": hil.GROWTH_LIMIT_PER_S,
                      "rise_factor": hil.RISE_FACTOR},
            "operators": operators_map(ctx, steps, device, scene_path),
            # The same with a period of loop delay, every model sizing for it.
            "operators_delayed": operators_map(
                ctx, steps, hil.Device(delay_s=1.0 / device.rate_hz), scene_path,
                "operators-delayed"),
            "walls": walls_map(ctx, steps, device),
            "delay": delay_map(ctx, steps, device)}
