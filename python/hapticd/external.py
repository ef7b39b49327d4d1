"""The world side of an external world's channel (docs/external-worlds.md): the shared memory
through which this process renders the virtual world of a daemon's [external] scene. The
environment is an admittance: the world reads the handle's state and the coupling's force
each step, and writes where its tool is.

    from hapticd import external
    with external.connect(instance="sim") as world:          # /run/hapticd/sim.world
        step = world.read()                                    # the daemon's last step
        world.write([max(step.handle_position_m[0], 0.0)])    # the tool, on the scene's axes

The layout is include/hapticd/env/external_world.h, version 1: little-endian numbers at pinned
offsets, two blocks with one writer each, each behind a sequence lock. Not for several threads
at once."""

from __future__ import annotations

import math
import mmap
import numbers
import os
import struct
import sys
import time
from dataclasses import dataclass
from typing import Any, Callable, List, Optional, Sequence, TextIO, Tuple

from hapticd.control import HapticdError, instance_socket

MAGIC = b"hapticdW"
VERSION = 1
#: The channel's size, and the mapping's.
SIZE = 4096

#: At 0, written once by the daemon: magic, version, size, axes, lockstep_every (0: free
#: running), rate_hz, stale_after_s, daemon_pid, closed; then reserved to 64.
HEADER = struct.Struct("<8sIIIIddiI")
HEADER_OFFSET = 0
CLOSED_OFFSET = 44
#: At 64, the daemon's block: sequence, step, answer_for (Q at 64, 72, 80); time_s, period_s,
#: stiffness_n_per_m, damping_n_s_per_m (d at 88..112); handle_position_m (3d at 120),
#: handle_velocity_mps (144), tool_position_m (168), coupling_force_n (192);
#: energy_removed_j (d at 216); state, reserved (I at 224, 228); update_in_force (Q at 232);
#: then reserved to 256.
TICK = struct.Struct("<QQQdddd3d3d3d3ddIIQ")
TICK_OFFSET = 64
#: At 256, the world's block: sequence, update, answers (Q at 256, 264, 272); world_time_s
#: (d at 280); tool_position_m (3d at 288); tool_velocity_mps (3d at 312); then reserved to 384.
UPDATE_OFFSET = 256
SEQUENCE = struct.Struct("<Q")
UPDATE_HEAD = struct.Struct("<QQd")        # update, answers, world_time_s: at 264
VECTOR = struct.Struct("<3d")              # tool_position_m at 288, tool_velocity_mps at 312

# The offsets the C header pins with static_assert (external_world.h), checked here once.
assert HEADER.size == 48 and struct.calcsize("<8sIIII") == 24                 # rate_hz
assert struct.calcsize("<8sIIIIddi") == CLOSED_OFFSET
assert TICK.size == 240 - TICK_OFFSET
assert struct.calcsize("<QQQdddd") == 120 - TICK_OFFSET                  # handle_position_m
assert struct.calcsize("<QQQdddd3d3d3d3d") == 216 - TICK_OFFSET          # energy_removed_j
assert struct.calcsize("<QQQdddd3d3d3d3ddII") == 232 - TICK_OFFSET       # update_in_force
assert UPDATE_OFFSET + SEQUENCE.size + UPDATE_HEAD.size == 288             # tool_position_m
assert 288 + VECTOR.size == 312 and 312 + VECTOR.size == 336               # tool_velocity_mps

#: hapticd_world_tick.state, by value.
STATES = ("waiting", "live", "stale")
#: How long read() retries a block the daemon is writing before it gives up.
READ_GIVE_UP_S = 1.0
#: The pause between two looks at the daemon's block while waiting for a step in lockstep.
POLL_S = 50e-6


class WorldError(HapticdError):
    """The channel could not be used: missing, not a channel of this version (the message
    names the path, the field, the value and what was expected), or no step came in time."""


class ChannelClosed(WorldError):
    """The daemon has let go of the channel (its `closed` flag), or the file at the path is no
    longer the one mapped (removed, or replaced by a daemon that started again): connect again."""


