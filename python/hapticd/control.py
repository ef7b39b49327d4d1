"""The control socket of a running hapticd (docs/control.md): one JSON object per line each
way, one reply per request in order, and a subscriber's telemetry events between them."""

from __future__ import annotations

import json
import math
import socket
import time
from collections import deque
from typing import Any, Deque, Dict, Iterator, List, Optional

PROTOCOL_VERSION = 1
#: The longest request line the daemon reads, its newline included (kMaxRequestBytes).
MAX_REQUEST_BYTES = 4096
#: A coupling or scene request runs the stability check, which may take seconds (check = "exact").
CHECKED_TIMEOUT_S = 120.0


class HapticdError(Exception):
    """Anything that went wrong talking to hapticd."""


class ConnectionLost(HapticdError):
    """The socket could not be reached, or closed, or a reply did not come in time."""


class RequestRefused(HapticdError):
    """The daemon answered ok: false. `error` is its message: it names the field, the value
    and what is allowed, or why the state refuses the request."""

    def __init__(self, request: str, error: str, reply: Dict[str, Any]):
        super().__init__(f"{request} refused: {error}" if not error.startswith(request) else error)
        self.request = request
        self.error = error
        self.reply = reply


def instance_socket(name: str) -> str:
    """Where hapticd@NAME serves its control socket (/run/hapticd/NAME.sock)."""
    if not name or "/" in name or name in (".", ".."):
        raise ValueError(f"instance name {name!r}: a non-empty name without '/'")
    return f"/run/hapticd/{name}.sock"


