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
import textwrap

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


def wrap(text, width_in, font_pt):
    """`text` wrapped at `width_in`: a character of a sans-serif font is about 0.55 of its
    size wide."""
    chars = max(20, int(width_in * 72.0 / (0.55 * font_pt)))
    return "\n".join(textwrap.fill(part, width=chars) for part in text.split("\n"))


def title(ax, text):
    """The axes' title, wrapped at the width of the axes (about 80 % of the figure's)."""
    import matplotlib
    width_in = 0.8 * ax.figure.get_size_inches()[0]
    ax.set_title(wrap(text, width_in, matplotlib.rcParams["font.size"]))


def save(figure, path, caption, legend_from=()):
    """Lays the figure out and writes it in the format its extension names, at its own size
    (never cropped: a paper's column width stays the width asked for). Below the axes, from
    the bottom: the caption line with the date, then one legend of every entry of the axes
    in `legend_from` (their own legends removed), so that no legend covers a curve."""
    import matplotlib
    font_pt = matplotlib.rcParams["font.size"]
    width_in, height_in = figure.get_size_inches()
    renderer = figure.canvas.get_renderer()
    gap = 0.03 / height_in
    columns = 2 if width_in >= 6.0 else 1

    def height_of(artist):
        return artist.get_window_extent(renderer).height / figure.dpi / height_in

    line = wrap(f"{caption} \u00b7 {today()}" if caption else today(), width_in, 0.8 * font_pt)
    text = figure.text(0.005, 0.005, line, ha="left", va="bottom", fontsize=0.8 * font_pt,
                       color="0.35")
    bottom = 0.005 + height_of(text) + gap
    handles, labels = [], []
    for ax in legend_from:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            if not label.startswith("_"):
                handles.append(handle)
                labels.append(wrap(label, 0.9 * width_in / columns - 0.5, 0.83 * font_pt))
        if ax.get_legend() is not None:
            ax.get_legend().remove()
    if handles:
        legend = figure.legend(handles, labels, loc="lower left", bbox_to_anchor=(0.005, bottom),
                               frameon=False, fontsize="small", borderaxespad=0.0, ncol=columns)
        bottom += height_of(legend) + gap
    figure.tight_layout(pad=0.6, rect=(0.0, min(bottom, 0.6), 1.0, 1.0))
    image = image_format(path)
    metadata = {"Creator": "hapticd"} if image in ("svg", "pdf") else {"Software": "hapticd"}
    # No time stamp in the file: the same chart, the same bytes.
    if image == "svg":
        metadata["Date"] = None
    if image == "pdf":
        metadata["CreationDate"] = None
    figure.savefig(path, format=image, dpi=PNG_DPI, metadata=metadata)
