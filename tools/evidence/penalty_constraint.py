"""Penalty against constraint, the same flat wall: a penalty [[wall]] of stiffness K (the tool
sinks into it by F/K, in series with the coupling, (17)) or a god-object [[proxy_plane]] (the
tool stays on it), in the unchanged daemon on the simulated pen display, a stiff grasp pushing
the handle into it. At rest: the tool's depth (the wall's own error), the handle's depth (what
the hand feels: that plus the coupling's give) and the tick's compute."""

from hil import number
from scene_detail import HOLD_S, RAMP_S, SETTLED_S, grasp, pen_config, run_hapticd

START_M = -0.005       # the handle starts 5 mm before the wall, in free space
PUSH_TO_M = 0.010      # the grasp's set-point 10 mm past it
PENALTY_WALLS_N_PER_M = [2e4, 1e5, 1e6, 1e7]


def scene(wall_n_per_m):
    text = '[scene]\nname = "evidence-flat-wall"\naxes = 1\n'
    if wall_n_per_m is None:
        return text + "[[proxy_plane]]\nnormal = [-1.0]\noffset = 0.0\n"
    return text + (f"[[wall]]\nnormal = [-1.0]\noffset = 0.0\nstiffness = {number(wall_n_per_m)}"
                   "\ndamping = 0.0\n")


def config(duration_s):
    return pen_config(1, number(START_M), grasp(PUSH_TO_M, duration_s, "[device.sim.human]"))


def one_run(ctx, wall_n_per_m):
    tag = "constraint" if wall_n_per_m is None else f"penalty-{wall_n_per_m:g}"
    duration_s = 0.3 + RAMP_S + HOLD_S
    columns, summary = run_hapticd(ctx, ctx.scratch(f"flat-{tag}"), config(duration_s),
                                   scene(wall_n_per_m), duration_s, f"the flat wall ({tag})")
    settled = [i for i, t in enumerate(columns["t_s"]) if t >= duration_s - SETTLED_S]

    def mean(name):
        return sum(columns[name][i] for i in settled) / len(settled)
    return {"wall": "constraint" if wall_n_per_m is None else "penalty",
            "wall_n_per_m": wall_n_per_m,
            "tool_depth_m": mean("xe0_m"), "handle_depth_m": mean("x0_m"),
            "force_n": -mean("f0_n"),
            "tick_compute_us_p50": summary["tick_compute_us"]["p50"],
            "solver_not_converged": summary["solver_not_converged"]}


def run(ctx):
    walls = PENALTY_WALLS_N_PER_M[::3] if ctx.quick else PENALTY_WALLS_N_PER_M
    return ctx.parallel(lambda wall: one_run(ctx, wall), walls + [None])
