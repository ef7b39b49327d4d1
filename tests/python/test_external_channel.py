"""hapticd.external against a fake daemon written here (no hapticd): connect's refusals naming
the field and the value, the two sequence-locked blocks at their pinned offsets
(include/hapticd/env/external_world.h), ChannelClosed, lockstep's answers and run(), and the
examples' step functions (examples/python/external_*.py)."""

import contextlib
import io
import math
import mmap
import os
import struct
import subprocess
import sys
import tempfile
import threading
import time
import unittest
from pathlib import Path

import numpy

import hapticd
from hapticd import external

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples" / "python"))
import external_mass_spring  # noqa: E402
import external_nonpassive  # noqa: E402
import external_wall  # noqa: E402

# The C header's layout, written out again here on purpose (not taken from the module).
HEADER = "<8sIIIIddiI"           # at 0
TICK_BODY = "<QQdddd3d3d3d3ddIIQ"  # at 72, after the daemon block's sequence at 64
UPDATE = "<QQQd3d3d"             # at 256


class FakeDaemon:
    """The daemon's side of a channel file: the header, and its block written with the
    sequence lock; the world's block read back raw."""

    def __init__(self, path, *, axes=3, lockstep_every=0, rate_hz=1000.0, stale_after_s=0.05,
                 pid=4242, magic=b"hapticdW", version=1, size=4096, file_size=4096):
        self.path = path
        with open(path, "wb") as file:
            file.write(bytes(file_size))
        self.map = None
        if file_size >= 4096:
            fd = os.open(path, os.O_RDWR)
            self.map = mmap.mmap(fd, 4096)
            os.close(fd)
            struct.pack_into(HEADER, self.map, 0, magic, version, size, axes, lockstep_every,
                             rate_hz, stale_after_s, pid, 0)

    def publish(self, step=1, answer_for=0, time_s=0.001, period_s=0.001, k_c=2000.0, b_c=10.0,
                handle=(0.0, 0.0, 0.0), handle_v=(0.0, 0.0, 0.0), tool=(0.0, 0.0, 0.0),
                force=(0.0, 0.0, 0.0), energy_j=0.0, state=1, update_in_force=0):
        sequence = struct.unpack_from("<Q", self.map, 64)[0]
        struct.pack_into("<Q", self.map, 64, sequence + 1)
        struct.pack_into(TICK_BODY, self.map, 72, step, answer_for, time_s, period_s, k_c, b_c,
                         *handle, *handle_v, *tool, *force, energy_j, state, 0, update_in_force)
        struct.pack_into("<Q", self.map, 64, sequence + 2)

    def world_block(self):
        return struct.unpack_from(UPDATE, self.map, 256)

    def let_go(self):
        struct.pack_into("<I", self.map, 44, 1)

    def close(self):
        if self.map is not None:
            self.map.close()


def wait_until(predicate, timeout_s=5.0):
    deadline = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > deadline:
            return False
        time.sleep(1e-4)
    return True


class ChannelTest(unittest.TestCase):
    def setUp(self):
        self.scratch = tempfile.TemporaryDirectory(prefix="hapticd-python-test-")
        self.path = os.path.join(self.scratch.name, "d.world")
        self.daemons = []
        self.worlds = []

    def tearDown(self):
        for world in self.worlds:
            world.close()
        for daemon in self.daemons:
            daemon.close()
        self.scratch.cleanup()

    def daemon(self, **header):
        daemon = FakeDaemon(self.path, **header)
        self.daemons.append(daemon)
        return daemon

    def connect(self, timeout_s=1.0):
        world = external.connect(self.path, timeout_s=timeout_s)
        self.worlds.append(world)
        return world


