"""Model no more than a scene needs: a spherical cavity rendered by the god-object as the
sphere itself ([[proxy_sphere]] side = "inside") or as N tangent planes ([[proxy_plane]], a
circumscribed polyhedron), in the unchanged daemon on the simulated 3-axis pen display. A
stiff grasp pushes the handle from the centre towards the wall in several directions; at
rest against it:

  surface error   how far the tool (the god-object's proxy, x_e) sits from the true sphere:
                  the facets' own error, which falls as the planes multiply;
  handle depth    how far the handle sits past the true sphere: the facets' error plus the
                  coupling's give F/k_c, which no number of planes removes;
  tick compute    the servo tick's median compute time (the lockstep run's summary).

Past the plane count where the facets' error drops under the coupling's give, more planes
buy the hand nothing: the point the chart marks.
"""

import json
import math

from hil import number

RADIUS_M = 0.03
COUPLING_N_PER_M = 3600.0          # the default config's k_c
GRASP_N_PER_M = 500.0              # each axis' stiff grasp
PUSH_PAST_M = 0.5 * RADIUS_M       # the set-point 1.5 R from the centre
RAMP_S, HOLD_S = 0.5, 1.5
SETTLED_S = 0.5                    # the last half second of the hold is averaged


def directions(count):
    """`count` unit vectors spread over the sphere (a Fibonacci lattice), deterministic."""
    golden = math.pi * (3.0 - math.sqrt(5.0))
    out = []
    for i in range(count):
        z = 1.0 - 2.0 * (i + 0.5) / count
        r = math.sqrt(1.0 - z * z)
        out.append((r * math.cos(golden * i), r * math.sin(golden * i), z))
    return out


def scene(planes):
    """The cavity: the sphere itself (planes = 0) or `planes` tangent planes, normals into
    the free space (towards the centre)."""
    text = '[scene]\nname = "evidence-cavity"\naxes = 3\n'
    if planes == 0:
        return text + (f'[[proxy_sphere]]\ncenter = [0.0, 0.0, 0.0]\nradius = {number(RADIUS_M)}'
                       '\nside = "inside"\n')
    for u in directions(planes):
        normal = ", ".join(number(-c) for c in u)
        text += f"[[proxy_plane]]\nnormal = [{normal}]\noffset = {number(-RADIUS_M)}\n"
    return text


def grasp(target_m, duration_s, table="[[device.sim.human]]"):
    """One axis' stiff grasp (0.3 kg, GRASP_N_PER_M, 5 N s/m), its set-point ramping to
    `target_m` from 0.3 s and held."""
    return (f'{table}\nmodel = "stiff-grasp"\nhand_mass = 0.3\n'
            f"hand_stiffness = {number(GRASP_N_PER_M)}\nhand_damping = 5.0\n"
            f"push = {{ to = {number(target_m)}, start = 0.3, ramp = {number(RAMP_S)}, "
            f"hold = {number(duration_s)} }}\n")


def pen_config(axes, initial_position, humans):
    """hapticd's config: the sim pen display on `axes` axes with a 1 nm encoder, the default
    config's coupling with the check off, the scene in scene.toml, and `humans`."""
    return ('[servo]\nrate_hz = 1000.0\nrealtime = "off"\n[device]\nplugin = "sim"\n'
            f"axes = {axes}\n[device.model]\nmass = 0.1\ndamping = 2.0\n"
            f'[coupling]\nstiffness = {number(COUPLING_N_PER_M)}\ndamping = 0.0\ncheck = "off"\n'
            '[scene]\nfile = "scene.toml"\n'
            "[safety]\nmax_force = 20.0\nmax_speed = 1.0\n"
            "[device.sim]\nmass = 0.1\ndamping = 2.0\ncounts_per_meter = 1e9\n"
            f'force_limit = 20.0\nclock = "lockstep"\ninitial_position = {initial_position}\n'
            + humans)


def config(direction, duration_s):
    humans = "".join(grasp(c * (RADIUS_M + PUSH_PAST_M), duration_s) for c in direction)
    return pen_config(3, "[0.0, 0.0, 0.0]", humans)


def run_hapticd(ctx, work, config_text, scene_text, duration_s, what):
    """One lockstep run in `work`: the log's columns (the log itself removed) and the
    summary."""
    (work / "cfg.toml").write_text(config_text)
    (work / "scene.toml").write_text(scene_text)
    log = work / "run.csv"
    ctx.run([ctx.program("hapticd"), "--lockstep", "--no-status", "--duration",
             number(duration_s), "--config", str(work / "cfg.toml"), "--log", str(log),
             "--summary", str(work / "summary.json")], f"hapticd, {what}")
    columns = read_log(log)
    log.unlink()
    return columns, json.loads((work / "summary.json").read_text())


def read_log(path):
    with open(path, encoding="utf-8") as f:
        lines = [line for line in f if not line.startswith("#")]
    names = lines[0].strip().split(",")
    columns = {name: [] for name in names}
    for line in lines[1:]:
        for name, value in zip(names, line.strip().split(",")):
            columns[name].append(float(value))
    return columns


