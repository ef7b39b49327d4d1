"""Where and with what a benchmark ran: the machine (CPU model, cores, kernel, load) and the
hapticd build (binary, version, build type, the source tree's commit), for the data files and
chart captions of bench/jitter.py and bench/tick_instructions.py.

    info = run_info.machine()          # {"cpu_model", "cpus", "kernel", "load_average_1_5_15"}
    build = run_info.build(hapticd)    # {"hapticd", "version", "build_type", "source_commit"}
    run_info.caption_machine(info)     # "AMD EPYC, 2 CPUs, kernel 6.18.44"
    run_info.caption_build(build)      # "hapticd 0.1.0 RelWithDebInfo (a964952)"

Nothing here raises for missing information: an unknown field is None.
"""

import os
import platform
import subprocess


def _first_line(command):
    """The first non-empty line a command prints (stdout, then stderr), or None."""
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return None
    for line in (done.stdout + "\n" + done.stderr).splitlines():
        if line.strip():
            return line.strip()
    return None


def tool_version(command):
    """The version line of a tool (e.g. ["stress-ng", "--version"]), or None."""
    return _first_line(command)


def cpu_model():
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as cpuinfo:
            for line in cpuinfo:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or None


def machine():
    return {
        "cpu_model": cpu_model(),
        "cpus": os.cpu_count(),
        "kernel": platform.release(),
        "load_average_1_5_15": [round(x, 2) for x in os.getloadavg()],
    }


def _cmake_cache(binary):
    """CMakeCache.txt of the build tree that holds `binary` (bin/ is one or two levels down)."""
    folder = os.path.dirname(os.path.abspath(binary))
    for _ in range(3):
        folder = os.path.dirname(folder)
        cache = os.path.join(folder, "CMakeCache.txt")
        if os.path.isfile(cache):
            entries = {}
            with open(cache, encoding="utf-8", errors="replace") as text:
                for line in text:
                    if ":" in line and "=" in line and not line.startswith(("#", "//")):
                        key, rest = line.split(":", 1)
                        entries[key] = rest.split("=", 1)[1].strip()
            return entries
    return {}


def build(hapticd):
    """The hapticd binary's version, build type and the HEAD of the source tree it was
    configured from (at run time: the binary may predate it)."""
    cache = _cmake_cache(hapticd)
    source_dir = cache.get("CMAKE_HOME_DIRECTORY")
    commit = None
    if source_dir:
        commit = _first_line(["git", "-C", source_dir, "rev-parse", "--short", "HEAD"])
        if commit and " " in commit:  # an error message, not a hash
            commit = None
    return {
        "hapticd": os.path.abspath(hapticd),
        "version": tool_version([hapticd, "--version"]),
        "build_type": cache.get("CMAKE_BUILD_TYPE") or None,
        "source_commit": commit,
    }


def caption_machine(info):
    kernel = (info.get("kernel") or "?").split("-")[0]
    return f"{info.get('cpu_model') or 'unknown CPU'}, {info.get('cpus')} CPUs, kernel {kernel}"


def caption_build(info):
    text = info.get("version") or "hapticd"
    if info.get("build_type"):
        text += f" {info['build_type']}"
    if info.get("source_commit"):
        text += f" ({info['source_commit']})"
    return text
