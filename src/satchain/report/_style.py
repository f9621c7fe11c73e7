"""Fixed figure layouts in inches, shared by the report's figures.

Constrained layout measures every tick label of every axes twice per draw (about half of a figure's time); a
layout fixed in inches costs nothing at draw time. Its margins are computed here from the font sizes in force
(``matplotlib.rcParams``, e.g. inside :func:`satchain.report.compare_plots.with_rc`) and, where tick labels vary
with the data, from the labels' strings measured with the font (no figure drawn)."""

from __future__ import annotations

import math
from typing import Literal

import matplotlib
from matplotlib.figure import Figure

__all__ = [
    "axis_band_in",
    "grid_axes",
    "legend_height_in",
    "pin_title",
    "pin_titles",
    "place_grid",
    "text_height_in",
    "title_band_in",
    "yaxis_width_in",
]

#: Height of one line of text (DejaVu Sans as Agg draws it: ~1.03 em; a mathtext superscript ~1.18 em), em.
_LINE_EM = 1.2
#: Slack added to every margin so that a label never touches the figure's edge, points.
_SLACK_PT = 3.0
#: The ``rcParams`` keys of the font sizes the layouts read.
FontSizeKey = Literal[
    "font.size",
    "axes.labelsize",
    "axes.titlesize",
    "figure.titlesize",
    "legend.fontsize",
    "xtick.labelsize",
    "ytick.labelsize",
]


def grid_axes(fig: Figure, rows: list[tuple[float, float]], cols: list[tuple[float, float]], *, left: float,
              top: float) -> list[list[tuple[float, float, float, float]]]:  # fmt: skip
    """Axes rectangles (figure fractions) of a fixed layout given in inches: ``rows`` as (gap above, height)
    from ``top`` (the margin above the first gap) down, ``cols`` as (gap before, width) from ``left``. A fixed
    layout costs nothing at draw time; constrained layout measures every tick label twice per draw."""
    w_in, h_in = fig.get_size_inches()
    out, y = [], h_in - top
    for gap_r, height in rows:
        y -= gap_r + height
        x, row = left, []
        for gap_c, width in cols:
            x += gap_c
            row.append((x / w_in, y / h_in, width / w_in, height / h_in))
            x += width
        out.append(row)
    return out


def _pt(key: FontSizeKey) -> float:
    """A font size of ``rcParams`` in points (named sizes such as "large" resolved)."""
    from matplotlib.font_manager import FontProperties

    return FontProperties(size=matplotlib.rcParams[key]).get_size_in_points()


def text_height_in(key: FontSizeKey = "font.size", lines: int = 1) -> float:
    """Height (in) of ``lines`` lines of text at the ``rcParams`` font size ``key``."""
    return lines * _LINE_EM * _pt(key) / 72


def axis_band_in(label: bool = True) -> float:
    """Height (in) below an axes taken by its x ticks, tick labels and (``label``) the axis label."""
    rc = matplotlib.rcParams
    pt = rc["xtick.major.size"] + rc["xtick.major.pad"] + _SLACK_PT
    h = pt / 72 + text_height_in("xtick.labelsize")
    if label:
        h += rc["axes.labelpad"] / 72 + text_height_in("axes.labelsize")
    return h


def title_band_in(lines: int = 1) -> float:
    """Height (in) above an axes taken by its title of ``lines`` lines."""
    return (matplotlib.rcParams["axes.titlepad"] + _SLACK_PT) / 72 + text_height_in("axes.titlesize", lines)


def legend_height_in(rows: int, key: FontSizeKey = "legend.fontsize") -> float:
    """Height (in) of a legend of ``rows`` rows with its frame (matplotlib's default spacings: 0.3 + 1.5 em a
    row) and the pad between it and what it is anchored to."""
    return (0.3 + 1.5 * rows + matplotlib.rcParams["legend.borderaxespad"]) * _pt(key) / 72


