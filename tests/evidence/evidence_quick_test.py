#!/usr/bin/python3
"""The evidence's quick mode end to end on this build (tools/evidence/make_evidence.py
--quick, into a scratch directory): every section writes its data and charts, the page
renders from them with every fact filled, and the closed-loop claims RESULTS.md makes hold
on the fresh runs:

  - the passive model's gains are stable for every operator the quick map runs;
  - the paper's gains are unstable hands-off (its hold (13) is optimistic);
  - the encoder model's gains are unstable for the steel grip tuned to Nyquist;
  - without a coupling the stiffest stable wall is within a grid step of 2b/T, and with the
    passive model's coupling every wall on the grid is stable;
  - the passive model is never optimistic about the loop delay;
  - at every servo rate the bisected limit, hands-off, is within a factor 2 of the passive
    model's 2b/T, and the paper's 8b/T is at or past the first unstable run;
  - the timing benches measured both programs under both loads, and an axis costs
    instructions;
  - identification: a longer log narrows the standard errors of m and b as the square root
    of its length and costs solve time; at the tests' excitation the error falls from the
    shortest log to the longest; at the longest log every excitation of 2.5 F_c or more
    meets the requirement (2 % for m and b, 10 % for F_c) and is accepted, and at F_c or
    less the handle sticks and every log is refused; at the default shooting segment the
    residual is the encoder's quantisation, and it grows with the segment under force noise.

    evidence_quick_test.py --build BUILD_DIR
"""

import argparse
import json
import pathlib
import shutil
import subprocess
import sys
import tempfile
import unittest

ROOT = pathlib.Path(__file__).resolve().parents[2]
BUILD = None
OUT = None


def setUpModule():
    global OUT
    OUT = pathlib.Path(tempfile.mkdtemp(prefix="hapticd-evidence-quick-"))
    done = subprocess.run([sys.executable, str(ROOT / "tools/evidence/make_evidence.py"),
                           "--quick", "--build", str(BUILD), "--out", str(OUT)],
                          capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"make_evidence.py --quick failed ({done.returncode}):\n"
                           f"{done.stdout}\n{done.stderr}")


def tearDownModule():
    shutil.rmtree(OUT, ignore_errors=True)


def section(name):
    with open(OUT / f"{name}.json", encoding="utf-8") as f:
        return json.load(f)


class EvidenceQuick(unittest.TestCase):
    def test_every_section_wrote_its_charts_and_the_page_is_whole(self):
        for name in ("stability-maps", "rate", "identification", "timing"):
            data = section(name)
            self.assertEqual(data["mode"], "quick")
            self.assertGreater(len(data["charts"]), 0, name)
            for chart in data["charts"]:
                path = OUT / chart
                self.assertTrue(path.is_file(), chart)
                self.assertGreater(path.stat().st_size, 1000, chart)
        page = (OUT / "RESULTS.md").read_text(encoding="utf-8")
        self.assertNotIn("{{", page)
        self.assertIn("| passive | 2,000 N/m |", page)

    def test_the_models_gains_against_the_operators(self):
        designs = {d["design"]: d for d in section("stability-maps")["operators"]["designs"]}
        self.assertEqual(designs["passive"]["unstable_for"], [])
        self.assertIn("hands-off", designs["paper"]["unstable_for"])
        self.assertIn("nyquist-grip", designs["encoder"]["unstable_for"])
        self.assertGreater(designs["paper"]["verdicts"]["hands-off"]["rise_growth_per_s"], 1.0)

    def test_the_coupling_makes_the_stiffest_wall_the_grids_stiffest(self):
        walls = section("stability-maps")["walls"]
        rows = {r["design"]: r for r in walls["rows"]}
        grid = walls["walls_n_per_m"]
        colgate = walls["colgate_bound_n_per_m"]
        step = grid[1] / grid[0]
        self.assertLessEqual(rows["none"]["stiffest_stable_wall_n_per_m"], colgate)
        self.assertGreater(rows["none"]["stiffest_stable_wall_n_per_m"], colgate / step)
        self.assertEqual(rows["passive"]["stiffest_stable_wall_n_per_m"], grid[-1])

    def test_the_passive_model_is_never_optimistic_about_the_delay(self):
        block = section("stability-maps")["delay"]
        for row in block["rows"]:
            limit = row["predicted_n_per_m"]["passive"]
            for k, verdict in zip(block["stiffness_n_per_m"], row["verdicts"]):
                if k <= limit:
                    self.assertTrue(verdict["stable"], (row["delay_periods"], k))

    def test_the_rate_buys_stiffness_as_the_passive_model_says(self):
        for row in section("rate")["rows"]:
            passive = row["predicted_n_per_m"]["passive"]
            self.assertAlmostEqual(passive, 4.0 * row["rate_hz"], delta=1e-6 * passive)  # 2b/T
            coupling = row["coupling"]
            self.assertIsNotNone(coupling["stiffest_stable_n_per_m"], row["rate_hz"])
            self.assertGreaterEqual(coupling["stiffest_stable_n_per_m"], 0.5 * passive)
            self.assertLessEqual(coupling["first_unstable_n_per_m"], 2.0 * passive)
            self.assertGreaterEqual(row["predicted_n_per_m"]["paper"],
                                    coupling["first_unstable_n_per_m"])

    def test_the_timing_benches_measured_both_programs_and_the_axes_cost(self):
        timing = section("timing")
        for load in ("idle", "stress"):
            for program in ("cyclictest", "hapticd"):
                p50 = timing["wake_latency"]["loads"][load]["programs"][program][
                    "wake_latency_us"]["p50"]
                self.assertIsNotNone(p50, (load, program))
                self.assertGreater(p50, 0.0)
        demo = {c["axes"]: c["instructions_per_tick"] for c in timing["instructions"]["configs"]
                if c["scene_name"] == "demo-wall"}
        self.assertLess(demo[1], demo[2])
        self.assertLess(demo[2], demo[3])
        self.assertGreater(timing["servo_tick"]["demo_wall_1axis"]["cpu_time_ns"], 0.0)