class Connect(ChannelTest):
    def test_the_channel_beside_a_socket_and_of_an_instance(self):
        self.assertEqual(external.channel_beside("/run/hapticd/sim.sock"), "/run/hapticd/sim.world")
        self.assertEqual(external.channel_beside("/tmp/d"), "/tmp/d.world")
        self.assertEqual(hapticd.channel_path("lab0"), "/run/hapticd/lab0.world")
        with self.assertRaisesRegex(ValueError, "instance name 'a/b'"):
            hapticd.channel_path("a/b")
        with self.assertRaisesRegex(ValueError, "not both or neither"):
            external.connect()

    def test_the_header_reads_into_the_properties(self):
        self.daemon(axes=2, lockstep_every=4, rate_hz=2000.0, stale_after_s=0.025, pid=777)
        world = self.connect()
        self.assertEqual((world.axes, world.lockstep_every, world.rate_hz, world.stale_after_s,
                          world.daemon_pid, world.path, world.closed, world.updates,
                          world.last_step),
                         (2, 4, 2000.0, 0.025, 777, self.path, False, 0, None))

    def test_a_file_that_is_not_a_channel_is_refused_naming_the_field(self):
        cases = [({"magic": b"hapticdX"}, "magic = b'hapticdX'; a channel begins with b'hapticdW'"),
                 ({"version": 2}, "version = 2; this client reads version 1"),
                 ({"size": 8192}, "size = 8192; version 1 channels are 4096 bytes"),
                 ({"axes": 4}, "axes = 4; 1 to 3"),
                 ({"rate_hz": -1.0}, "rate_hz = -1.0; a finite rate > 0"),
                 ({"rate_hz": math.inf}, "rate_hz = inf; a finite rate > 0")]
        for header, says in cases:
            with self.subTest(says):
                daemon = FakeDaemon(self.path, **header)
                started = time.monotonic()
                with self.assertRaises(external.WorldError) as refused:
                    external.connect(self.path, timeout_s=5.0)
                daemon.close()
                self.assertEqual(str(refused.exception), f"{self.path}: {says}")
                self.assertLess(time.monotonic() - started, 1.0)   # no waiting for these

    def test_a_zero_field_is_waited_for_as_a_header_being_written_then_named(self):
        cases = [({"version": 0}, "version = 0; this client reads version 1"),
                 ({"size": 0}, "size = 0; version 1 channels are 4096 bytes"),
                 ({"axes": 0}, "axes = 0; 1 to 3"),
                 ({"rate_hz": 0.0}, "rate_hz = 0.0; a finite rate > 0")]
        for header, says in cases:
            with self.subTest(says):
                daemon = FakeDaemon(self.path, **header)
                with self.assertRaises(external.WorldError) as refused:
                    external.connect(self.path, timeout_s=0.05)
                daemon.close()
                self.assertEqual(str(refused.exception), f"{self.path}: {says} (waited 0.05 s)")
        # The rest of the header arrives within the wait: taken.
        daemon = self.daemon(axes=0)
        finish = threading.Timer(0.1, lambda: struct.pack_into("<I", daemon.map, 16, 2))
        finish.start()
        world = self.connect(timeout_s=5.0)
        finish.join()
        self.assertEqual(world.axes, 2)

    def test_a_short_a_blank_or_no_file_is_waited_for_then_named(self):
        with self.assertRaises(external.WorldError) as refused:
            external.connect(self.path, timeout_s=0.05)
        self.assertEqual(str(refused.exception), f"{self.path}: no channel: is hapticd running "
                                                 f"an [external] scene? (waited 0.05 s)")
        Path(self.path).write_bytes(bytes(100))
        with self.assertRaises(external.WorldError) as refused:
            external.connect(self.path, timeout_s=0.05)
        self.assertEqual(str(refused.exception), f"{self.path}: the file is 100 bytes; a channel "
                                                 f"is 4096 (waited 0.05 s)")
        Path(self.path).write_bytes(bytes(4096))
        with self.assertRaises(external.WorldError) as refused:
            external.connect(self.path, timeout_s=0.05)
        self.assertEqual(str(refused.exception), f"{self.path}: the header is not written yet "
                                                 f"(no magic) (waited 0.05 s)")
        # The magic written last, after the rest: waited for too.
        daemon = self.daemon(magic=bytes(8), axes=3)
        finish = threading.Timer(0.1, lambda: daemon.map.__setitem__(slice(0, 8), b"hapticdW"))
        finish.start()
        world = self.connect(timeout_s=5.0)
        finish.join()
        self.assertEqual(world.axes, 3)

    def test_a_channel_let_go_of_is_refused_and_a_new_one_taken(self):
        self.daemon(pid=99).let_go()
        with self.assertRaises(external.ChannelClosed) as refused:
            external.connect(self.path, timeout_s=0.05)
        self.assertIn("closed = 1: the daemon (pid 99) has let go of it, and no new channel "
                      "came within 0.05 s", str(refused.exception))
        replace = threading.Timer(0.1, lambda: self.daemon(pid=100))
        replace.start()
        world = self.connect(timeout_s=5.0)
        replace.join()
        self.assertEqual(world.daemon_pid, 100)

    def test_connect_waits_for_the_daemon_to_create_it(self):
        create = threading.Timer(0.1, lambda: self.daemon(axes=1))
        create.start()
        world = self.connect(timeout_s=5.0)
        create.join()
        self.assertEqual(world.axes, 1)


