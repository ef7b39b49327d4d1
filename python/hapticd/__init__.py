"""hapticd's Python client: a running daemon's control socket, its recordings, and the
channel through which a process renders an [external] scene's world.

    import hapticd
    with hapticd.Client(instance="lab0") as daemon:       # or Client("/path/to/socket")
        daemon.mark("trial 3")
        print(daemon.status()["state"])
    run = hapticd.read_recording("/var/log/hapticd/lab0/take1.csv")
    run["x0_m"], run.preamble["coupling_stiffness_n_per_m"], run.marks
    with hapticd.external.connect(instance="lab0") as world:   # /run/hapticd/lab0.world
        world.run(lambda step, dt_s: [max(step.handle_position_m[0], 0.0)], rate_hz=500.0)

The protocol is docs/control.md; the recording format docs/daemon.md, "Telemetry"; the
channel include/hapticd/env/external_world.h (docs/external-worlds.md). Standard library
only; numpy (Debian's python3-numpy) when it is installed, for the columns.
"""

from hapticd import external
from hapticd.control import Client, ConnectionLost, HapticdError, RequestRefused, instance_socket
from hapticd.external import ChannelClosed, World, WorldError, channel_path
from hapticd.recording import Mark, Recording, RecordingFormatError, read_recording

__all__ = [
    "ChannelClosed",
    "Client",
    "ConnectionLost",
    "HapticdError",
    "Mark",
    "Recording",
    "RecordingFormatError",
    "RequestRefused",
    "World",
    "WorldError",
    "channel_path",
    "external",
    "instance_socket",
    "read_recording",
]
