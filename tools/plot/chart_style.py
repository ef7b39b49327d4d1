"""One look for every chart hapticd draws (haptic-tune's charts, the evidence of
tools/evidence): the image format from the file's extension, a size and a font size fit for
a paper, text kept as text (editable SVG, TrueType in PDF), and a caption line under the
axes that names the model, the device and the date.

    plt, np = chart_style.pyplot(font_size_pt=9)
    figure = chart_style.new_figure(plt, (7.0, 4.5))
    ... draw ...
    chart_style.save(figure, "out.pdf", caption="passive model; pen display m = 0.1 kg ...")

The date is today's, or SOURCE_DATE_EPOCH's when that is set (reproducible output).
Raises ImportError when matplotlib or numpy is missing, ValueError for an unknown extension.
"""

import datetime
import os

FORMATS = {".png": "png", ".svg": "svg", ".pdf": "pdf"}
DEFAULT_SIZE_IN = (7.0, 4.8)
DEFAULT_FONT_SIZE_PT = 9.0
PNG_DPI = 200


def image_format(path):
    """'png', 'svg' or 'pdf' from the path's extension (any case); ValueError otherwise."""
    extension = os.path.splitext(path)[1].lower()
    if extension not in FORMATS:
        raise ValueError(f"{path}: unsupported extension {extension!r} "
                         f"(allowed: {', '.join(FORMATS)})")
    return FORMATS[extension]


def pyplot(font_size_pt=DEFAULT_FONT_SIZE_PT):
    """matplotlib.pyplot and numpy, set up for files (Agg) with text kept as text."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    matplotlib.rcParams.update({
        "font.size": font_size_pt,
        "svg.fonttype": "none",  # <text> elements, editable in Inkscape or Illustrator
        "pdf.fonttype": 42,      # TrueType, editable text in PDF
        "ps.fonttype": 42,
        "svg.hashsalt": "hapticd",  # stable element ids: the same chart, the same file
        "legend.fontsize": "small",
        "legend.framealpha": 0.92,
        "axes.titlesize": "medium",
    })
    return plt, np


def new_figure(plt, size_in=DEFAULT_SIZE_IN):
    return plt.figure(figsize=tuple(size_in))


def today():
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    if epoch:
        moment = datetime.datetime.fromtimestamp(int(epoch), datetime.timezone.utc)
    else:
        moment = datetime.datetime.now(datetime.timezone.utc)
    return moment.strftime("%Y-%m-%d")


def grid(ax):
    ax.grid(True, which="major", alpha=0.45)
    ax.grid(True, which="minor", alpha=0.15)


def save(figure, path, caption):
    """Lays the figure out with the caption line (and the date) below everything, and writes
    it in the format its extension names, at its own size (never cropped: a paper's column
    width stays the width asked for)."""
    import matplotlib
    line = f"{caption} \u00b7 {today()}" if caption else today()
    font_pt = matplotlib.rcParams["font.size"] * 0.8
    text = figure.text(0.005, 0.005, line, ha="left", va="bottom", fontsize=font_pt,
                       color="0.35", wrap=True)
    height_in = figure.get_size_inches()[1]
    lines = 1 + line.count("\n")
    reserved = min(0.3, (lines * 1.5 * font_pt / 72.0 + 0.04) / height_in)
    figure.tight_layout(rect=(0.0, reserved, 1.0, 1.0))
    text.set_wrap(False)
    image = image_format(path)
    metadata = {"Creator": "hapticd"} if image in ("svg", "pdf") else {"Software": "hapticd"}
    if image == "svg":
        metadata["Date"] = None  # no time stamp in the file: the same chart, the same bytes
    figure.savefig(path, format=image, dpi=PNG_DPI, metadata=metadata)
