#!/usr/bin/python3
"""Draws the speed-against-accuracy charts of haptic-tune identify from the tables that
bench/tune/identify_sweep writes (docs/identification.md has the commands), with the
drawing code of the evidence (tools/evidence/identification_charts.py: the one way to draw
them, in the look of every hapticd chart, tools/plot/chart_style.py):

  identification_chart.py TABLE.json OUT.png|OUT.svg|OUT.pdf [--size W,H] [--font-size PT]

TABLE.json is one of
  "identification-sweep":    error of m, b and F_c and solve time against log length, one
                             line per excitation amplitude (identify_sweep);
  "identification-segments": spread of the estimates, calibration of the standard errors and
                             the residual against the shooting-segment length
                             (identify_sweep --segments).

The C++ computes every number; this script only draws them (matplotlib, Agg backend).
Exit codes: 0 drawn; 2 bad input; 3 matplotlib cannot be imported.
"""

import argparse
import json
import pathlib
import sys

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "evidence"))

import chart_style  # noqa: E402
import identification  # noqa: E402
import identification_charts  # noqa: E402

EXIT_BAD_INPUT = 2
EXIT_NO_MATPLOTLIB = 3


def fail(message, code=EXIT_BAD_INPUT):
    print(f"identification_chart.py: {message}", file=sys.stderr)
    sys.exit(code)


def size(text):
    try:
        width, height = (float(side) for side in text.split(","))
    except ValueError as error:
        raise argparse.ArgumentTypeError(f"{text!r}: want W,H in inches") from error
    if not (1.0 <= width <= 40.0 and 1.0 <= height <= 40.0):
        raise argparse.ArgumentTypeError(f"{text!r}: each side 1 to 40 in")
    return width, height


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("table", help="identify_sweep's JSON table")
    parser.add_argument("out", help="the chart: .png, .svg or .pdf")
    parser.add_argument("--size", type=size, default=None, help="W,H in inches")
    parser.add_argument("--font-size", type=float, default=chart_style.DEFAULT_FONT_SIZE_PT,
                        help="points (default %(default)g)")
    args = parser.parse_args()
    try:
        chart_style.image_format(args.out)
    except ValueError as error:
        fail(str(error))
    if not 4.0 <= args.font_size <= 30.0:
        fail(f"--font-size {args.font_size:g}: allowed 4 to 30")
    try:
        with open(args.table, encoding="utf-8") as f:
            table = json.load(f)
    except (OSError, ValueError) as error:
        fail(f"cannot read {args.table}: {error}")
    kind = table.get("kind") if isinstance(table, dict) else None
    try:
        if kind == "identification-sweep":
            draw = identification_charts.draw_sweep
            what = identification_charts.what_sweep(table)
            caption = f"{what}. The {identification.describe_device(table['device'])}"
            default_size = identification_charts.SWEEP_SIZE_IN
            options = {"default_amplitude": identification.DEFAULT_AMPLITUDE_RMS_N}
        elif kind == "identification-segments":
            draw = identification_charts.draw_segments
            caption = identification_charts.what_segments(table)
            default_size = identification_charts.SEGMENTS_SIZE_IN
            options = {"default_segment_s": identification.DEFAULT_SEGMENT_S}
        else:
            fail(f"{args.table}: unknown table kind {kind!r}")
    except (KeyError, TypeError, ValueError) as error:
        fail(f"{args.table}: malformed table ({error!r})")
    try:
        chart_style.pyplot(args.font_size)
    except ImportError as error:
        fail(f"cannot import matplotlib ({error}); install python3-matplotlib",
             EXIT_NO_MATPLOTLIB)
    try:
        identification_charts.draw_one(args.out, draw, table, caption, args.size or default_size,
                                       args.font_size, **options)
    except (KeyError, TypeError, ValueError, IndexError) as error:
        fail(f"{args.table}: malformed table ({error!r})")
    except OSError as error:
        fail(f"cannot write {args.out}: {error}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
