"""hapticd's Python client: a running daemon's control socket, and its recordings.

    import hapticd
    with hapticd.Client(instance="lab0") as daemon:       # or Client("/path/to/socket")
        daemon.mark("trial 3")
        print(daemon.status()["state"])
    run = hapticd.read_recording("/var/log/hapticd/lab0/take1.csv")
    run["x0_m"], run.preamble["coupling_stiffness_n_per_m"], run.marks

The protocol is docs/control.md; the recording format docs/daemon.md, "Telemetry". Standard
library only; numpy (Debian's python3-numpy) when it is installed, for the columns.
"""

from hapticd.control import Client, ConnectionLost, HapticdError, RequestRefused, instance_socket
from hapticd.recording import Mark, Recording, RecordingFormatError, read_recording

__all__ = [
    "Client",
    "ConnectionLost",
    "HapticdError",
    "Mark",
    "Recording",
    "RecordingFormatError",
    "RequestRefused",
    "instance_socket",
    "read_recording",
]