def channel_beside(socket_path: str) -> str:
    """The channel of the daemon serving `socket_path`: NAME.sock -> NAME.world, any other
    path + ".world" (the daemon's own rule)."""
    if socket_path.endswith(".sock"):
        return socket_path[:-len(".sock")] + ".world"
    return socket_path + ".world"


def channel_path(instance: str) -> str:
    """The channel of hapticd@NAME (/run/hapticd/NAME.world)."""
    return channel_beside(instance_socket(instance))


@dataclass(frozen=True)
class Step:
    """One step of the daemon's environment, as its block carried it. Vectors have 3
    components; those past the scene's axes are 0. Forces are on the tool, in newtons."""

    step: int                    #: the environment's steps since the channel began, from 1
    answer_for: int              #: lockstep: the step that waits for an answer; 0: none
    time_s: float                #: the servo's time at this step
    period_s: float              #: this step's interval T
    stiffness_n_per_m: float     #: the coupling's k_c in force
    damping_n_s_per_m: float     #: the coupling's b_c in force
    handle_position_m: Tuple[float, float, float]      #: x_d
    handle_velocity_mps: Tuple[float, float, float]    #: v_d, the backward difference
    tool_position_m: Tuple[float, float, float]        #: x_e as rendered at the step
    coupling_force_n: Tuple[float, float, float]       #: k_c (x_d - x_e) + b_c (v_d - v_e)
    energy_removed_j: float      #: what the passivity controller has taken, since start
    state: str                   #: "waiting" (no update yet), "live" or "stale"
    update_in_force: int         #: the world's update the step rendered (0: none)


class _NotYet(Exception):
    """connect(): the channel is not there (yet): try again until the deadline."""


def connect(path: Optional[str] = None, *, instance: Optional[str] = None,
            timeout_s: float = 5.0) -> "World":
    """Maps the channel at `path`, or hapticd@`instance`'s, waiting up to `timeout_s` for the
    daemon to create it (or to replace one it let go of). Raises WorldError naming the path,
    the field, its value and what was expected when the file is not a channel of version 1,
    ChannelClosed when the only one there stayed let go of."""
    if (path is None) == (instance is None):
        raise ValueError("give path or instance, not both or neither")
    if not (timeout_s >= 0.0 and math.isfinite(timeout_s)):
        raise ValueError(f"timeout_s = {timeout_s!r}: a finite number of seconds >= 0")
    where = path if path is not None else channel_path(instance or "")
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            return _open(where)
        except _NotYet as waiting:
            if time.monotonic() >= deadline:
                reason = str(waiting)
                if reason.startswith("closed"):
                    raise ChannelClosed(f"{where}: {reason}, and no new channel came within "
                                        f"{timeout_s:g} s") from None
                raise WorldError(f"{where}: {reason} (waited {timeout_s:g} s)") from None
        time.sleep(0.01)


def _open(path: str) -> "World":
    try:
        fd = os.open(path, os.O_RDWR | os.O_CLOEXEC)
    except FileNotFoundError:
        raise _NotYet("no channel: is hapticd running an [external] scene?") from None
    except PermissionError as error:
        # The daemon creates it, then gives it mode 0660 and its group: wait for that too.
        raise _NotYet(f"cannot open it to read and write: {error.strerror or error} (the "
                      f"channel is the group hapticd's: is this user in it?)") from None
    except OSError as error:
        raise WorldError(f"{path}: cannot open it to read and write: "
                         f"{error.strerror or error}") from None
    mapping: Optional[mmap.mmap] = None
    try:
        status = os.fstat(fd)
        if status.st_size < SIZE:
            # The daemon may be creating it: wait, and name the size if it stays short.
            raise _NotYet(f"the file is {status.st_size} bytes; a channel is {SIZE}")
        mapping = mmap.mmap(fd, SIZE, mmap.MAP_SHARED, mmap.PROT_READ | mmap.PROT_WRITE)
        world = World(path, mapping, (status.st_dev, status.st_ino))
        mapping = None
        return world
    finally:
        if mapping is not None:
            mapping.close()
        os.close(fd)     # the mapping keeps the file (and its inode number) alive


