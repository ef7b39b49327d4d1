"""hapticd.Client against a real hapticd on the simulated device: every request of the
control protocol, its refusals as RequestRefused with the daemon's message, a recording with
marks read back with read_recording, and the telemetry stream as arrays."""

import os
import subprocess
import sys
import time
import unittest

import hapticd
from daemon_support import SOURCE_DIR, Daemon, ScratchDir


def wait_for(predicate, timeout_s=10.0):
    deadline = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError("not within the time")
        time.sleep(0.02)


class ClientAgainstTheDaemon(unittest.TestCase):
    def setUp(self):
        self.scratch = ScratchDir()
        self.directory = self.scratch.__enter__()
        self.daemon = Daemon(self.directory)
        self.client = hapticd.Client(self.daemon.socket)

    def tearDown(self):
        self.client.close()
        code = self.daemon.stop()
        self.scratch.__exit__(None, None, None)
        self.assertEqual(code, 0)

    def ticks_past(self, tick, ticks=3):
        wait_for(lambda: self.client.status()["tick"] >= tick + ticks)

    def test_status_disarm_arm_and_a_refused_coupling(self):
        status = self.client.status()
        self.assertEqual(status["coupling"]["stiffness"], 3600.0)
        self.assertIn(status["state"], ("arming", "running"))
        self.client.disarm()
        wait_for(lambda: self.client.status()["state"] == "disabled")
        self.assertEqual(self.client.arm(), "disabled")
        accepted = self.client.coupling(2000.0)
        self.assertIn("passive model", accepted["verdict"])
        with self.assertRaises(hapticd.RequestRefused) as refused:
            self.client.coupling(4500.0)
        self.assertTrue(str(refused.exception).startswith("coupling refused: "))
        self.assertIn("passive model", refused.exception.error)
        with self.assertRaises(hapticd.RequestRefused) as out_of_range:
            self.client.coupling(5e9)
        self.assertIn("stiffness = 5e+09 is out of range", out_of_range.exception.error)
        wait_for(lambda: self.client.status()["coupling"]["stiffness"] == 2000.0)

    def test_a_recording_with_marks_reads_back(self):
        started = self.client.record_start("take.csv")
        self.assertEqual(started["path"], os.path.join(self.directory, "take.csv"))
        self.ticks_past(started["first_tick"], 1)  # the file has rows before the first mark
        first = self.client.mark("trial A")
        self.ticks_past(self.client.status()["tick"])
        self.client.coupling(2000.0, 0.5)
        self.ticks_past(self.client.status()["tick"])
        last = self.client.mark("trial B")
        self.ticks_past(self.client.status()["tick"])
        stopped = self.client.record_stop()
        self.assertTrue(stopped["complete"])
        self.assertEqual((first, last), (1, 3))
        run = hapticd.read_recording(stopped["path"])
        self.assertEqual(len(run), stopped["records"])
        self.assertEqual(run.number("coupling_stiffness_n_per_m"), 3600.0)
        self.assertEqual([m.number for m in run.marks], [1, 2, 3])
        self.assertEqual(run.marks[0].text, "trial A")
        self.assertTrue(run.marks[1].text.startswith("coupling k_c 2000 N/m, b_c 0.5 N s/m; "))
        for mark in run.marks:
            self.assertEqual(run["mark"][mark.row], mark.number)
            self.assertEqual(run["mark"][mark.row - 1], mark.number - 1)
        self.assertEqual(set(run.trial(2)["mark"]), {2.0})
        # The example that loads a recording into numpy prints a line per trial.
        example = subprocess.run(
            [sys.executable, str(SOURCE_DIR / "examples" / "python" / "load_recording.py"),
             stopped["path"]], capture_output=True, text=True)
        self.assertEqual(example.returncode, 0, example.stderr)
        self.assertIn("k_c 3600 N/m, b_c 0 N s/m", example.stdout)
        for line in ("mark 0 (before the first mark): ", "mark 1 (trial A): ",
                     "mark 2 (coupling k_c 2000 N/m", "mark 3 (trial B): "):
            self.assertIn(line, example.stdout)
        refused = subprocess.run(
            [sys.executable, str(SOURCE_DIR / "examples" / "python" / "load_recording.py"),
             stopped["path"], "--axis", "3"], capture_output=True, text=True)
        self.assertEqual(refused.returncode, 2)
        self.assertIn("--axis 3: the file has axes 0..0", refused.stderr)

    def test_refusals_name_the_field(self):
        for text, says in [("", "empty"), ("x" * 201, "201 bytes"),
                           ("a\nb", "a control character at byte 2")]:
            with self.subTest(says), self.assertRaises(hapticd.RequestRefused) as refused:
                self.client.mark(text)
            self.assertIn(says, refused.exception.error)
        with self.assertRaises(hapticd.RequestRefused) as unknown:
            self.client.request("dance")
        self.assertIn('unknown request "dance"', unknown.exception.error)
        with self.assertRaises(hapticd.RequestRefused) as outside:
            self.client.record_start("/etc/passwd")
        self.assertIn("record_start refused", str(outside.exception))
        with self.assertRaises(ValueError):
            self.client.mark("x" * 5000)  # longer than any request line the daemon reads

    def test_the_stream_as_arrays(self):
        arrays = self.client.stream_arrays(100.0, 5)
        self.assertEqual(len(arrays["tick"]), 5)
        self.assertEqual(len(arrays["x_m"][0]), 1)
        ticks = list(arrays["tick"])
        self.assertEqual(ticks, sorted(ticks))
        self.assertEqual(self.client.status()["state"] in ("arming", "running"), True)


class ClientWithoutADaemon(unittest.TestCase):
    def test_an_absent_socket_is_a_connection_error(self):
        with ScratchDir() as directory:
            with self.assertRaises(hapticd.ConnectionLost) as lost:
                hapticd.Client(os.path.join(directory, "none.sock"))
        self.assertIn("none.sock: cannot connect", str(lost.exception))

    def test_arguments_are_checked(self):
        with self.assertRaises(ValueError):
            hapticd.Client()
        with self.assertRaises(ValueError):
            hapticd.Client("/x", instance="y")
        with self.assertRaises(ValueError):
            hapticd.instance_socket("../etc")
        self.assertEqual(hapticd.instance_socket("lab0"), "/run/hapticd/lab0.sock")


if __name__ == "__main__":
    sys.exit(unittest.main())