class Blocks(ChannelTest):
    def test_read_returns_the_daemons_block(self):
        daemon = self.daemon()
        world = self.connect()
        initial = world.read()
        self.assertEqual((initial.step, initial.state, initial.update_in_force), (0, "waiting", 0))
        for state, name in enumerate(("waiting", "live", "stale")):
            daemon.publish(step=7 + state, answer_for=3, time_s=0.125, period_s=0.001,
                           k_c=1500.0, b_c=2.5, handle=(0.01, -0.02, 0.03),
                           handle_v=(0.1, 0.2, -0.3), tool=(0.011, -0.021, 0.0),
                           force=(1.5, -2.0, 0.0), energy_j=0.0625, state=state,
                           update_in_force=41)
            step = world.read()
            self.assertEqual(step, external.Step(
                step=7 + state, answer_for=3, time_s=0.125, period_s=0.001,
                stiffness_n_per_m=1500.0, damping_n_s_per_m=2.5,
                handle_position_m=(0.01, -0.02, 0.03), handle_velocity_mps=(0.1, 0.2, -0.3),
                tool_position_m=(0.011, -0.021, 0.0), coupling_force_n=(1.5, -2.0, 0.0),
                energy_removed_j=0.0625, state=name, update_in_force=41))
            self.assertIs(world.last_step, step)

    def test_an_unknown_state_is_refused(self):
        daemon = self.daemon()
        world = self.connect()
        daemon.publish(step=5, state=3)
        with self.assertRaisesRegex(external.WorldError, "state = 3 at step 5; 0 .waiting."):
            world.read()

    def test_read_waits_out_a_write_and_gives_up_on_one_that_never_ends(self):
        daemon = self.daemon()
        world = self.connect()
        daemon.publish(step=1)
        struct.pack_into("<Q", daemon.map, 64, 3)                       # in a write
        struct.pack_into("<Q", daemon.map, 72, 2)
        finish = threading.Timer(0.05, lambda: struct.pack_into("<Q", daemon.map, 64, 4))
        finish.start()
        self.assertEqual(world.read().step, 2)
        finish.join()
        struct.pack_into("<Q", daemon.map, 64, 5)
        saved = external.READ_GIVE_UP_S
        external.READ_GIVE_UP_S = 0.05
        try:
            with self.assertRaisesRegex(external.WorldError, "stayed in a write .sequence 5."):
                world.read()
        finally:
            external.READ_GIVE_UP_S = saved

    def test_write_puts_the_values_at_the_pinned_offsets(self):
        daemon = self.daemon(axes=3)
        world = self.connect()
        self.assertEqual(world.write([0.01, -0.02, 0.03], (0.1, 0.2, 0.3), world_time_s=1.5,
                                     answers=12), 1)
        sequence, update, answers, world_time, *vectors = daemon.world_block()
        self.assertEqual((sequence, update, answers, world_time), (2, 1, 12, 1.5))
        self.assertEqual(vectors, [0.01, -0.02, 0.03, 0.1, 0.2, 0.3])
        # The same, field by field at the header's offsets.
        self.assertEqual(struct.unpack_from("<3d", daemon.map, 288), (0.01, -0.02, 0.03))
        self.assertEqual(struct.unpack_from("<3d", daemon.map, 312), (0.1, 0.2, 0.3))
        self.assertEqual(struct.unpack_from("<d", daemon.map, 280), (1.5,))
        self.assertEqual(bytes(daemon.map[336:384]), bytes(48))          # reserved untouched
        self.assertEqual(bytes(daemon.map[64:256]), bytes(192))          # the daemon's block too

        world.write(numpy.array([0.5, 0.25]))
        sequence, update, answers, world_time, *vectors = daemon.world_block()
        self.assertEqual((sequence, update, answers), (4, 2, 0))
        self.assertTrue(math.isnan(world_time))
        self.assertEqual(vectors[:3], [0.5, 0.25, 0.0])
        self.assertTrue(all(math.isnan(v) for v in vectors[3:]))
        self.assertEqual(world.updates, 2)

    def test_one_axis_pads_and_too_many_or_non_finite_are_refused(self):
        daemon = self.daemon(axes=1)
        world = self.connect()
        world.write((0.125,), [-0.5])
        self.assertEqual(daemon.world_block()[4:], (0.125, 0.0, 0.0, -0.5, 0.0, 0.0))
        refusals = [(([0.1, 0.2],), "tool_position_m has 2 components; the scene has 1 axis"),
                    (([],), "tool_position_m has 0 components"),
                    (([math.inf],), "tool_position_m[0] = inf: a finite number of m"),
                    (([math.nan],), "tool_position_m[0] = nan: a finite number of m"),
                    (([0.0], [math.nan]), "tool_velocity_mps[0] = nan: a finite number of m/s"),
                    ((0.1,), "tool_position_m = 0.1: a sequence of 1 number"),
                    (("1",), "tool_position_m = '1': a sequence")]
        for arguments, says in refusals:
            with self.subTest(says):
                with self.assertRaises(ValueError) as refused:
                    world.write(*arguments)
                self.assertIn(says, str(refused.exception))
        with self.assertRaisesRegex(ValueError, "world_time_s = inf"):
            world.write([0.0], world_time_s=math.inf)
        self.assertEqual(daemon.world_block()[:2], (2, 1))    # nothing written by a refusal

    def test_the_sequence_goes_on_from_a_world_that_died_mid_write(self):
        daemon = self.daemon()
        struct.pack_into("<QQ", daemon.map, 256, 7, 3)       # odd: a write never finished
        world = self.connect()
        world.write([0.0])
        self.assertEqual(daemon.world_block()[:2], (10, 1))
        world.write([0.0])
        self.assertEqual(daemon.world_block()[:2], (12, 2))