class World:
    """The world's end of one channel; connect() makes it. Use as a context manager, or call
    close(). Once the daemon has let go, read(), write(), wait_for_step() and answer() raise
    ChannelClosed, and run() returns. Not for several threads at once."""

    def __init__(self, path: str, mapping: mmap.mmap, identity: Tuple[int, int]):
        (magic, version, size, axes, lockstep_every, rate_hz, stale_after_s, daemon_pid,
         closed) = HEADER.unpack_from(mapping, HEADER_OFFSET)
        if magic == bytes(len(MAGIC)):
            raise _NotYet("the header is not written yet (no magic)")
        if magic != MAGIC:
            raise WorldError(f"{path}: magic = {magic!r}; a channel begins with {MAGIC!r}")
        checks = (("version", version, version == VERSION, f"this client reads version {VERSION}"),
                  ("size", size, size == SIZE, f"version {VERSION} channels are {SIZE} bytes"),
                  ("axes", axes, 1 <= axes <= 3, "1 to 3"),
                  ("rate_hz", rate_hz, rate_hz > 0.0 and math.isfinite(rate_hz),
                   "a finite rate > 0"))
        for name, value, right, expected in checks:
            if not right:
                # A 0 is a header the daemon is still writing (or never will): wait, then name it.
                if value == 0:
                    raise _NotYet(f"{name} = {value!r}; {expected}")
                raise WorldError(f"{path}: {name} = {value!r}; {expected}")
        if closed != 0:
            raise _NotYet(f"closed = {closed}: the daemon (pid {daemon_pid}) has let go of it")
        self._path = path
        self._map: Optional[mmap.mmap] = mapping
        self._identity = identity
        self._axes = int(axes)
        self._lockstep_every = int(lockstep_every)
        self._rate_hz = float(rate_hz)
        self._stale_after_s = float(stale_after_s)
        self._daemon_pid = int(daemon_pid)
        # A world that wrote here before may have died in the middle of a write (odd): this
        # one goes on from the next even number, so that its first write ends even.
        sequence = SEQUENCE.unpack_from(mapping, UPDATE_OFFSET)[0]
        self._sequence = sequence + (sequence & 1)
        self._update = 0
        self._answered = 0
        self._last_step: Optional[Step] = None

    def __enter__(self) -> "World":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Unmaps the channel (the daemon keeps it: it is the daemon's to remove)."""
        if self._map is not None:
            self._map.close()
            self._map = None

    # --- the header -----------------------------------------------------------------------
    @property
    def path(self) -> str:
        return self._path

    @property
    def axes(self) -> int:
        """The scene's axes, 1 to 3: a tool position has at most this many components."""
        return self._axes

    @property
    def rate_hz(self) -> float:
        """The servo's rate."""
        return self._rate_hz

    @property
    def lockstep_every(self) -> int:
        """0: free-running; N: the servo waits for the world's answer every N steps."""
        return self._lockstep_every

    @property
    def stale_after_s(self) -> float:
        """With no update for this long the daemon holds the tool and ramps the force to 0."""
        return self._stale_after_s

    @property
    def daemon_pid(self) -> int:
        """The daemon that created the channel."""
        return self._daemon_pid

    @property
    def closed(self) -> bool:
        """This World is closed, or the daemon has let go of the channel."""
        return self._map is None or self._let_go() is not None

    @property
    def updates(self) -> int:
        """The updates this World has written (the `update` of its last one)."""
        return self._update

    @property
    def last_step(self) -> Optional[Step]:
        """The Step read() returned last, or None before the first."""
        return self._last_step

    # --- the daemon's block ------------------------------------------------------------------
    def read(self) -> Step:
        """The daemon's block as of its last complete write (a sequence-lock read: a copy
        between two equal, even reads of its sequence). Raises ChannelClosed once the daemon
        has let go, WorldError when it stays in the middle of a write for READ_GIVE_UP_S."""
        mapping = self._open_map()
        give_up: Optional[float] = None
        while True:
            for _ in range(1000):
                before = SEQUENCE.unpack_from(mapping, TICK_OFFSET)[0]
                if before & 1:
                    continue
                values = TICK.unpack_from(mapping, TICK_OFFSET)
                if SEQUENCE.unpack_from(mapping, TICK_OFFSET)[0] == before == values[0]:
                    self._last_step = self._step(values)
                    return self._last_step
            now = time.monotonic()
            if give_up is None:
                give_up = now + READ_GIVE_UP_S
            elif now > give_up:
                raise WorldError(f"{self._path}: the daemon's block stayed in a write (sequence "
                                 f"{before}) for {READ_GIVE_UP_S:g} s")
            self._check_open()
            time.sleep(POLL_S)

    def _step(self, values: Tuple[Any, ...]) -> Step:
        state = values[20]
        if state >= len(STATES):
            raise WorldError(f"{self._path}: state = {state} at step {values[1]}; 0 (waiting), "
                             f"1 (live) or 2 (stale)")
        return Step(step=values[1], answer_for=values[2], time_s=values[3], period_s=values[4],
                    stiffness_n_per_m=values[5], damping_n_s_per_m=values[6],
                    handle_position_m=tuple(values[7:10]),
                    handle_velocity_mps=tuple(values[10:13]),
                    tool_position_m=tuple(values[13:16]), coupling_force_n=tuple(values[16:19]),
                    energy_removed_j=values[19], state=STATES[state],
                    update_in_force=values[22])

    # --- the world's block -------------------------------------------------------------------
    def write(self, tool_position_m: Sequence[float],
              tool_velocity_mps: Optional[Sequence[float]] = None, *,
              world_time_s: Optional[float] = None, answers: int = 0) -> int:
        """Publishes where the world's tool is (1 to `axes` components, the rest 0) and,
        optionally, its velocity (NaN when not given) and the world's clock. `answers`: in
        lockstep, the step this answers (answer() sets it). Returns the update's number."""
        position = self._vector("tool_position_m", tool_position_m, "m")
        velocity = (self._vector("tool_velocity_mps", tool_velocity_mps, "m/s")
                    if tool_velocity_mps is not None else [math.nan] * 3)
        if world_time_s is None:
            world_time = math.nan
        else:
            world_time = float(world_time_s)
            if not math.isfinite(world_time):
                raise ValueError(f"world_time_s = {world_time_s!r}: a finite number of seconds "
                                 f"(None: none)")
        if not (isinstance(answers, int) and answers >= 0):
            raise ValueError(f"answers = {answers!r}: a step number >= 0")
        mapping = self._open_map()
        self._update += 1
        # The sequence lock's write: odd, the payload, even again. Each pack_into is one C call
        # whose stores are done when it returns, and x86-64 (TSO) keeps stores in program
        # order, so the daemon sees the odd sequence before the payload and the payload before
        # the even one; on a little-endian host struct packs "<Q" with the native 8-byte copy.
        # The daemon checks every value it takes in any case.
        SEQUENCE.pack_into(mapping, UPDATE_OFFSET, self._sequence + 1)
        UPDATE_HEAD.pack_into(mapping, UPDATE_OFFSET + 8, self._update, answers, world_time)
        VECTOR.pack_into(mapping, UPDATE_OFFSET + 32, *position)
        VECTOR.pack_into(mapping, UPDATE_OFFSET + 56, *velocity)
        self._sequence += 2
        SEQUENCE.pack_into(mapping, UPDATE_OFFSET, self._sequence)
        return self._update

    def _vector(self, name: str, values: Sequence[float], unit: str) -> List[float]:
        wanted = "1 number" if self._axes == 1 else f"1 to {self._axes} numbers"
        if isinstance(values, (str, bytes)):
            raise ValueError(f"{name} = {values!r}: a sequence of {wanted}")
        try:
            components = [float(value) for value in values]
        except (TypeError, ValueError):
            raise ValueError(f"{name} = {values!r}: a sequence of {wanted}") from None
        if not 1 <= len(components) <= self._axes:
            raise ValueError(f"{name} has {len(components)} components; the scene has "
                             f"{self._axes} ax{'is' if self._axes == 1 else 'es'}")
        for axis, value in enumerate(components):
            if not math.isfinite(value):
                raise ValueError(f"{name}[{axis}] = {value!r}: a finite number of {unit}")
        return components + [0.0] * (3 - len(components))

    # --- lockstep ----------------------------------------------------------------------------
    def wait_for_step(self, timeout_s: float = 5.0) -> Step:
        """Lockstep: the next step that waits for this world's answer (answer_for later than
        the last one answered). Raises WorldError when the channel is not in lockstep or none
        comes within `timeout_s`, ChannelClosed when the daemon lets go."""
        if self._lockstep_every <= 0:
            raise WorldError(f"{self._path}: lockstep_every = {self._lockstep_every}: the "
                             f"channel is free-running; no step waits for an answer")
        if not (timeout_s >= 0.0 and math.isfinite(timeout_s)):
            raise ValueError(f"timeout_s = {timeout_s!r}: a finite number of seconds >= 0")
        deadline = time.monotonic() + timeout_s
        while True:
            step = self.read()          # raises ChannelClosed once the daemon lets go
            if step.answer_for != 0 and step.answer_for > self._answered:
                return step
            if time.monotonic() > deadline:
                raise WorldError(f"{self._path}: no step waited for an answer within "
                                 f"{timeout_s:g} s (the daemon's last: step {step.step} at "
                                 f"{step.time_s:g} s, {step.state}; answered up to "
                                 f"{self._answered}){self._daemon_gone()}")
            time.sleep(POLL_S)

    def answer(self, step: Step, tool_position_m: Sequence[float],
               tool_velocity_mps: Optional[Sequence[float]] = None, *,
               world_time_s: Optional[float] = None) -> int:
        """Lockstep: the tool's state that answers `step` (one wait_for_step returned)."""
        if step.answer_for == 0:
            raise ValueError(f"step {step.step} waits for no answer (answer_for = 0)")
        update = self.write(tool_position_m, tool_velocity_mps, world_time_s=world_time_s,
                            answers=step.answer_for)
        self._answered = max(self._answered, step.answer_for)
        return update

    # --- the loop ------------------------------------------------------------------------------
    def run(self, step_fn: Callable[[Step, float], Any], *, rate_hz: Optional[float] = None,
            duration_s: Optional[float] = None, timeout_s: float = 5.0) -> int:
        """The world's loop. `step_fn(step, dt_s)` returns the tool's position (a sequence of 1
        to `axes` numbers), or a tuple (position, velocity) of two sequences.

        In lockstep, each step that waits is answered with step_fn(step, lockstep_every *
        step.period_s), until `duration_s` of the daemon's time has passed since the first
        (that step answered too); `timeout_s` bounds each wait (WorldError). Free-running,
        every 1/`rate_hz` s of wall time on a fixed schedule, the last step is read and
        step_fn(step, 1/rate_hz) written, until `duration_s` of wall time (when step_fn
        overran whole periods, they are skipped and dt_s counts them). Either returns when the
        daemon lets go, or runs on until it does without `duration_s`. Returns the number of
        updates written."""
        if duration_s is not None and not (duration_s >= 0.0 and math.isfinite(duration_s)):
            raise ValueError(f"duration_s = {duration_s!r}: a finite number of seconds >= 0")
        written = 0
        world_time = 0.0
        try:
            if self._lockstep_every > 0:
                first: Optional[float] = None
                while True:
                    step = self.wait_for_step(timeout_s)
                    dt_s = self._lockstep_every * step.period_s
                    position, velocity = _tool_state(step_fn(step, dt_s))
                    world_time += dt_s
                    self.answer(step, position, velocity, world_time_s=world_time)
                    written += 1
                    first = step.time_s if first is None else first
                    if duration_s is not None and step.time_s - first >= duration_s:
                        return written
            if rate_hz is None:
                raise ValueError(f"{self._path} is free-running (lockstep_every = 0): run() "
                                 f"needs rate_hz")
            if not (rate_hz > 0.0 and math.isfinite(rate_hz)):
                raise ValueError(f"rate_hz = {rate_hz!r}: a finite rate > 0")
            period_s = 1.0 / rate_hz
            start = time.monotonic()
            slot, previous = 0, -1          # slot k is due at start + k * period_s
            while duration_s is None or time.monotonic() - start < duration_s:
                step = self.read()
                dt_s = (slot - previous) * period_s
                previous = slot
                position, velocity = _tool_state(step_fn(step, dt_s))
                world_time += dt_s
                self.write(position, velocity, world_time_s=world_time)
                written += 1
                # The next slot, or, when step_fn overran, the latest one already due (the
                # ones between are skipped: no burst of writes to catch up).
                now = time.monotonic()
                slot = max(slot + 1, math.floor((now - start) / period_s))
                pause = start + slot * period_s - now
                if pause > 0.0:
                    time.sleep(pause)
            return written
        except ChannelClosed:
            return written

    # --- the channel's state --------------------------------------------------------------------
    def _open_map(self) -> mmap.mmap:
        self._check_open()
        assert self._map is not None
        return self._map

    def _check_open(self) -> None:
        if self._map is None:
            raise WorldError(f"{self._path}: this World is closed")
        reason = self._let_go()
        if reason is not None:
            raise ChannelClosed(f"{self._path}: {reason}: connect again")

    def _daemon_gone(self) -> str:
        """", and the daemon (pid N) is gone" when no such process is left (only said: a
        world in another pid namespace may not see the daemon's pid)."""
        try:
            os.kill(self._daemon_pid, 0)
        except ProcessLookupError:
            return f"; the daemon (pid {self._daemon_pid}) is gone"
        except OSError:
            pass
        return ""

    def _let_go(self) -> Optional[str]:
        assert self._map is not None
        closed = struct.unpack_from("<I", self._map, CLOSED_OFFSET)[0]
        if closed != 0:
            return (f"the daemon (pid {self._daemon_pid}) has let go of the channel "
                    f"(closed = {closed})")
        try:
            status = os.stat(self._path)
        except FileNotFoundError:
            return "the channel has been removed"
        except OSError as error:
            return f"the channel cannot be looked at: {error.strerror or error}"
        if (status.st_dev, status.st_ino) != self._identity:
            return "the channel has been replaced (the daemon started again)"
        return None


def serve(make_step: Callable[["World"], Callable[[Step, float], Any]], *, name: str,
          path: Optional[str] = None, instance: Optional[str] = None,
          rate_hz: Optional[float] = None, duration_s: Optional[float] = None,
          out: Optional[TextIO] = None, err: Optional[TextIO] = None) -> int:
    """A world's whole life, for a script: connect (`path` or `instance`), run the step
    function `make_step(world)` returns with World.run() until the daemon lets go, the duration
    ends or Ctrl-C, then print on `out` "NAME: N updates written; the passivity controller
    removed E J" (standard output when `out` is None). Returns 0; 2 when the channel cannot be
    used or a step is refused (the reason on `err`, standard error when None, prefixed with
    NAME); 130 for a Ctrl-C before the world ran."""
    out = out if out is not None else sys.stdout
    err = err if err is not None else sys.stderr
    try:
        with connect(path, instance=instance) as world:
            try:
                world.run(make_step(world), rate_hz=rate_hz, duration_s=duration_s)
            except KeyboardInterrupt:
                pass
            last = world.last_step
            print(f"{name}: {world.updates} updates written; the passivity controller removed "
                  f"{last.energy_removed_j:.6g} J" if last is not None else
                  f"{name}: {world.updates} updates written; no step read", file=out)
    except (WorldError, ValueError) as error:
        print(f"{name}: {error}", file=err)
        return 2
    except KeyboardInterrupt:
        return 130
    return 0


def _tool_state(result: Any) -> Tuple[Sequence[float], Optional[Sequence[float]]]:
    """step_fn's result: a position, or (position, velocity) with both sequences."""
    if (isinstance(result, tuple) and len(result) == 2
            and not isinstance(result[0], numbers.Real)):
        return result[0], result[1]
    return result, None
