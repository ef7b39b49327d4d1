#!/usr/bin/python3
"""Draws haptic-tune's charts. haptic-tune computes every number and sends one JSON
document on standard input; this script only draws it (matplotlib, Agg backend), in the
look every hapticd chart shares (chart_style.py).

Input: {"kind": str, "title": str, "caption": str, ...the kind's data...,
        "output": {"path": str, "format": "png" | "svg" | "pdf",
                   "size_in": [width, height], "font_size_pt": number}}
Kinds: "design-procedure" and "zwidth" (design_charts.py), "run" (run_chart.py),
"identify-fit" (fit_chart.py); each module's docstring has its data.

Exit codes: 0 drawn; 2 bad input; 3 matplotlib (or numpy) cannot be imported.
"""

import json
import sys

import chart_style
import design_charts
import fit_chart
import run_chart

EXIT_BAD_INPUT = 2
EXIT_NO_MATPLOTLIB = 3

DRAW = {**design_charts.DRAW, **run_chart.DRAW, **fit_chart.DRAW}
BAD_DATA = (KeyError, TypeError, ValueError, IndexError, design_charts.BadChart)


def fail(message, code=EXIT_BAD_INPUT):
    print(f"hapticd_chart.py: {message}", file=sys.stderr)
    sys.exit(code)


def read_output(chart):
    output = chart.get("output") or {}
    path = output.get("path")
    image_format = output.get("format")
    if not path or image_format not in chart_style.FORMATS.values():
        fail("output.path and output.format (png, svg or pdf) are required")
    try:
        size_in = tuple(float(side) for side in output.get("size_in", chart_style.DEFAULT_SIZE_IN))
        font_size_pt = float(output.get("font_size_pt", chart_style.DEFAULT_FONT_SIZE_PT))
    except (TypeError, ValueError) as error:
        fail(f"output.size_in and output.font_size_pt must be numbers: {error}")
    if len(size_in) != 2 or not all(1.0 <= side <= 40.0 for side in size_in):
        fail(f"output.size_in {size_in} must be [width, height], each 1 to 40 in")
    if not 4.0 <= font_size_pt <= 30.0:
        fail(f"output.font_size_pt {font_size_pt} must be 4 to 30")
    return path, image_format, size_in, font_size_pt


def main():
    try:
        chart = json.load(sys.stdin)
    except json.JSONDecodeError as error:
        fail(f"input is not JSON: {error}")
    if not isinstance(chart, dict):
        fail("input must be a JSON object")
    kind = chart.get("kind")
    if kind not in DRAW:
        fail(f"unknown chart kind {kind!r} (allowed: {', '.join(DRAW)})")
    path, image_format, size_in, font_size_pt = read_output(chart)
    if chart_style.image_format(path) != image_format:
        fail(f"output.format {image_format} does not match {path}")
    try:
        plt, np = chart_style.pyplot(font_size_pt)
    except ImportError as error:
        fail(f"cannot import matplotlib with {sys.executable}: {error}; "
             "install python3-matplotlib", EXIT_NO_MATPLOTLIB)

    figure = chart_style.new_figure(plt, size_in)
    try:
        axes = DRAW[kind](plt, np, chart, figure)
    except BAD_DATA as error:
        fail(f"malformed {kind} chart data: {error!r}")
    chart_style.title(axes[0], chart.get("title", ""))
    try:
        chart_style.save(figure, path, chart.get("caption", ""), legend_from=axes)
    except OSError as error:
        fail(f"cannot write {path}: {error}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