class Closed(ChannelTest):
    def assert_closed(self, world, says):
        self.assertTrue(world.closed)
        for operation in (world.read, lambda: world.write([0.0]), world.wait_for_step):
            with self.assertRaises(external.ChannelClosed) as closed:
                operation()
            self.assertIn(says, str(closed.exception))

    def test_the_daemon_lets_go(self):
        daemon = self.daemon(lockstep_every=1, pid=55)
        world = self.connect()
        daemon.let_go()
        self.assert_closed(world, "the daemon (pid 55) has let go of the channel (closed = 1)")

    def test_the_file_is_replaced_or_removed(self):
        self.daemon(lockstep_every=1)
        world = self.connect()
        os.unlink(self.path)
        self.assert_closed(world, "the channel has been removed")
        self.daemon(lockstep_every=1)          # a new daemon's channel at the same path
        self.assertEqual(Path(self.path).stat().st_size, 4096)
        self.assert_closed(world, "the channel has been replaced")

    def test_a_closed_world(self):
        self.daemon()
        world = self.connect()
        world.close()
        world.close()
        self.assertTrue(world.closed)
        with self.assertRaisesRegex(external.WorldError, "this World is closed"):
            world.read()


def serve_lockstep(daemon, steps, period_s, stop, seen, handle=lambda n: (0.0, 0.0, 0.0)):
    """The daemon in lockstep: publishes each step n of `steps` with answer_for = n, waits for
    the world block that answers it, and keeps (n, that block) in `seen`."""
    for n in steps:
        if stop.is_set():
            return
        daemon.publish(step=n, answer_for=n, time_s=n * period_s, period_s=period_s,
                       handle=handle(n), energy_j=n * 0.5)
        wait_until(lambda: daemon.world_block()[2] == n or stop.is_set())
        if daemon.world_block()[2] != n:       # the world stopped (it answered before `stop`)
            return
        seen.append((n, daemon.world_block()))


