"""What the Python client's tests share: the binaries under test (from the environment
CMake sets: HAPTICD_BIN, HAPTICD_SOURCE_DIR) and a real-time hapticd on the simulated device
serving a control socket in a scratch directory."""

from __future__ import annotations

import os
import subprocess
import tempfile
import time
from pathlib import Path

HAPTICD_BIN = os.environ["HAPTICD_BIN"]
SOURCE_DIR = Path(os.environ["HAPTICD_SOURCE_DIR"])


def default_config() -> str:
    """config/hapticd.toml with its scene path absolute, and an overrun budget that a shared
    VM's stalls do not exhaust (these tests judge the client, not the host's timing)."""
    text = (SOURCE_DIR / "config" / "hapticd.toml").read_text()
    scene = 'file = "scenes/demo-wall.toml"'
    assert scene in text and "[safety]\n" in text
    text = text.replace(scene, f'file = "{SOURCE_DIR}/config/scenes/demo-wall.toml"')
    return text.replace("[safety]\n", "[safety]\nmax_missed_periods = 1000\n"
                                      "max_consecutive_overruns = 1000\n", 1)


class Daemon:
    """hapticd in real time with --socket and --summary in `directory` (so that a client's
    recordings go there too), stopped with SIGTERM by stop()."""

    def __init__(self, directory: str, config: str | None = None):
        self.directory = Path(directory)
        self.socket = str(self.directory / "d.sock")
        config_path = self.directory / "d.toml"
        config_path.write_text(config if config is not None else default_config())
        self.summary = self.directory / "summary.json"
        self._err = open(self.directory / "d.err", "w")
        self.process = subprocess.Popen(
            [HAPTICD_BIN, "--no-status", "--config", str(config_path), "--socket", self.socket,
             "--summary", str(self.summary)], stdout=subprocess.DEVNULL, stderr=self._err)
        deadline = time.monotonic() + 30.0
        while not os.path.exists(self.socket):
            if self.process.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"hapticd did not serve {self.socket}: {self.messages()}")
            time.sleep(0.02)

    def messages(self) -> str:
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
