"""hapticd.read_recording: the preamble, the marks with their rows, the columns, and a
refusal that names the line and the column; against a file written here and a log of the
real daemon."""

import math
import os
import subprocess
import sys
import unittest
from pathlib import Path

import hapticd
from daemon_support import HAPTICD_BIN, ScratchDir

SAMPLE = """# hapticd telemetry: the columns ... docs/daemon.md, "Telemetry"
# version: 0.1.0
# coupling_stiffness_n_per_m: 2000
# scene: wall (impedance, /etc/hapticd/wall.toml)
tick,t_s,x0_m,f0_n,mark
0,0,0.001,0.5,0
# mark 1: trial A
1,0.001,0.002,0.25,1
2,0.002,0.003,0,1
# mark 2: coupling k_c 1000 N/m, b_c 0 N s/m; passed
3,0.003,0.004,-0.25,2
"""


class ReadRecording(unittest.TestCase):
    def write(self, directory: str, text: str) -> str:
        path = os.path.join(directory, "run.csv")
        Path(path).write_text(text)
        return path

    def test_the_preamble_the_marks_and_the_columns(self):
        with ScratchDir() as directory:
            run = hapticd.read_recording(self.write(directory, SAMPLE))
        self.assertEqual(run.preamble["version"], "0.1.0")
        self.assertEqual(run.number("coupling_stiffness_n_per_m"), 2000.0)
        self.assertEqual(run.preamble["scene"], "wall (impedance, /etc/hapticd/wall.toml)")
        self.assertEqual(run.columns, ["tick", "t_s", "x0_m", "f0_n", "mark"])
        self.assertEqual(len(run), 4)
        self.assertEqual(run.axes, 1)
        self.assertEqual([(m.number, m.row, m.text) for m in run.marks],
                         [(1, 1, "trial A"),
                          (2, 3, "coupling k_c 1000 N/m, b_c 0 N s/m; passed")])
        self.assertEqual(list(run["x0_m"]), [0.001, 0.002, 0.003, 0.004])
        self.assertEqual(list(run.trial(1)["tick"]), [1.0, 2.0])
        with self.assertRaisesRegex(KeyError, "no column 'v0_mps'"):
            run["v0_mps"]

    def test_the_old_flags_column_reads_as_tick_flags(self):
        with ScratchDir() as directory:
            run = hapticd.read_recording(self.write(directory, "tick,t_s,flags\n0,0,8\n"))
        self.assertEqual(list(run["tick_flags"]), [8.0])

    def test_a_bad_file_is_refused_naming_the_line_and_column(self):
        cases = [("tick,t_s\n0,0\n1\n", ":3: 1 fields, but the header has 2"),
                 ("tick,t_s\n0,abc\n", ":2:2 (t_s): 'abc' is not a finite number"),
                 ("tick,t_s\n0,nan\n", ":2:2 (t_s): 'nan' is not a finite number"),
                 ("# only a comment\n", "no header row")]
        for text, says in cases:
            with self.subTest(says), ScratchDir() as directory:
                with self.assertRaises(hapticd.RecordingFormatError) as refused:
                    hapticd.read_recording(self.write(directory, text))
                self.assertIn(says, str(refused.exception))

    def test_a_log_of_the_daemon_reads_back_exactly(self):
        with ScratchDir() as directory:
            log = os.path.join(directory, "log.csv")
            done = subprocess.run([HAPTICD_BIN, "--no-status", "--lockstep", "--duration", "0.5",
                                   "--log", log], capture_output=True, text=True)
            self.assertEqual(done.returncode, 0, done.stderr)
            run = hapticd.read_recording(log)
        self.assertEqual(len(run), 500)
        self.assertEqual(run.number("rate_hz"), 1000.0)
        self.assertEqual(run.number("coupling_stiffness_n_per_m"), 3600.0)
        self.assertEqual(len(run.preamble["config_sha256"]), 64)
        self.assertIn("tick_flags", run.columns)
        self.assertNotIn("flags", run.columns)
        for tick, t_s in zip(run["tick"], run["t_s"]):  # the doubles nearest tick / rate
            self.assertEqual(t_s, tick / 1000.0)
        self.assertTrue(all(math.isfinite(t) and t > 1.7e9 for t in run["unix_time_s"]))


if __name__ == "__main__":
    sys.exit(unittest.main())