def yaxis_width_in(*axes, label: bool = True, label_lines: float = 1.0) -> float:
    """Width (in) left of the axes taken by their y ticks, the widest tick label (its string from the axis'
    own locator and formatter, measured with the font: nothing drawn) and (``label``) the axis label (rotated:
    its height, ``label_lines`` lines). Call it after the data and limits are set."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import TextToPath

    rc = matplotlib.rcParams
    prop = FontProperties(size=rc["ytick.labelsize"])
    ttp, widest = TextToPath(), 0.0
    for ax in axes:
        lo, hi = sorted(ax.get_ylim())
        locs = [v for v in ax.yaxis.get_major_locator()() if lo - 1e-9 * (hi - lo) <= v <= hi + 1e-9 * (hi - lo)]
        for s in ax.yaxis.get_major_formatter().format_ticks(locs):
            widest = max(widest, ttp.get_text_width_height_descent(s, prop, ismath=False)[0] if s else 0.0)
    w = (rc["ytick.major.size"] + rc["ytick.major.pad"] + _SLACK_PT + widest) / 72
    if label:
        w += rc["axes.labelpad"] / 72 + label_lines * text_height_in("axes.labelsize")
    return math.ceil(w * 100) / 100


def place_grid(fig: Figure, axes: list[list], *, top: float, bottom: float, right: float = 0.25,
               hgap: float | None = None, vgap: float = 0.0, left: float | None = None) -> None:  # fmt: skip
    """Place ``axes`` (rows of axes) on equal cells of a fixed layout in inches: ``top``/``bottom``/``right``
    margins and ``vgap`` between rows given; ``left`` (default: :func:`yaxis_width_in` of every axes, measured
    once the axes have about their final size, as their tick locators depend on it) and ``hgap`` between
    columns (default: ``left`` plus room for a tick label's overhang, each panel labelling its own y axis).
    Call it after the data, limits, labels and titles are set: a title with nothing between it and its axes
    (no top ticks or x label, no y offset text) is pinned at its place, so that drawing does not measure every
    tick label again to find it (its text set anew with ``y=1``, keeping its font and colour)."""
    w, h = fig.get_size_inches()
    n_rows, n_cols = len(axes), len(axes[0])
    flat = [ax for row in axes for ax in row]

    def put(lft: float, gap: float) -> None:
        col = (w - lft - right - gap * (n_cols - 1)) / n_cols
        height = (h - top - bottom - vgap * (n_rows - 1)) / n_rows
        g = grid_axes(fig, [(0.0 if i == 0 else vgap, height) for i in range(n_rows)],
                      [(0.0 if j == 0 else gap, col) for j in range(n_cols)], left=lft, top=top)  # fmt: skip
        for row_axes, row_rects in zip(axes, g, strict=True):
            for ax, rect in zip(row_axes, row_rects, strict=True):
                ax.set_position(rect)

    if left is None:
        put(0.8, 0.95 if hgap is None else hgap)  # about the final sizes, for the tick locators
        left = yaxis_width_in(*flat)
    put(left, left + 0.15 if hgap is None else hgap)
    pin_titles(*flat)


def pin_titles(*axes) -> None:
    """:func:`pin_title` of every axes given."""
    for ax in axes:
        pin_title(ax)


def pin_title(ax) -> None:
    """Fix ``ax``'s centre title at y = 1 (plus its pad) when matplotlib's automatic placement would put it
    there anyway (see ``Axes._update_title_position``): nothing drawn above the axes but the title."""
    if not ax.get_title() or ax.get_title(loc="left") or ax.get_title(loc="right"):
        return
    top = ax.xaxis.get_ticks_position() in ("top", "unknown") or ax.xaxis.get_label_position() == "top"
    lo, hi = sorted(ax.get_ylim())
    fmt = ax.yaxis.get_major_formatter()
    fmt.format_ticks([v for v in ax.yaxis.get_major_locator()() if lo <= v <= hi])
    if top or fmt.get_offset() or ax.child_axes:
        return
    t = ax.title
    ax.set_title(t.get_text(), y=1.0, fontproperties=t.get_fontproperties().copy(), color=t.get_color())
