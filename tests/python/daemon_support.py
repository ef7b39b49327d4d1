"""What the Python client's tests share: the binaries under test (from the environment
CMake sets: HAPTICD_BIN, HAPTICD_SOURCE_DIR), a real-time hapticd on the simulated device
serving a control socket in a scratch directory, and a virtual-time (--lockstep) run of an
[external] scene with a world script as users run it."""

from __future__ import annotations

import json
import os
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Optional, Sequence

import hapticd

HAPTICD_BIN = os.environ["HAPTICD_BIN"]
SOURCE_DIR = Path(os.environ["HAPTICD_SOURCE_DIR"])
#: The interpreter the world scripts run with, as users run them (Debian's, as ctest's).
PYTHON = "/usr/bin/python3"
EXAMPLES = SOURCE_DIR / "examples" / "python"


def default_config(scene_file: Optional[str] = None, *, overrun_budget: bool = True) -> str:
    """config/hapticd.toml with its scene path absolute (the demo wall, or `scene_file`), and
    (`overrun_budget`) an overrun budget that a shared VM's stalls do not exhaust (these tests
    judge the client, not the host's timing)."""
    text = (SOURCE_DIR / "config" / "hapticd.toml").read_text()
    scene = 'file = "scenes/demo-wall.toml"'
    assert scene in text and "[safety]\n" in text
    if scene_file is None:
        scene_file = f"{SOURCE_DIR}/config/scenes/demo-wall.toml"
    text = text.replace(scene, f'file = "{scene_file}"')
    if not overrun_budget:
        return text
    return text.replace("[safety]\n", "[safety]\nmax_missed_periods = 1000\n"
                                      "max_consecutive_overruns = 1000\n", 1)


def world_environment() -> Dict[str, str]:
    """The environment a world script runs in: this tree's client on its PYTHONPATH."""
    environment = dict(os.environ)
    environment["PYTHONPATH"] = str(SOURCE_DIR / "python")
    environment["PYTHONDONTWRITEBYTECODE"] = "1"
    return environment


def wait_for_path(path: Path, process: subprocess.Popen, timeout_s: float = 60.0) -> bool:
    """Until `path` exists (True), or `process` has ended without making it (False); raises
    RuntimeError after `timeout_s` (a bound for a hung daemon, not a judgement of speed)."""
    deadline = time.monotonic() + timeout_s
    while not os.path.exists(path):
        if process.poll() is not None:
            return os.path.exists(path)
        if time.monotonic() > deadline:
            raise RuntimeError(f"{path} did not appear within {timeout_s:g} s")
        time.sleep(0.005)
    return True


@dataclass
class LockstepRun:
    """What run_lockstep() leaves: the daemon's exit code, its summary (None if it wrote
    none), its --log read back (None if none), its standard error, and the world's run."""

    code: int
    summary: Optional[Dict[str, Any]]
    recording: Optional[hapticd.Recording]
    messages: str
    world: Optional[subprocess.CompletedProcess]
    directory: Path

    def describe(self) -> str:
        """For a failed assertion: the daemon's and the world's messages."""
        world = ("no world run" if self.world is None else
                 f"world exit {self.world.returncode}: {self.world.stdout}{self.world.stderr}")
        return f"hapticd exit {self.code}: {self.messages}\n{world}"


def run_lockstep(directory: str, name: str, scene: str, world: Optional[Sequence[str]] = None,
                 *, duration_s: float = 6.0) -> LockstepRun:
    """hapticd --lockstep (virtual time) for `duration_s`, on config/hapticd.toml with the
    scene file `scene` (its text), serving a control socket in DIRECTORY/NAME (so its [external]
    channel is DIRECTORY/NAME/d.world), with --log and --summary there. `world`: a script and
    its arguments, run with PYTHON and `--channel CHANNEL` once the daemon has created the
    channel; the daemon's run ends at `duration_s` of its own time and the world's with it."""
    here = Path(directory) / name
    here.mkdir()
    scene_path = here / "scene.toml"
    scene_path.write_text(scene)
    config_path = here / "d.toml"
    config_path.write_text(default_config(str(scene_path), overrun_budget=False))
    channel = here / "d.world"
    summary = here / "summary.json"
    log = here / "log.csv"
    world_run: Optional[subprocess.CompletedProcess] = None
    with open(here / "d.err", "w") as errors:
        daemon = subprocess.Popen(
            [HAPTICD_BIN, "--lockstep", "--no-status", "--config", str(config_path),
             "--socket", str(here / "d.sock"), "--duration", repr(duration_s),
             "--log", str(log), "--summary", str(summary)],
            stdout=subprocess.DEVNULL, stderr=errors)
        try:
            if world is not None and wait_for_path(channel, daemon):
                world_run = subprocess.run(
                    [PYTHON, *world, "--channel", str(channel)], env=world_environment(),
                    stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=300)
            code = daemon.wait(timeout=300)
        finally:
            if daemon.poll() is None:
                daemon.kill()
                daemon.wait()
    return LockstepRun(
        code=code,
        summary=json.loads(summary.read_text()) if summary.exists() else None,
        recording=hapticd.read_recording(str(log)) if log.exists() else None,
        messages=(here / "d.err").read_text(), world=world_run, directory=here)


class Daemon:
    """hapticd in real time with --socket and --summary in `directory` (so that a client's
    recordings go there too) and any further `arguments` (--log FILE...), stopped with SIGTERM
    by stop()."""

    def __init__(self, directory: str, config: str | None = None,
                 arguments: Sequence[str] = ()):
        self.directory = Path(directory)
        self.socket = str(self.directory / "d.sock")
        config_path = self.directory / "d.toml"
        config_path.write_text(config if config is not None else default_config())
        self.summary = self.directory / "summary.json"
        self._err = open(self.directory / "d.err", "w")
        self.process = subprocess.Popen(
            [HAPTICD_BIN, "--no-status", "--config", str(config_path), "--socket", self.socket,
             "--summary", str(self.summary), *arguments],
            stdout=subprocess.DEVNULL, stderr=self._err)
        deadline = time.monotonic() + 30.0
        while not os.path.exists(self.socket):
            if self.process.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"hapticd did not serve {self.socket}: {self.messages()}")
            time.sleep(0.02)

    def messages(self) -> str:
        if not self._err.closed:
            self._err.flush()
        return (self.directory / "d.err").read_text()

    def stop(self) -> int:
        if self.process.poll() is None:
            self.process.terminate()
        code = self.process.wait(timeout=60)
        self._err.close()
        return code


class ScratchDir:
    def __enter__(self) -> str:
        self._dir = tempfile.TemporaryDirectory(prefix="hapticd-python-test-")
        return self._dir.name

    def __exit__(self, *exc: object) -> None:
        self._dir.cleanup()