def settled_radius(columns, prefix, from_s):
    """Mean distance from the centre of the point `prefix`{0,1,2}_m after from_s."""
    t = columns["t_s"]
    radii = [math.sqrt(sum(columns[f"{prefix}{a}_m"][i] ** 2 for a in range(3)))
             for i in range(len(t)) if t[i] >= from_s]
    return sum(radii) / len(radii)


def one_run(ctx, planes, index, direction, duration_s):
    columns, summary = run_hapticd(ctx, ctx.scratch(f"cavity-{planes}-{index}"),
                                   config(direction, duration_s), scene(planes), duration_s,
                                   f"cavity of {planes} planes")
    from_s = duration_s - SETTLED_S
    return {"surface_error_m": settled_radius(columns, "xe", from_s) - RADIUS_M,
            "handle_depth_m": settled_radius(columns, "x", from_s) - RADIUS_M,
            "tick_compute_us_p50": summary["tick_compute_us"]["p50"],
            "solver_not_converged": summary["solver_not_converged"]}


def run(ctx):
    counts = [0, 6, 24, 96] if ctx.quick else [0, 4, 6, 8, 12, 16, 24, 32, 48, 64, 96, 128, 192, 256]
    spread = directions(3 if ctx.quick else 7)
    duration_s = 0.3 + RAMP_S + HOLD_S
    jobs = [(planes, i, d) for planes in counts for i, d in enumerate(spread)]
    results = ctx.parallel(lambda job: one_run(ctx, *job, duration_s), jobs)
    rows = []
    for planes in counts:
        cells = [r for (p, _, _), r in zip(jobs, results) if p == planes]
        compute = sorted(c["tick_compute_us_p50"] for c in cells)[len(cells) // 2]
        rows.append({
            "planes": planes,
            "surface_error_max_m": max(abs(c["surface_error_m"]) for c in cells),
            "handle_depth_mean_m": sum(c["handle_depth_m"] for c in cells) / len(cells),
            "tick_compute_us_p50": compute,
            "solver_not_converged": sum(c["solver_not_converged"] for c in cells),
            "runs": cells})
    push_force_n = GRASP_N_PER_M * PUSH_PAST_M
    import penalty_constraint  # it reuses this module's settings
    return {"flat_wall": penalty_constraint.run(ctx),
            "device": "the simulated pen display on 3 axes, m = 0.1 kg, b = 2 N s/m per axis, "
                      "1000 Hz, 1 nm encoder counts",
            "radius_m": RADIUS_M, "coupling_n_per_m": COUPLING_N_PER_M,
            "push_force_n": push_force_n,
            # What the coupling gives under the push: the floor no plane count removes.
            "coupling_give_m": push_force_n / COUPLING_N_PER_M,
            "directions": len(spread), "rows": rows}


def enough_planes(data):
    """The fewest planes whose facets err by less than the coupling gives under the push:
    past it, the coupling's compliance, not the geometry, is most of what the hand feels."""
    for row in data["rows"]:
        if row["planes"] > 0 and row["surface_error_max_m"] < data["coupling_give_m"]:
            return row["planes"]
    return None


def draw(data, out_dir, caption):
    import chart_style
    what = ("A spherical cavity as the sphere itself or as N tangent planes (the god-object), "
            f"pushed into in {data['directions']} directions: the surface's error, the handle's "
            "depth and the tick's compute against N")
    sphere = next(r for r in data["rows"] if r["planes"] == 0)
    faceted = [r for r in data["rows"] if r["planes"] > 0]
    planes = [r["planes"] for r in faceted]
    written = []
    for extension in ("png", "pdf"):
        plt, _ = chart_style.pyplot()
        figure = chart_style.new_figure(plt, (7.0, 5.6))
        ax, ax_cost = figure.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1.3]})
        ax.plot(planes, [1e3 * r["surface_error_max_m"] for r in faceted], "o-",
                color="tab:blue", label="planes: the tool's distance from the true sphere "
                                        "(worst direction)")
        ax.plot(planes, [1e3 * r["handle_depth_mean_m"] for r in faceted], "s-",
                color="tab:red", label="planes: the handle's depth past the true sphere (mean)")
        ax.axhline(1e3 * sphere["handle_depth_mean_m"], color="tab:red", linestyle="--",
                   label="sphere primitive: the handle's depth (its surface error is "
                         f"{1e3 * sphere['surface_error_max_m']:.1g} mm)")
        ax.axhline(1e3 * data["coupling_give_m"], color="0.3", linestyle=":",
                   label=f"the coupling's give under the push, F/k_c = "
                         f"{1e3 * data['coupling_give_m']:.2f} mm")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylabel("distance (mm)")
        chart_style.grid(ax)
        ax_cost.plot(planes, [r["tick_compute_us_p50"] for r in faceted], "o-", color="0.2",
                     label="planes: the tick's compute (median)")
        ax_cost.axhline(sphere["tick_compute_us_p50"], color="0.2", linestyle="--",
                        label="sphere primitive: the tick's compute")
        ax_cost.set_ylabel("tick compute (us)")
        ax_cost.set_xlabel("tangent planes N")
        chart_style.grid(ax_cost)
        chart_style.save(figure, str(out_dir / f"scene-detail.{extension}"),
                         f"{what}. {caption}", legend_from=[ax, ax_cost])
        plt.close(figure)
        written.append(f"scene-detail.{extension}")
    return written
