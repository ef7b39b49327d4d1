"""What every evidence section gets: where the project's programs are, where to write, how
much to run, and one way to run a program and read its JSON."""

import concurrent.futures
import dataclasses
import json
import os
import pathlib
import platform
import subprocess


class EvidenceError(RuntimeError):
    """A program the evidence runs failed, or wrote what it should not have."""


@dataclasses.dataclass
class Context:
    source_dir: pathlib.Path  # the project's source tree
    bin_dir: pathlib.Path     # the build's executables (hapticd, haptic-tune, ...)
    out_dir: pathlib.Path     # where the data files and charts go
    work_dir: pathlib.Path    # scratch: configs, logs (removed at the end)
    quick: bool               # the CI mode: few points, short runs
    jobs: int = 2             # programs run at once

    def program(self, name):
        path = self.bin_dir / name
        if not path.is_file():
            raise EvidenceError(f"{path} is missing: build the project first "
                                f"(cmake --build --preset release)")
        return str(path)

    def run(self, args, what, env=None, timeout_s=600, exits=(0,)):
        """Runs `args`; returns its standard output. EvidenceError naming `what`, the command
        and its messages when its exit status is not one of `exits`."""
        merged = dict(os.environ, **(env or {}))
        try:
            done = subprocess.run(args, capture_output=True, text=True, env=merged,
                                  timeout=timeout_s, check=False)
        except subprocess.TimeoutExpired as error:
            raise EvidenceError(f"{what}: timed out after {timeout_s} s: {' '.join(args)}") from error
        if done.returncode not in exits:
            raise EvidenceError(f"{what}: exit {done.returncode}: {' '.join(args)}\n"
                                f"{done.stderr.strip()}")
        return done.stdout

    def run_json(self, args, what, **kwargs):
        out = self.run(args, what, **kwargs)
        try:
            return json.loads(out)
        except json.JSONDecodeError as error:
            raise EvidenceError(f"{what}: not JSON ({error}): {out[:200]}") from error

    def parallel(self, function, items):
        """function(item) for every item, `jobs` at a time; the results in the items' order."""
        with concurrent.futures.ThreadPoolExecutor(max_workers=self.jobs) as pool:
            return list(pool.map(function, items))

    def scratch(self, name):
        path = self.work_dir / name
        path.mkdir(parents=True, exist_ok=True)
        return path


def machine():
    """The machine the evidence ran on, for every data file and caption."""
    cpu = "unknown CPU"
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as info:
            for line in info:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {"cpu": cpu, "cores": os.cpu_count(), "kernel": platform.release(),
            "system": platform.system()}


def describe_machine(info):
    return f"{info['cpu']}, {info['cores']} cores, Linux {info['kernel']}"
