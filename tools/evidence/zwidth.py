"""Speed against accuracy: the Z-width, the range of impedances the hand can feel, from
theory beside what the hand feels in closed loop with the unchanged daemon (zwidth_hil.py).

  theory   haptic-tune zwidth: |Z_min| (24), the device alone, and |Z_max| (25), the device
           plus the coupling behind the hold and the loop delay against a rigid wall, per
           stability model (their hold terms differ: docs/stability-models.md)
  HIL      the impedance the hand feels, F_h/v_h, at frequencies of the theory's grid: in
           free motion (nothing in reach) and pressing on a 1e7 N/m wall, for each coupling
           stiffness, with no loop delay and with one period; and the static stiffness the
           hand is held with, on that wall and on a soft one (the coupling in series with the
           wall: k_c K/(k_c + K))

What the physics says the fits should find: in free motion the device's m and b; in
contact the series stiffness, and a damping of b + b_c - k_c (T/2 + D): the spring's force
acts half a period late on average behind the zero-order hold and D later with a loop delay,
and a spring k late by τ is k/(jω) e^{-jωτ} ~ k/(jω) - k τ, a negative damping. The paper's
hold (13), (1/2)(1 + z^{-1}), cancels the half period against the lead of the integrator in
(16) and predicts b + b_c - k_c D.
"""

import designs as design_models
import felt_impedance
import hil
import zwidth_hil
from hil import number

MODELS = ("paper", "encoder", "passive")
COUPLING_DAMPING = 1.0       # N s/m
RIGID_WALL = 1e7             # N/m, the scenes' upper limit: (25)'s rigid environment
SOFT_WALL = 2000.0           # N/m, where the series k_c K/(k_c + K) is far from k_c
BAND_HZ = (0.3, 100.0)       # HIL frequencies: above the ramp's zero, where the free-motion
                             # run measures the method's own error (aliasing) below 0.5 %
FIT_MAX_HZ = 30.0            # the mass-damper-spring fit: where (25) is that to 1e-3


def plan(quick):
    """The force comes on at once with the handle 2 mm inside the wall; the slowest contact
    (k_c = 2000 N/m behind a period of delay, damped by the hand alone) is back to a count
    per period in about 3 s, when the push starts."""
    if quick:
        return {"couplings": [500.0, 2000.0], "theory_points": 201, "stride": 8,
                "push_at_s": 3.0, "after_push_s": 3.0}
    return {"couplings": [500.0, 1000.0, 2000.0], "theory_points": 401, "stride": 16,
            "push_at_s": 3.0, "after_push_s": 4.0}


def theory(ctx, device, stiffness, points):
    """haptic-tune zwidth's answer for the coupling (stiffness, COUPLING_DAMPING)."""
    args = [ctx.program("haptic-tune"), "zwidth", "--mass", number(device.mass_kg),
            "--damping", number(device.damping_n_s_per_m), "--rate", number(device.rate_hz),
            "--stiffness", number(stiffness), "--coupling-damping", number(COUPLING_DAMPING),
            "--delay", number(device.delay_s), "--points", str(points), "--json"]
    return ctx.run_json(args, f"haptic-tune zwidth (k_c = {stiffness:g} N/m)")


def band_indices(frequency_hz, stride):
    """Every stride-th point of the theory's grid within BAND_HZ: the HIL frequencies (the
    same in the quick and the full mode, whose grids are 2:1)."""
    return [i for i, f in enumerate(frequency_hz)
            if i % stride == 0 and BAND_HZ[0] <= f <= BAND_HZ[1]]


def curve(values):
    """A theory curve for the chart, to 6 digits (the comparisons use the full values)."""
    return [float(f"{v:.6g}") for v in values]


def relative_deviation(measured, predicted):
    return [m / p - 1.0 for m, p in zip(measured, predicted)]


def fit(measured):
    low = [i for i, f in enumerate(measured["frequency_hz"]) if f <= FIT_MAX_HZ]
    impedance = [complex(measured["felt_real_n_s_per_m"][i], measured["felt_imag_n_s_per_m"][i])
                 for i in low]
    stiffness, damping, mass = felt_impedance.fit_mass_damper_spring(
        [measured["frequency_hz"][i] for i in low], impedance)
    return {"stiffness_n_per_m": stiffness, "damping_n_s_per_m": damping, "mass_kg": mass}


def expected_contact(device, stiffness, wall):
    period = 1.0 / device.rate_hz
    base = device.damping_n_s_per_m + COUPLING_DAMPING
    return {"series_stiffness_n_per_m": stiffness * wall / (stiffness + wall),
            "damping_n_s_per_m": base - stiffness * (period / 2.0 + device.delay_s),
            "paper_damping_n_s_per_m": base - stiffness * device.delay_s,
            "mass_kg": device.mass_kg}


def least_passive_zmax(answer, grid):
    """The index of the grid point in the band where the passive model's |Z_max| is least:
    the contact resonance, where the felt impedance is its damping alone."""
    zmax = answer["models"]["passive"]["zmax_magnitude"]
    inside = [i for i, f in enumerate(grid) if BAND_HZ[0] <= f <= BAND_HZ[1]]
    return min(inside, key=lambda i: zmax[i])


