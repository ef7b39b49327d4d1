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


FACTS = {
    "scene.run": lambda d: run_info(d, "scene-detail"),
    "scene.device": lambda d: d["scene-detail"]["device"],
    "scene.table": scene_table,
    "scene.give": lambda d: mm(d["scene-detail"]["coupling_give_m"]),
    "scene.enough": scene_enough,
    "scene.sphere_compute": lambda d: f"{scene_row(d, 0)['tick_compute_us_p50']:.2f} us",
    "scene.sphere_depth": lambda d: mm(scene_row(d, 0)["handle_depth_mean_m"]),
    "scene.directions": lambda d: str(d["scene-detail"]["directions"]),
}
