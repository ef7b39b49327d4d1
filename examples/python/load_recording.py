#!/usr/bin/python3
"""Load a hapticd recording into numpy and summarise each trial.

    /usr/bin/python3 examples/python/load_recording.py take1.csv

The rows of one mark are one trial (hapticctl mark, or a change of gains or scene:
docs/daemon.md, "Telemetry"). For each: its text, its length, the largest force on the
handle, the deepest the tool went past where it started, and the energy the passivity
observer counted. Prints one line per trial, and the gains and the verdict the file names.
"""

import argparse
import sys

import numpy

import hapticd


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recording", help="a hapticd --log file or a hapticctl recording")
    parser.add_argument("--axis", type=int, default=0, help="the axis to summarise (default 0)")
    arguments = parser.parse_args()
    try:
        run = hapticd.read_recording(arguments.recording)
    except (OSError, hapticd.RecordingFormatError) as error:
        print(f"load_recording: {error}", file=sys.stderr)
        return 2
    if not 0 <= arguments.axis < run.axes:
        print(f"load_recording: --axis {arguments.axis}: the file has axes 0..{run.axes - 1}",
              file=sys.stderr)
        return 2
    axis = str(arguments.axis)
    print(f"{arguments.recording}: {len(run)} ticks at {run.preamble.get('rate_hz', '?')} Hz, "
          f"k_c {run.preamble.get('coupling_stiffness_n_per_m', '?')} N/m, "
          f"b_c {run.preamble.get('coupling_damping_n_s_per_m', '?')} N s/m")
    print(f"  stability: {run.preamble.get('stability', '(not named: an older file)')}")
    texts = {mark.number: mark.text for mark in run.marks}
    marks = run["mark"] if "mark" in run.columns else numpy.zeros(len(run))
    for number in numpy.unique(marks).astype(int):
        trial = run.trial(int(number)) if "mark" in run.columns else run.data
        force = numpy.abs(trial["f" + axis + "_n"])
        travel = trial["x" + axis + "_m"] - trial["x" + axis + "_m"][0]
        seconds = trial["t_s"][-1] - trial["t_s"][0]
        print(f"  mark {number} ({texts.get(int(number), 'before the first mark')}): "
              f"{len(force)} ticks, {seconds:.3f} s, peak |F| {force.max():.3f} N, "
              f"travel {travel.min() * 1e3:+.3f}..{travel.max() * 1e3:+.3f} mm, "
              f"observer {trial['energy_j'][-1]:.3g} J")
    return 0


if __name__ == "__main__":
    sys.exit(main())
