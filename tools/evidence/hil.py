"""One point of a stability map: the unchanged daemon (hapticd --lockstep) on the simulated
pen display, pushed into a stiff penalty wall, and the handle's trajectory judged by
haptic-tune plot-run (the trajectory judge the HIL tests use, tune/oscillation.hpp).

The experiment is the HIL tests' wall contact (tests/support/wall_contact.hpp): a wall at
x = 0 with free space at x < 0, and a 100 N/m spring anchored 5 mm inside it, 0.5 N toward
the wall at its surface, so that an operator without a set-point of its own still rests on
the wall. The handle starts at rest on the wall's surface and the force switches on at once
(no soft-start ramp): the step and the encoder's quantisation excite the loop. A stable
loop settles into the encoder's dither; an unstable one grows from it until the handle
bounces off the wall (the wall only pushes).
"""

import dataclasses
import json
import math

# The sim's encoder at 1 nm, not the pen display's 10 um: a stiff grip holds the handle
# within a count of 10 um, and quantisation would hide its growth (no count ever changes).
COUNTS_PER_METER = 1e9
FLOOR_M = 3.0 / COUNTS_PER_METER       # dither up to 3 counts is quantisation
JUDGE_FROM_S = 0.2                     # the soft start's wait for a still handle ends
WINDOW_S = 0.05                        # >= 1.5 periods of the slowest oscillation (30 Hz)
GROWTH_LIMIT_PER_S = 0.5               # fitted growth above this: unstable
RISE_FACTOR = 10.0                     # ... or a rise from the floor by this much


@dataclasses.dataclass(frozen=True)
class Device:
    """The simulated device and what [device.model] says of it."""
    mass_kg: float = 0.1
    damping_n_s_per_m: float = 2.0
    rate_hz: float = 1000.0
    delay_s: float = 0.0          # the sim's loop delay, and [device.model] delay
    counts_per_meter: float = COUNTS_PER_METER

    def describe(self):
        delay = f", loop delay {self.delay_s * 1e3:.3g} ms" if self.delay_s > 0 else ""
        return (f"pen display m = {self.mass_kg:g} kg, b = {self.damping_n_s_per_m:g} N s/m, "
                f"{self.rate_hz:g} Hz, {1e9 / self.counts_per_meter:g} nm encoder counts{delay}")


@dataclasses.dataclass(frozen=True)
class Operator:
    """A passive human model of the sim (docs/sim-device.md)."""
    name: str
    label: str        # short, for a chart's axis
    description: str  # with its parameters, for the tables
    human_toml: str   # the keys of [device.sim.human]
    in_pen_grip_class: bool   # a member of config/operators/pen-grip.toml's class


def number(value):
    text = repr(float(value))
    return text if ("." in text or "e" in text or "n" in text) else text + ".0"


# The operators of the maps: the exact model's families (docs/stability-models.md), with the
# parameters the HIL tests hold the pen display with, and two adversaries no hand is.
OPERATORS = [
    Operator("hands-off", "hands-off", "hands-off", 'model = "hands-off"\n', False),
    Operator("light-hand", "light hand", "light hand 0.05 kg, 0.2 N s/m to ground",
             'model = "heavy-hand"\nhand_mass = 0.05\nhand_damping = 0.2\n', False),
    Operator("heavy-hand", "heavy hand", "heavy hand 0.3 kg, 0.5 N s/m to ground",
             'model = "heavy-hand"\nhand_mass = 0.3\nhand_damping = 0.5\n', False),
    Operator("stiff-grasp", "stiff grasp", "stiff grasp 0.3 kg, 500 N/m, 5 N s/m",
             'model = "stiff-grasp"\nhand_mass = 0.3\nhand_stiffness = 500.0\n'
             'hand_damping = 5.0\n', True),
    Operator("two-mass-grasp", "two-mass grasp",
             "two-mass grasp: skin 1000 N/m, 1 N s/m; hand 0.5 kg; arm 100 N/m, 10 N s/m",
             'model = "two-mass-grasp"\nhand_mass = 0.5\nskin_stiffness = 1000.0\n'
             'skin_damping = 1.0\narm_stiffness = 100.0\narm_damping = 10.0\n', False),
    # The lossless steel grip tuned to Nyquist: k_h = m (pi/T)^2, no hand mass, no damping.
    Operator("nyquist-grip", "Nyquist steel grip",
             "steel grip tuned to Nyquist: 987 kN/m, no mass, no damping (no hand)",
             'model = "stiff-grasp"\nhand_mass = 0.0\nhand_stiffness = '
             + number(0.1 * (math.pi * 1000.0) ** 2) + '\nhand_damping = 0.0\n', False),
    # Two modes on the first two odd harmonics of Nyquist, 500 and 1500 Hz, lossless.
    Operator("alias-grasp", "alias two-mode grasp",
             "two-mode grasp on 500 and 1500 Hz, the aliases of Nyquist, lossless (no hand)",
             'model = "two-mass-grasp"\nhand_mass = 0.946\nskin_stiffness = 7926000.0\n'
             'skin_damping = 0.0\narm_stiffness = 10464000.0\narm_damping = 0.0\n', False),
]