class Client:
    """A connection to one daemon's control socket.

    `socket_path` or `instance` (hapticd@NAME's socket) names the daemon. `timeout_s` bounds
    each reply (a coupling or scene check gets CHECKED_TIMEOUT_S). Use as a context manager, or
    call close(). Not for several threads at once.
    """

    def __init__(self, socket_path: Optional[str] = None, *, instance: Optional[str] = None,
                 timeout_s: float = 5.0):
        if (socket_path is None) == (instance is None):
            raise ValueError("give socket_path or instance, not both or neither")
        if not (timeout_s > 0.0 and math.isfinite(timeout_s)):
            raise ValueError(f"timeout_s = {timeout_s!r}: a finite number of seconds > 0")
        self.path = socket_path if socket_path is not None else instance_socket(instance or "")
        self.timeout_s = timeout_s
        self._socket = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            self._socket.settimeout(timeout_s)
            self._socket.connect(self.path)
        except OSError as error:
            self._socket.close()
            raise ConnectionLost(f"{self.path}: cannot connect: {error.strerror or error}") from None
        self._buffer = b""
        self._events: Deque[Dict[str, Any]] = deque()
        self._next_id = 1

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        self._socket.close()

    # --- the requests (docs/control.md, "Requests") ------------------------------------
    def status(self) -> Dict[str, Any]:
        """The daemon's status: state, tick, coupling, scene, recording, faults..."""
        return self.request("status")["status"]

    def arm(self) -> str:
        """Forces may flow (after a still handle and the soft start). Returns the state before."""
        return self.request("arm")["state_before"]

    def disarm(self) -> str:
        """Zero force from the next tick on. Returns the state before."""
        return self.request("disarm")["state_before"]

    def reset(self) -> str:
        """Clears a latched fault (the loop starts again disarmed or through the soft start)."""
        return self.request("reset")["state_before"]

    def coupling(self, stiffness_n_per_m: float,
                 damping_n_s_per_m: Optional[float] = None) -> Dict[str, Any]:
        """New coupling gains k_c, b_c of (16), after the daemon's stability check; the reply
        has the verdict. Raises RequestRefused with the verdict when they fail it."""
        fields: Dict[str, Any] = {"stiffness": float(stiffness_n_per_m)}
        if damping_n_s_per_m is not None:
            fields["damping"] = float(damping_n_s_per_m)
        return self.request("coupling", timeout_s=CHECKED_TIMEOUT_S, **fields)

    def scene(self, path: str) -> Dict[str, Any]:
        """Render the scene file at `path` (absolute) from a tick boundary on."""
        return self.request("scene_load", timeout_s=CHECKED_TIMEOUT_S, path=path)

    def record_start(self, path: str) -> Dict[str, Any]:
        """Record every tick to a new file in the daemon's outputs directory."""
        return self.request("record_start", timeout_s=30.0, path=path)

    def record_stop(self) -> Dict[str, Any]:
        """End the recording: `records`, `dropped`, `complete` (and `failure` when not)."""
        return self.request("record_stop", timeout_s=30.0)

    def identify(self, path: Optional[str] = None) -> Dict[str, Any]:
        """Play the identification excitation open loop on the disarmed daemon."""
        fields = {} if path is None else {"path": path}
        return self.request("identify", timeout_s=30.0, **fields)

    def mark(self, text: str) -> int:
        """A trial marker: the number every record carries from the servo's next tick on
        (the recordings' `mark` column, docs/daemon.md "Telemetry")."""
        return int(self.request("mark", text=text)["mark"])

    def stream(self, rate_hz: float = 10.0, count: Optional[int] = None) -> Iterator[Dict[str, Any]]:
        """The telemetry events (tick, t_s, state, x_m, xe_m, f_n, faults) at `rate_hz`
        (0.001 to 100), `count` of them or until the caller stops; unsubscribes at the end."""
        self.request("subscribe", rate_hz=float(rate_hz))
        period_s = 1.0 / rate_hz
        try:
            taken = 0
            while count is None or taken < count:
                yield self._event(max(self.timeout_s, 3.0 * period_s))
                taken += 1
        finally:
            try:
                self.request("unsubscribe")
            except HapticdError:
                pass
            self._events.clear()

    def stream_arrays(self, rate_hz: float, count: int) -> Dict[str, Any]:
        """`count` telemetry events as arrays (numpy when installed, else lists): tick, t_s,
        and x_m, xe_m, f_n with one column per axis."""
        if count < 1:
            raise ValueError(f"count = {count}: at least 1")
        events = list(self.stream(rate_hz, count))
        columns: Dict[str, List[Any]] = {"tick": [e["tick"] for e in events],
                                         "t_s": [e["t_s"] for e in events]}
        for key in ("x_m", "xe_m", "f_n"):
            columns[key] = [e[key] for e in events]
        try:
            import numpy
        except ImportError:
            return columns
        return {key: numpy.asarray(values) for key, values in columns.items()}

    # --- the protocol ---------------------------------------------------------------------
    def request(self, name: str, *, timeout_s: Optional[float] = None, **fields: Any) -> Dict[str, Any]:
        """Sends request `name` with `fields`; returns the ok reply, or raises RequestRefused
        (ok: false) or ConnectionLost."""
        request_id = self._next_id
        self._next_id += 1
        line = json.dumps({"v": PROTOCOL_VERSION, "id": request_id, "request": name, **fields},
                          ensure_ascii=False, allow_nan=False).encode() + b"\n"
        if len(line) > MAX_REQUEST_BYTES:
            raise ValueError(f"{name}: the request is {len(line)} bytes; the daemon reads at most "
                             f"{MAX_REQUEST_BYTES}")
        try:
            self._socket.sendall(line)
        except OSError as error:
            raise ConnectionLost(f"{self.path}: sending {name}: {error.strerror or error}") from None
        deadline = time.monotonic() + (timeout_s if timeout_s is not None else self.timeout_s)
        while True:
            message = self._read_message(deadline, name)
            if "event" in message:
                self._events.append(message)
                continue
            if message.get("id") != request_id:
                raise ConnectionLost(f"{self.path}: a reply to {message.get('id')!r} came for "
                                     f"request {request_id} ({name})")
            if message.get("ok") is True:
                return message
            raise RequestRefused(name, str(message.get("error", "refused")), message)

    def _event(self, timeout_s: float) -> Dict[str, Any]:
        if self._events:
            return self._events.popleft()
        deadline = time.monotonic() + timeout_s
        while True:
            message = self._read_message(deadline, "the stream")
            if "event" in message:
                return message

    def _read_message(self, deadline: float, waiting_for: str) -> Dict[str, Any]:
        while b"\n" not in self._buffer:
            left = deadline - time.monotonic()
            if left <= 0:
                raise ConnectionLost(f"{self.path}: no reply to {waiting_for} in time")
            self._socket.settimeout(left)
            try:
                chunk = self._socket.recv(65536)
            except socket.timeout:
                raise ConnectionLost(f"{self.path}: no reply to {waiting_for} in time") from None
            except OSError as error:
                raise ConnectionLost(f"{self.path}: {error.strerror or error}") from None
            if not chunk:
                raise ConnectionLost(f"{self.path}: the daemon closed the connection "
                                     f"(waiting for {waiting_for})")
            self._buffer += chunk
        line, self._buffer = self._buffer.split(b"\n", 1)
        try:
            message = json.loads(line.decode("utf-8", errors="replace"))
        except ValueError:
            raise ConnectionLost(f"{self.path}: a line that is not JSON: {line[:80]!r}") from None
        if not isinstance(message, dict) or message.get("v") != PROTOCOL_VERSION:
            raise ConnectionLost(f"{self.path}: not a control protocol {PROTOCOL_VERSION} line: "
                                 f"{line[:80]!r}")
        return message
