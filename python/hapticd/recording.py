"""A hapticd log or recording (docs/daemon.md, "Telemetry"), read whole: the preamble's
"# key: value" lines, the "# mark N: text" lines with the row each starts at, and the
columns (numpy arrays when numpy is installed, else lists of floats)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional

#: `flags` was `tick_flags`'s name before the preamble (hapticd 0.1.0): read as the new name.
_RENAMED = {"flags": "tick_flags"}


class RecordingFormatError(ValueError):
    """The file is not a telemetry log: the message names the file, the line and the column."""


@dataclass
class Mark:
    """A trial marker or a change of gains or scene: the rows from `row` on carry `number`
    in their `mark` column."""

    number: int
    row: int
    text: str


@dataclass
class Recording:
    path: str
    preamble: Dict[str, str] = field(default_factory=dict)
    marks: List[Mark] = field(default_factory=list)
    columns: List[str] = field(default_factory=list)
    data: Dict[str, Any] = field(default_factory=dict)

    def __getitem__(self, name: str) -> Any:
        try:
            return self.data[name]
        except KeyError:
            raise KeyError(f"{self.path} has no column {name!r}; it has "
                           f"{', '.join(self.columns)}") from None

    def __len__(self) -> int:
        return len(self.data[self.columns[0]]) if self.columns else 0

    @property
    def axes(self) -> int:
        return sum(1 for name in self.columns if name.startswith("x") and name.endswith("_m")
                   and name[1:-2].isdigit())

    def number(self, key: str) -> Optional[float]:
        """A preamble value as a number (rate_hz, coupling_stiffness_n_per_m...), or None."""
        text = self.preamble.get(key)
        try:
            return float(text) if text is not None else None
        except ValueError:
            return None

    def trial(self, number: int) -> Dict[str, Any]:
        """The columns of the rows that carry mark `number`."""
        marks = self.data.get("mark")
        if marks is None:
            raise KeyError(f"{self.path} has no mark column")
        rows = [i for i, m in enumerate(marks) if int(m) == number]
        try:
            import numpy
            return {name: numpy.asarray(values)[rows] for name, values in self.data.items()}
        except ImportError:
            return {name: [values[i] for i in rows] for name, values in self.data.items()}


def _mark(text: str, row: int) -> Optional[Mark]:
    body = text[1:].strip()
    if not body.startswith("mark "):
        return None
    number, colon, rest = body[5:].partition(":")
    if not colon or not number.strip().isdigit():
        return None
    return Mark(int(number), row, rest.strip())


def read_recording(path: str) -> Recording:
    """Reads the file at `path`. Raises RecordingFormatError naming the line and the column
    for anything that is not a telemetry log (no header, a short row, a value that is not a
    finite number)."""
    recording = Recording(path)
    values: List[List[float]] = []
    with open(path, encoding="utf-8", errors="replace") as lines:
        for number, line in enumerate(lines, start=1):
            line = line.rstrip("\r\n")
            if not line.strip():
                continue
            if line.lstrip().startswith("#"):
                if not recording.columns:
                    key, colon, value = line.lstrip()[1:].strip().partition(": ")
                    if colon and key and " " not in key:
                        recording.preamble[key] = value.strip()
                elif (mark := _mark(line.strip(), len(values[0]) if values else 0)) is not None:
                    recording.marks.append(mark)
                continue
            fields = [text.strip() for text in line.split(",")]
            if not recording.columns:
                recording.columns = [_RENAMED.get(name.strip('"'), name.strip('"'))
                                     for name in fields]
                values = [[] for _ in fields]
                continue
            if len(fields) != len(values):
                raise RecordingFormatError(f"{path}:{number}: {len(fields)} fields, but the "
                                           f"header has {len(values)}")
            for column, text in enumerate(fields):
                try:
                    value = float(text)
                except ValueError:
                    value = math.nan
                if not math.isfinite(value):
                    raise RecordingFormatError(
                        f"{path}:{number}:{column + 1} ({recording.columns[column]}): "
                        f"{text!r} is not a finite number")
                values[column].append(value)
    if not recording.columns:
        raise RecordingFormatError(f"{path}: no header row (expected tick,t_s,...)")
    try:
        import numpy
        recording.data = {name: numpy.asarray(column, dtype=float)
                          for name, column in zip(recording.columns, values)}
    except ImportError:
        recording.data = dict(zip(recording.columns, values))
    return recording