class Lockstep(ChannelTest):
    def serve(self, daemon, steps, period_s=0.001, handle=lambda n: (0.0, 0.0, 0.0)):
        stop, seen = threading.Event(), []
        thread = threading.Thread(target=serve_lockstep,
                                  args=(daemon, steps, period_s, stop, seen, handle), daemon=True)
        thread.start()
        return thread, stop, seen

    def test_free_running_waits_for_no_step(self):
        self.daemon(lockstep_every=0)
        world = self.connect()
        with self.assertRaisesRegex(external.WorldError, "lockstep_every = 0: the channel is "
                                                         "free-running"):
            world.wait_for_step()

    def test_each_step_that_waits_is_answered_once(self):
        daemon = self.daemon(lockstep_every=10, axes=2, pid=os.getpid())
        world = self.connect()
        thread, stop, seen = self.serve(daemon, [10, 20, 30, 40, 50],
                                        handle=lambda n: (n * 1e-3, -n * 1e-3, 0.0))
        for _ in range(5):
            step = world.wait_for_step(timeout_s=5.0)
            world.answer(step, [step.handle_position_m[0] + 1.0, step.handle_position_m[1]],
                         world_time_s=step.time_s)
        thread.join(5.0)
        self.assertEqual([n for n, _ in seen], [10, 20, 30, 40, 50])
        for update, (n, block) in enumerate(seen, start=1):
            self.assertEqual(block[1:7], (update, n, n * 0.001, n * 1e-3 + 1.0, -n * 1e-3, 0.0))
            self.assertEqual(block[0] % 2, 0)
        # Step 50 stays in the block: it has been answered, so it is not returned again.
        with self.assertRaises(external.WorldError) as waited:
            world.wait_for_step(timeout_s=0.05)
        self.assertEqual(str(waited.exception), f"{self.path}: no step waited for an answer "
                                                f"within 0.05 s (the daemon's last: step 50 at "
                                                f"0.05 s, live; answered up to 50)")
        with self.assertRaisesRegex(ValueError, "step 50 waits for no answer"):
            world.answer(external.Step(50, 0, 0.0, 0.0, 0.0, 0.0, (0.0,) * 3, (0.0,) * 3,
                                       (0.0,) * 3, (0.0,) * 3, 0.0, "live", 0), [0.0])

    def test_a_timeout_says_when_the_daemon_is_gone(self):
        gone = subprocess.Popen(["true"])
        gone.wait()                            # reaped: no process has its pid now
        self.daemon(lockstep_every=1, pid=gone.pid)
        world = self.connect()
        with self.assertRaises(external.WorldError) as waited:
            world.wait_for_step(timeout_s=0.01)
        self.assertTrue(str(waited.exception).endswith(
            f"answered up to 0); the daemon (pid {gone.pid}) is gone"), str(waited.exception))

    def test_the_daemon_letting_go_ends_a_wait(self):
        daemon = self.daemon(lockstep_every=1)
        world = self.connect()
        letting_go = threading.Timer(0.05, daemon.let_go)
        letting_go.start()
        with self.assertRaises(external.ChannelClosed):
            world.wait_for_step(timeout_s=5.0)
        letting_go.join()

    def test_run_stops_after_the_daemons_duration(self):
        period_s = 2.0 ** -10
        daemon = self.daemon(lockstep_every=4, axes=1)
        world = self.connect()
        thread, stop, seen = self.serve(daemon, range(4, 4000, 4), period_s,
                                        handle=lambda n: (n * 1e-4, 0.0, 0.0))
        calls = []

        def step_fn(step, dt_s):
            calls.append((step.step, dt_s))
            return [step.handle_position_m[0] * 2.0]

        written = world.run(step_fn, duration_s=10 * 4 * period_s)
        stop.set()
        thread.join(5.0)
        self.assertEqual(written, 11)                       # steps 4 to 44: 40 periods later
        self.assertEqual(calls, [(n, 4 * period_s) for n in range(4, 48, 4)])
        self.assertEqual(world.updates, 11)
        self.assertEqual([n for n, _ in seen], list(range(4, 48, 4)))
        last = daemon.world_block()
        self.assertEqual(last[1:5], (11, 44, 11 * 4 * period_s, 44 * 1e-4 * 2.0))

    def test_run_returns_when_the_daemon_lets_go(self):
        daemon = self.daemon(lockstep_every=1, axes=1)
        world = self.connect()
        thread, stop, seen = self.serve(daemon, range(1, 6))
        written = world.run(lambda step, dt_s: ([0.0], [0.0]) if step.step < 5 else
                            (daemon.let_go() or [0.0], [0.0]))
        stop.set()
        thread.join(5.0)
        self.assertEqual(written, 4)                         # step 5's answer found it closed
        self.assertEqual(daemon.world_block()[2], 4)


