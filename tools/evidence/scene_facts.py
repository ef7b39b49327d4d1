"""The scene detail's numbers (scene_detail.py's data) that docs/RESULTS.md quotes."""

import scene_detail
from fact_text import run_info, mm


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
    planes = scene_detail.enough_planes(data["scene-detail"])
    if planes is None:
        return "no plane count on the grid"
    row = scene_row(data, planes)
    return (f"{planes} planes (the facets err by {mm(row['surface_error_max_m'])}, the tick "
            f"costs {row['tick_compute_us_p50']:.2f} us)")


def um(value_m):
    return f"{1e6 * value_m:,.1f} um"


def flat_wall_table(data):
    lines = ["| the flat wall | the tool's depth | the handle's depth | force | tick compute "
             "(median) |", "|---|---|---|---|---|"]
    for r in data["scene-detail"]["flat_wall"]:
        name = ("god-object plane (constraint)" if r["wall"] == "constraint" else
                f"penalty wall, K = {r['wall_n_per_m']:,.0f} N/m")
        lines.append(f"| {name} | {um(r['tool_depth_m'])} | {mm(r['handle_depth_m'])} | "
                     f"{r['force_n']:.2f} N | {r['tick_compute_us_p50']:.2f} us |")
    return "\n".join(lines)


def flat_wall_compute(data):
    rows = data["scene-detail"]["flat_wall"]
    constraint = next(r for r in rows if r["wall"] == "constraint")
    penalty = [r["tick_compute_us_p50"] for r in rows if r["wall"] == "penalty"]
    return (f"{constraint['tick_compute_us_p50']:.2f} us a tick against the penalty wall's "
            f"{min(penalty):.2f} to {max(penalty):.2f} us (the series solve of (17))")


def not_converged(data):
    block = data["scene-detail"]
    return str(sum(r["solver_not_converged"] for r in block["rows"]) +
               sum(r["solver_not_converged"] for r in block["flat_wall"]))


FACTS = {
    "scene.run": lambda d: run_info(d, "scene-detail"),
    "scene.device": lambda d: d["scene-detail"]["device"],
    "scene.table": scene_table,
    "scene.give": lambda d: mm(d["scene-detail"]["coupling_give_m"]),
    "scene.enough": scene_enough,
    "scene.sphere_compute": lambda d: f"{scene_row(d, 0)['tick_compute_us_p50']:.2f} us",
    "scene.sphere_depth": lambda d: mm(scene_row(d, 0)["handle_depth_mean_m"]),
    "scene.flat_wall_table": flat_wall_table,
    "scene.flat_wall_compute": flat_wall_compute,
    "scene.not_converged": not_converged,
    "scene.directions": lambda d: str(d["scene-detail"]["directions"]),
}
