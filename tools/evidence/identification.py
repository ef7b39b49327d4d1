"""Speed against accuracy: `haptic-tune identify` (the Ceres fit of m, b, F_c and F_0),
its parameter error and solve time against the log's length and the excitation's amplitude,
and the shooting-segment study behind its default segment length.

Both tables are bench/tune/identify_sweep's (docs/identification.md, "Accuracy and speed"),
on the tests' simulated pen display (tests/support/identification_sim_run.hpp: 10 um counts,
Coulomb friction, a force offset, white force noise), kept as it wrote them:

  sweep     identify_sweep: per log length and multisine amplitude, over seeds, the median
            |error| of m, b and F_c, the solve time (thread CPU) and how many runs the
            default options refuse (each run is fitted with the checks off too, so that the
            error shows where the defaults refuse);
  segments  identify_sweep --segments: per shooting-segment length and force noise, over
            seeds of the 10 s run, the spread of the estimates, the calibration of their
            standard errors (RMS z) and the residual.

The quick mode runs one seed of the sweep and two of the segment study (the same grid):
its medians are single runs, not the published ones.
"""

import json
import os

from context import EvidenceError

DEFAULT_AMPLITUDE_RMS_N = 1.0  # the tests' excitation (SimulatedRun::force_rms_n), 5 F_c
DEFAULT_SEGMENT_S = 0.02       # IdentificationOptions::segment_s (also in the sweep's table)
REQUIREMENT = {"mass": 0.02, "damping": 0.02, "coulomb": 0.10}  # relative, the issue's


def plan(quick):
    return {"sweep_seeds": 1, "segment_seeds": 2} if quick else \
        {"sweep_seeds": 5, "segment_seeds": 20}


def run(ctx):
    steps = plan(ctx.quick)
    load = os.getloadavg()  # the solve times are CPU times, but a shared machine slows them
    program = ctx.program("identify_sweep")
    scratch = ctx.scratch("identification")
    jobs = [("sweep", ["--seeds", str(steps["sweep_seeds"])]),
            ("segments", ["--segments", "--seeds", str(steps["segment_seeds"])])]

    def one(job):
        name, options = job
        path = scratch / f"identification-{name}.json"
        ctx.run([program, *options, "--out", str(path)], f"identify_sweep {' '.join(options)}",
                timeout_s=1800)
        try:
            with open(path, encoding="utf-8") as f:
                return json.load(f)
        except (OSError, ValueError) as error:
            raise EvidenceError(f"identify_sweep {' '.join(options)}: {path}: {error}") from error

    sweep, segments = ctx.parallel(one, jobs)
    if sweep.get("kind") != "identification-sweep" or \
            segments.get("kind") != "identification-segments":
        raise EvidenceError("identify_sweep wrote tables of the wrong kind")
    return {"device": describe_device(sweep["device"]),
            "default_amplitude_rms_n": DEFAULT_AMPLITUDE_RMS_N,
            "default_segment_s": sweep.get("segment_s", DEFAULT_SEGMENT_S),
            "requirement": REQUIREMENT, "load_average_1_5_15": list(load),
            "sweep": sweep, "segments": segments}


def describe_device(device):
    """The simulated device of identify_sweep's table, for the page and the captions."""
    return (f"pen display m = {device['mass']:g} kg, b = {device['damping']:g} N s/m, "
            f"F_c = {device['coulomb']:g} N, F_0 = {device['offset']:g} N, "
            f"{1e6 / device['counts_per_meter']:g} \u00b5m counts, "
            f"{device['force_noise_n']:g} N force noise, {device['rate_hz']:g} Hz")