class FreeRunning(ChannelTest):
    def test_run_needs_a_rate(self):
        self.daemon()
        world = self.connect()
        with self.assertRaisesRegex(ValueError, "free-running .lockstep_every = 0.: run.. "
                                                "needs rate_hz"):
            world.run(lambda step, dt_s: [0.0])
        with self.assertRaisesRegex(ValueError, "rate_hz = -1"):
            world.run(lambda step, dt_s: [0.0], rate_hz=-1.0)

    def test_run_writes_on_a_fixed_schedule_for_the_duration(self):
        daemon = self.daemon(axes=2)
        daemon.publish(step=3, handle=(0.25, 0.5, 0.0))
        world = self.connect()
        steps = []
        started = time.monotonic()
        written = world.run(lambda step, dt_s: steps.append(dt_s) or
                            ([step.handle_position_m[0], 0.0], [1.0, 0.0]),
                            rate_hz=200.0, duration_s=0.1)
        elapsed = time.monotonic() - started
        self.assertGreaterEqual(elapsed, 0.1)
        self.assertLess(elapsed, 1.0)
        self.assertTrue(5 <= written <= 21, written)         # 20 slots; a loaded host skips some
        self.assertEqual(len(steps), written)
        self.assertEqual(steps[0], 0.005)
        for dt_s in steps:
            self.assertAlmostEqual(dt_s / 0.005, round(dt_s / 0.005), places=9)
        sequence, update, answers, world_time, *vectors = daemon.world_block()
        self.assertEqual((sequence, update, answers), (2 * written, written, 0))
        self.assertAlmostEqual(world_time, sum(steps), places=12)
        self.assertEqual(vectors, [0.25, 0.0, 0.0, 1.0, 0.0, 0.0])

    def test_run_returns_when_the_daemon_lets_go(self):
        daemon = self.daemon(axes=1)
        world = self.connect()
        letting_go = threading.Timer(0.05, daemon.let_go)
        letting_go.start()
        written = world.run(lambda step, dt_s: [0.0], rate_hz=1000.0)
        letting_go.join()
        self.assertGreater(written, 0)
        self.assertEqual(daemon.world_block()[1], written)


def energy_j(x, v, xd, *, m, k_s, k_c):
    return 0.5 * k_s * x * x + 0.5 * m * v * v + 0.5 * k_c * (xd - x) ** 2