def free_motion(measured, answer, band):
    zmin = [answer["models"][m]["zmin_magnitude"] for m in MODELS]
    at_points = {m: [z[i] for i in band] for m, z in zip(MODELS, zmin)}
    measured.update({"fit": fit(measured), "zmin_at_points": at_points,
                     "deviation_from_zmin": {m: relative_deviation(
                         measured["felt_magnitude_n_s_per_m"], at_points[m]) for m in MODELS}})
    return measured


def rigid_contact(measured, answer, band, dip, device, stiffness):
    """The contact run's block; its last frequency is the resonance's (`dip`)."""
    zmax = {m: answer["models"][m]["zmax_magnitude"] for m in MODELS}
    dip_felt = measured["felt_magnitude_n_s_per_m"][-1]
    for key in ("frequency_hz", "felt_real_n_s_per_m", "felt_imag_n_s_per_m",
                "felt_magnitude_n_s_per_m", "device_side_magnitude_n_s_per_m"):
        measured[key] = measured[key][:-1]
    at_points = {m: [zmax[m][i] for i in band] for m in MODELS}
    measured.update({
        "coupling_stiffness_n_per_m": stiffness, "wall_stiffness_n_per_m": RIGID_WALL,
        "expected": expected_contact(device, stiffness, RIGID_WALL), "fit": fit(measured),
        "zmax_at_points": at_points,
        "deviation_from_zmax": {m: relative_deviation(
            measured["felt_magnitude_n_s_per_m"], at_points[m]) for m in MODELS},
        "dip": {"frequency_hz": answer["frequency_hz"][dip], "felt_magnitude_n_s_per_m": dip_felt,
                "zmax_magnitude_n_s_per_m": {m: zmax[m][dip] for m in MODELS}},
        "theory_zmax_n_s_per_m": {m: curve(zmax[m]) for m in MODELS}})
    return measured


def soft_contact(measured, stiffness):
    keep = ("static_stiffness_n_per_m", "speed_at_start_mps", "speed_at_end_mps",
            "peak_speed_mps", "faults")
    return {"coupling_stiffness_n_per_m": stiffness, "wall_stiffness_n_per_m": SOFT_WALL,
            "series_stiffness_n_per_m": stiffness * SOFT_WALL / (stiffness + SOFT_WALL),
            **{key: measured[key] for key in keep}}


def one_delay(ctx, steps, delay_periods):
    device = hil.Device(delay_s=delay_periods / hil.Device().rate_hz)
    couplings = steps["couplings"]
    answers = [theory(ctx, device, k, steps["theory_points"]) for k in couplings]
    grid = answers[0]["frequency_hz"]
    band = band_indices(grid, steps["stride"])
    points = [grid[i] for i in band]
    dips = [least_passive_zmax(answer, grid) for answer in answers]
    duration = steps["push_at_s"] + steps["after_push_s"]

    def run_of(stiffness, wall, contact):
        return zwidth_hil.Run(device, (stiffness, COUPLING_DAMPING), wall, contact,
                              steps["push_at_s"], duration)

    # In free motion the coupling carries no force (the tool follows the handle): any k_c.
    jobs = [("free", run_of(couplings[0], RIGID_WALL, False), points)]
    jobs += [(f"rigid-{k:g}", run_of(k, RIGID_WALL, True), points + [grid[d]])
             for k, d in zip(couplings, dips)]
    jobs += [(f"soft-{k:g}", run_of(k, SOFT_WALL, True), points) for k in couplings]
    tag = f"zwidth-delay-{delay_periods:g}"
    measured = ctx.parallel(lambda job: zwidth_hil.measure(ctx, job[1], f"{tag}-{job[0]}",
                                                           job[2]), jobs)
    rigid, soft = measured[1:1 + len(couplings)], measured[1 + len(couplings):]
    passive = design_models.Design("passive", "", "", ())
    return {"delay_s": device.delay_s, "delay_periods": delay_periods,
            "passive_stiffness_n_per_m": design_models.sized_stiffness(
                ctx, device, passive, COUPLING_DAMPING),
            "theory_frequency_hz": curve(grid),
            "theory_zmin_n_s_per_m": {m: curve(answers[0]["models"][m]["zmin_magnitude"])
                                      for m in MODELS},
            "free": free_motion(measured[0], answers[0], band),
            "contact": [rigid_contact(block, answer, band, dip, device, k)
                        for k, answer, dip, block in zip(couplings, answers, dips, rigid)],
            "soft_wall": [soft_contact(block, k) for k, block in zip(couplings, soft)]}


def run(ctx):
    steps = plan(ctx.quick)
    rows = [one_delay(ctx, steps, d) for d in (0.0, 1.0)]
    device = hil.Device(counts_per_meter=zwidth_hil.COUNTS_PER_METER)
    return {"device": device.describe(), "hand": zwidth_hil.HAND_DESCRIPTION,
            "coupling_damping_n_s_per_m": COUPLING_DAMPING, "rigid_wall_n_per_m": RIGID_WALL,
            "soft_wall_n_per_m": SOFT_WALL, "step_m": zwidth_hil.STEP_M,
            "ramp_s": zwidth_hil.RAMP_PERIODS / device.rate_hz,
            "push_at_s": steps["push_at_s"], "after_push_s": steps["after_push_s"],
            "band_hz": list(BAND_HZ), "fit_max_hz": FIT_MAX_HZ, "models": list(MODELS),
            "couplings_n_per_m": steps["couplings"], "delays": rows}