def identification_cells():
    block = section("identification")
    sweep = block["sweep"]
    cells = {(c["length_s"], c["amplitude_rms_n"]): c for c in sweep["cells"]}
    return block, sweep, cells


def median(values):
    values = sorted(values)
    n = len(values)
    return values[n // 2] if n % 2 else 0.5 * (values[n // 2 - 1] + values[n // 2])


class IdentificationQuick(unittest.TestCase):
    def test_a_longer_log_narrows_the_standard_errors_as_its_square_root(self):
        block, sweep, cells = identification_cells()
        shortest, longest = sweep["lengths_s"][0], sweep["lengths_s"][-1]
        amplitude = block["default_amplitude_rms_n"]
        expected = (longest / shortest) ** 0.5  # the information grows with the samples
        for name in ("mass", "damping"):
            short, long = (median(r[f"{name}_std_error"] for r in cells[(length, amplitude)]["runs"])
                           for length in (shortest, longest))
            self.assertGreater(short / long, 0.5 * expected, name)
            self.assertLess(short / long, 2.0 * expected, name)

    def test_at_the_tests_excitation_the_error_falls_as_the_log_grows(self):
        block, sweep, cells = identification_cells()
        amplitude = block["default_amplitude_rms_n"]

        def worst(length):
            cell = cells[(length, amplitude)]
            return max(cell["median_abs_mass_error"], cell["median_abs_damping_error"])
        self.assertLess(worst(sweep["lengths_s"][-1]), 0.5 * worst(sweep["lengths_s"][0]))

    def test_the_solve_time_grows_with_the_log(self):
        block, sweep, cells = identification_cells()
        amplitude = block["default_amplitude_rms_n"]
        shortest, longest = sweep["lengths_s"][0], sweep["lengths_s"][-1]
        short = cells[(shortest, amplitude)]["median_cpu_time_s"]
        long = cells[(longest, amplitude)]["median_cpu_time_s"]
        self.assertGreater(long, 0.25 * (longest / shortest) * short)

    def test_at_the_longest_log_enough_excitation_meets_the_requirement(self):
        block, sweep, cells = identification_cells()
        coulomb = sweep["device"]["coulomb"]
        longest = sweep["lengths_s"][-1]
        for amplitude in sweep["amplitudes_rms_n"]:
            if amplitude < 2.5 * coulomb:
                continue
            cell = cells[(longest, amplitude)]
            self.assertEqual(cell["refused_by_default"], 0, amplitude)
            for name, limit in block["requirement"].items():
                self.assertLess(cell[f"median_abs_{name}_error"], limit, (amplitude, name))

    def test_at_coulomb_friction_or_less_every_log_is_refused(self):
        _, sweep, cells = identification_cells()
        coulomb = sweep["device"]["coulomb"]
        for (length, amplitude), cell in cells.items():
            if amplitude <= coulomb:
                self.assertEqual(cell["refused_by_default"], sweep["seeds"], (length, amplitude))

    def test_the_default_segment_leaves_the_quantisation_and_longer_ones_drift(self):
        block = section("identification")
        rows = block["segments"]["rows"]
        for noise in sorted({r["force_noise_n"] for r in rows if r["force_noise_n"] > 0}):
            subset = sorted((r for r in rows if r["force_noise_n"] == noise),
                            key=lambda r: r["segment_s"])
            residual = [r["median_residual_rms_counts"] for r in subset]
            at_default = next(r["median_residual_rms_counts"] for r in subset
                              if r["segment_s"] == block["default_segment_s"])
            # Uniform quantisation: 1/sqrt(12) counts RMS.
            self.assertLess(abs(at_default - 12 ** -0.5), 0.15, noise)
            self.assertEqual(residual, sorted(residual), noise)
            self.assertGreater(residual[-1], 10.0 * residual[0], noise)


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--build", type=pathlib.Path, required=True)
    args, rest = parser.parse_known_args()
    BUILD = args.build
    unittest.main(argv=[sys.argv[0]] + rest, verbosity=2)