class Examples(ChannelTest):
    def test_the_wall_projects_the_handle_onto_free_space(self):
        # Free space above (normal +1) ...
        self.assertEqual(external_wall.step([-0.01, 0.2, 0.3], 0.0, 1), [0.0, 0.2, 0.3])
        self.assertEqual(external_wall.step([0.05], 0.01, 1), [0.05])
        self.assertEqual(external_wall.step((0.005, -1.0), 0.01, 1), [0.01, -1.0])
        self.assertEqual(external_wall.step(numpy.array([-0.5, 0.0]), -0.25, 1), [-0.25, 0.0])
        # ... and below, the default (the demo wall's side).
        self.assertEqual(external_wall.step([0.004, 0.2]), [0.0, 0.2])
        self.assertEqual(external_wall.step([-0.02], 0.01), [-0.02])

    def test_the_walls_velocity_never_extrapolates_the_tool_through_the_wall(self):
        # In contact: at rest along the normal, the other axes the handle's.
        self.assertEqual(external_wall.tool_velocity([0.004, 0.0], [0.3, 0.2], 0.01), [0.0, 0.2])
        # Free, far from the wall: the handle's.
        self.assertEqual(external_wall.tool_velocity([-0.02], [0.1], 0.01), [0.1])
        self.assertEqual(external_wall.tool_velocity([-0.02], [-0.5], 0.01), [-0.5])
        # Free, 1 mm from it at 0.2 m/s: capped so that dt_s on it reaches the wall, no further.
        self.assertAlmostEqual(external_wall.tool_velocity([-0.001], [0.2], 0.01)[0], 0.1)
        self.assertAlmostEqual(external_wall.tool_velocity([0.011], [-0.2], 0.01, 0.01, 1)[0],
                               -0.1)

    def test_the_implicit_mass_spring_never_gains_energy(self):
        m, k_s, k_c, b_c, dt = 0.5, 100.0, 2000.0, 10.0, 0.01
        for b_s in (0.0, 1.0):
            with self.subTest(b_s=b_s):
                x, v, xd = 0.05, 0.3, 0.01
                energies = [energy_j(x, v, xd, m=m, k_s=k_s, k_c=k_c)]
                for _ in range(1000):
                    x, v = external_mass_spring.step(
                        x, v, xd, 0.0, dt, mass_kg=m, stiffness_n_per_m=k_s,
                        damping_n_s_per_m=b_s, coupling_stiffness_n_per_m=k_c,
                        coupling_damping_n_s_per_m=b_c)
                    energies.append(energy_j(x, v, xd, m=m, k_s=k_s, k_c=k_c))
                for before, after in zip(energies, energies[1:]):
                    self.assertLessEqual(after, before * (1.0 + 1e-12))
                # It settles where the two springs balance, with the least energy there.
                self.assertAlmostEqual(x, k_c * xd / (k_s + k_c), places=12)
                self.assertAlmostEqual(v, 0.0, places=12)
                self.assertAlmostEqual(energies[-1], 0.5 * k_s * k_c / (k_s + k_c) * xd * xd,
                                       places=12)
                self.assertLess(energies[-1], 0.01 * energies[0])

    def test_the_implicit_step_solves_backward_euler_exactly(self):
        m, k_s, b_s, k_c, b_c, dt = 0.5, 100.0, 1.0, 2000.0, 10.0, 0.01
        x0, v0, xd, vd = 0.02, -0.1, 0.03, 0.4
        x1, v1 = external_mass_spring.step(x0, v0, xd, vd, dt, mass_kg=m, stiffness_n_per_m=k_s,
                                           damping_n_s_per_m=b_s, coupling_stiffness_n_per_m=k_c,
                                           coupling_damping_n_s_per_m=b_c)
        self.assertAlmostEqual(x1, x0 + dt * v1, places=15)
        residual = m * (v1 - v0) / dt - (-k_s * x1 - b_s * v1 + k_c * (xd + vd * dt - x1)
                                         + b_c * (vd - v1))
        self.assertAlmostEqual(residual, 0.0, places=10)
        x1, v1 = external_mass_spring.step(x0, v0, xd, vd, dt, mass_kg=m, stiffness_n_per_m=k_s,
                                           damping_n_s_per_m=b_s, coupling_stiffness_n_per_m=k_c,
                                           coupling_damping_n_s_per_m=b_c, explicit=True)
        self.assertEqual(x1, x0 + dt * v0)
        self.assertAlmostEqual(v1, v0 + dt / m * (-k_s * x0 - b_s * v0 + k_c * (xd - x0)
                                                  + b_c * (vd - v0)), places=15)

    def test_the_nonpassive_world_gains_energy_on_its_own(self):
        m, k_s, dt = 0.5, 100.0, 0.01
        x, v = 0.01, 0.0
        energies = [energy_j(x, v, 0.0, m=m, k_s=k_s, k_c=0.0)]
        for _ in range(200):
            x, v = external_nonpassive.step(x, v, 0.0, 0.0, dt)        # b_s = -3, k_c = b_c = 0
            energies.append(energy_j(x, v, 0.0, m=m, k_s=k_s, k_c=0.0))
        for before, after in zip(energies, energies[1:]):
            self.assertGreaterEqual(after, before)
        self.assertGreater(energies[-1], 100.0 * energies[0])

    def test_the_mass_starts_at_rest_where_the_daemon_has_the_tool(self):
        model = external_mass_spring.MassSpring(2, 0.5, 100.0, 1.0)
        now = external.Step(1, 0, 0.001, 0.001, 0.0, 0.0, (0.1, 0.1, 0.0), (0.0,) * 3,
                            (0.04, -0.02, 0.0), (0.0,) * 3, 0.0, "waiting", 0)
        position, velocity = model(now, 0.01)
        self.assertEqual(len(position), 2)
        expected = [external_mass_spring.step(x0, 0.0, 0.1, 0.0, 0.01, mass_kg=0.5,
                                              stiffness_n_per_m=100.0, damping_n_s_per_m=1.0,
                                              coupling_stiffness_n_per_m=0.0,
                                              coupling_damping_n_s_per_m=0.0)
                    for x0 in (0.04, -0.02)]
        self.assertEqual(position, [x for x, _ in expected])
        self.assertEqual(velocity, [v for _, v in expected])

    def test_the_wall_example_against_a_lockstep_daemon(self):
        daemon = self.daemon(lockstep_every=1, axes=1)
        daemon.publish(step=0, energy_j=0.0)
        stop, seen = threading.Event(), []
        thread = threading.Thread(target=serve_lockstep, daemon=True,
                                  args=(daemon, range(1, 1000), 2.0 ** -10, stop, seen,
                                        lambda n: (-0.001 * n, 0.0, 0.0)))
        thread.start()
        output = io.StringIO()
        with contextlib.redirect_stdout(output):
            code = external_wall.main(["--channel", self.path, "--offset-m", "-0.005",
                                       "--normal", "1", "--duration-s", "0.009765625"])
        stop.set()
        thread.join(5.0)
        self.assertEqual(code, 0)
        self.assertEqual(output.getvalue(), "external_wall: 11 updates written; the passivity "
                                            "controller removed 5.5 J\n")
        self.assertEqual([block[4] for _, block in seen[:11]],
                         [max(-0.001 * n, -0.005) for n in range(1, 12)])

    def test_the_examples_run_free_and_refuse_a_bad_channel_and_bad_options(self):
        daemon = self.daemon(axes=1)
        output = io.StringIO()
        with contextlib.redirect_stdout(output):
            code = external_mass_spring.main(["--channel", self.path, "--rate-hz", "200",
                                              "--duration-s", "0.05"])
        self.assertEqual(code, 0)
        written = daemon.world_block()[1]
        self.assertGreater(written, 0)
        self.assertEqual(output.getvalue(), f"external_mass_spring: {written} updates written; "
                                            f"the passivity controller removed 0 J\n")
        daemon.close()
        self.daemon(version=2)
        errors = io.StringIO()
        with contextlib.redirect_stderr(errors):
            code = external_nonpassive.main(["--channel", self.path])
        self.assertEqual(code, 2)
        self.assertEqual(errors.getvalue(), f"external_nonpassive: {self.path}: version = 2; "
                                            f"this client reads version 1\n")
        with contextlib.redirect_stderr(errors), self.assertRaises(SystemExit) as refused:
            external_mass_spring.main(["--channel", self.path, "--damping-n-s-per-m", "-1"])
        self.assertEqual(refused.exception.code, 2)
        self.assertIn("--damping-n-s-per-m -1: >= 0", errors.getvalue())
        with contextlib.redirect_stderr(errors), self.assertRaises(SystemExit):
            external_wall.main(["--duration-s", "1"])
        self.assertIn("one of the arguments --instance --channel is required", errors.getvalue())

if __name__ == "__main__":
    unittest.main()
