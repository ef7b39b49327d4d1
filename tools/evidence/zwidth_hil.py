"""One run of the Z-width experiment: the unchanged daemon (hapticd --lockstep) on the
simulated pen display, held by a stiff grasp whose set-point steps, and what the hand felt
(felt_impedance.py).

The hand (the sim's stiff grasp: 0.3 kg on the handle, 500 N/m and 5 N s/m to its set-point)
holds the handle at rest; at `push_at_s` its set-point ramps by `step_m` over `ramp_s` and
stays. A ramp of two periods excites every frequency up to Nyquist but the ramp's own zeros
(multiples of 1/ramp_s); the run ends at rest, so the record holds the whole transient.

  free motion  the wall is 10 cm away: nothing in reach, the device's force stays zero and
               the hand feels the device alone, Z_min = m jω + b (24);
  contact      the handle starts 2 mm inside a wall that the hand keeps pressing on, and is
               pushed deeper: the hand feels the coupling in series with the wall, behind
               the hold and the loop delay, plus the device, Z_max (25) for a rigid wall.

The handle never leaves the wall (it is only pushed in), so the loop is linear in contact.
"""

import csv
import dataclasses
import json

import felt_impedance
import hil
from hil import number

HAND = (0.3, 500.0, 5.0)           # the stiff grasp of the maps: kg, N/m, N s/m
HAND_DESCRIPTION = "stiff grasp 0.3 kg, 500 N/m, 5 N s/m"
COUNTS_PER_METER = 1e10            # 0.1 nm: 1e-7 of the step
STEP_M = 0.001                     # the set-point's step (peak set-point speed 0.5 m/s)
RAMP_PERIODS = 2                   # the step's ramp, in periods: first zero at rate/2
CONTACT_DEPTH_M = 0.002            # where the handle starts inside the wall
FREE_WALL_DISTANCE_M = 0.1         # the wall in free motion: out of reach
REST_BEFORE_PUSH_S = 0.25          # the analysis starts this long before the push


@dataclasses.dataclass(frozen=True)
class Run:
    device: hil.Device
    coupling: tuple                   # (k_c, b_c)
    wall_stiffness_n_per_m: float
    in_contact: bool
    push_at_s: float                  # the set-point starts its ramp (after the settle)
    duration_s: float

    @property
    def ramp_s(self):
        return RAMP_PERIODS / self.device.rate_hz


def set_point_m(run, count):
    """The hand's set-point at samples 0..count-1: the sim's push profile (docs/sim-device.md),
    its corners on period boundaries."""
    period = 1.0 / run.device.rate_hz
    start = round(run.push_at_s * run.device.rate_hz)
    points = []
    for n in range(count):
        into = (n - start) * period
        points.append(STEP_M * min(max(into / run.ramp_s, 0.0), 1.0))
    return points


def operator(run):
    mass, stiffness, damping = HAND
    hold = run.duration_s + 1.0   # the set-point never returns within the run
    toml = (f'model = "stiff-grasp"\nhand_mass = {number(mass)}\n'
            f"hand_stiffness = {number(stiffness)}\nhand_damping = {number(damping)}\n"
            f"set_point = 0.0\npush = {{ to = {number(STEP_M)}, start = "
            f"{number(run.push_at_s)}, ramp = {number(run.ramp_s)}, hold = {number(hold)} }}\n")
    return hil.Operator("zwidth-grasp", "stiff grasp", HAND_DESCRIPTION, toml, True)


def scene(run):
    """A wall whose free space is x < -depth (contact: the handle at 0 starts inside it) or
    x < the free-motion distance (nothing in reach)."""
    offset = CONTACT_DEPTH_M if run.in_contact else -FREE_WALL_DISTANCE_M
    return ('[scene]\nname = "evidence-zwidth"\naxes = 1\n'
            f"[[wall]]\nnormal = [-1.0]\noffset = {number(offset)}\n"
            f"stiffness = {number(run.wall_stiffness_n_per_m)}\ndamping = 0.0\n")


def read_log(path):
    positions, forces = [], []
    with open(path, encoding="utf-8", newline="") as log:
        for row in csv.DictReader(line for line in log if not line.startswith("#")):
            positions.append(float(row["x0_m"]))
            forces.append(float(row["f0_n"]))
    return positions, forces


def execute(ctx, run, tag):
    """Runs the daemon; returns (positions m, forces N, the summary's faults)."""
    work = ctx.scratch(tag)
    device = dataclasses.replace(run.device, counts_per_meter=COUNTS_PER_METER)
    (work / "cfg.toml").write_text(hil.daemon_config(device, operator(run), run.coupling))
    (work / "scene.toml").write_text(scene(run))
    log = work / "run.csv"
    ctx.run([ctx.program("hapticd"), "--lockstep", "--no-status", "--duration",
             number(run.duration_s), "--config", str(work / "cfg.toml"), "--log", str(log),
             "--summary", str(work / "summary.json")], f"hapticd for {tag}")
    positions, forces = read_log(log)
    log.unlink()
    summary = json.loads((work / "summary.json").read_text())
    return positions, forces, summary["faults"]


def measure(ctx, run, tag, frequency_hz):
    """What the hand felt: Z_P at each frequency (hand side, and the device side's
    cross-check), the static stiffness between the rests before and after the push, and how
    still the handle was at both ends of the record."""
    positions, forces, faults = execute(ctx, run, tag)
    period = 1.0 / run.device.rate_hz
    push = round(run.push_at_s * run.device.rate_hz)
    first = push - round(REST_BEFORE_PUSH_S * run.device.rate_hz)
    x, f = positions[first:], forces[first:]
    s = set_point_m(run, len(positions))[first:]
    felt = felt_impedance.hand_side(x, s, frequency_hz, period, HAND)
    check = felt_impedance.device_side(x, f, frequency_hz, period, run.device.mass_kg,
                                       run.device.damping_n_s_per_m, run.device.delay_s)
    rest = round(0.05 * run.device.rate_hz)
    return {"frequency_hz": list(frequency_hz),
            "felt_real_n_s_per_m": [float(z.real) for z in felt],
            "felt_imag_n_s_per_m": [float(z.imag) for z in felt],
            "felt_magnitude_n_s_per_m": [float(abs(z)) for z in felt],
            "device_side_magnitude_n_s_per_m": [float(abs(z)) for z in check],
            "static_stiffness_n_per_m": float(felt_impedance.static_stiffness(
                x, f, push - first - 1, len(x) - 1)),
            "speed_at_start_mps": felt_impedance.largest_speed(x, period, 1, rest),
            "speed_at_end_mps": felt_impedance.largest_speed(x, period, len(x) - rest, len(x) - 1),
            "peak_speed_mps": felt_impedance.largest_speed(x, period, 1, len(x) - 1),
            "faults": faults}