def wall_scene(wall_stiffness_n_per_m):
    return ('[scene]\nname = "evidence-wall"\naxes = 1\n'
            f'[[wall]]\nnormal = [-1.0]\noffset = 0.0\nstiffness = {number(wall_stiffness_n_per_m)}'
            '\ndamping = 0.0\n[[spring]]\nanchor = [0.005]\nstiffness = 100.0\n')


def daemon_config(device, operator, coupling):
    """hapticd's config: `coupling` is (k_c, b_c) or None for no coupling (the conventional
    design: the wall's force on the handle directly). The start-up check is off: the maps
    run gains past every bound on purpose."""
    if coupling is None:
        coupling_table = '[coupling]\nenabled = false\ncheck = "off"\n'
    else:
        coupling_table = (f"[coupling]\nstiffness = {number(coupling[0])}\n"
                          f'damping = {number(coupling[1])}\ncheck = "off"\n')
    delay = f"delay = {number(device.delay_s)}\n" if device.delay_s > 0 else ""
    return (f'[servo]\nrate_hz = {number(device.rate_hz)}\nrealtime = "off"\n'
            '[device]\nplugin = "sim"\naxes = 1\n'
            f"[device.model]\nmass = {number(device.mass_kg)}\n"
            f"damping = {number(device.damping_n_s_per_m)}\n{delay}"
            f"{coupling_table}"
            '[scene]\nfile = "scene.toml"\n'
            '[safety]\nmax_force = 20.0\nmax_speed = 1.0\nsoft_start_ramp = 0.0\n'
            'passivity = "observe"\n'
            f"[device.sim]\nmass = {number(device.mass_kg)}\n"
            f"damping = {number(device.damping_n_s_per_m)}\n"
            f"counts_per_meter = {number(device.counts_per_meter)}\nforce_limit = 20.0\n"
            f'clock = "lockstep"\ninitial_position = 0.0\n{delay}'
            f"[device.sim.human]\n{operator.human_toml}")


@dataclasses.dataclass(frozen=True)
class Point:
    device: Device
    operator: Operator
    coupling: object          # (k_c, b_c) or None
    wall_stiffness_n_per_m: float
    duration_s: float


def run_point(ctx, point, tag):
    """Runs one point; returns the judgement: growth_per_s (fitted over every window),
    rise_growth_per_s, peak_amplitude_m, faults, and `stable` (False when the fitted growth
    exceeds GROWTH_LIMIT_PER_S, or the oscillation rose from the floor by RISE_FACTOR)."""
    work = ctx.scratch(tag)
    (work / "cfg.toml").write_text(daemon_config(point.device, point.operator, point.coupling))
    (work / "scene.toml").write_text(wall_scene(point.wall_stiffness_n_per_m))
    log = work / "run.csv"
    ctx.run([ctx.program("hapticd"), "--lockstep", "--no-status", "--duration",
             number(point.duration_s), "--config", str(work / "cfg.toml"), "--log", str(log),
             "--summary", str(work / "summary.json")], f"hapticd for {tag}")
    judged = ctx.run_json([ctx.program("haptic-tune"), "plot-run", str(log), "--json",
                           "--from", number(JUDGE_FROM_S), "--window", number(WINDOW_S),
                           "--floor", number(FLOOR_M)], f"haptic-tune plot-run for {tag}")
    log.unlink()
    summary = json.loads((work / "summary.json").read_text())
    rose = judged["peak_amplitude_m"] >= RISE_FACTOR * FLOOR_M and judged["rise_growth_per_s"] > 0
    stable = judged["growth_per_s"] <= GROWTH_LIMIT_PER_S and not rose
    return {"growth_per_s": judged["growth_per_s"],
            "rise_growth_per_s": judged["rise_growth_per_s"],
            "peak_amplitude_m": judged["peak_amplitude_m"],
            "faults": [f["fault"] for f in judged["faults"]],
            "tick_compute_us_p50": summary["tick_compute_us"]["p50"],
            "stable": bool(stable)}
