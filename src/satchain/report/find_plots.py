"""Figure of ``satchain measure find``: the edges found on the image, and the combined ACT / ALT MTF.

Examples
--------
>>> import os, tempfile
>>> from satchain.measure.find_mtf import measure_found_edges
>>> y, x = np.mgrid[0:160, 0:160]
>>> t = np.deg2rad(6.0)
>>> img = 0.2 + 0.6 / (1 + np.exp(-((x - 80.3) * np.cos(t) - (y - 80) * np.sin(t)) / 0.5))
>>> path = os.path.join(tempfile.mkdtemp(), "find.png")
>>> plot_find(measure_found_edges(img), path, image=img)
>>> os.path.getsize(path) > 10_000
True
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from satchain.report._save import save_figure

__all__ = ["plot_find"]

_COLOR = {"ACT": "tab:blue", "ALT": "tab:red"}
_MAX_THUMB_PX = 1200


def _thumbnail(image) -> tuple[np.ndarray, int]:
    """A strided view of at most ~_MAX_THUMB_PX per side, and its stride (never a full-size float copy)."""
    a = np.asarray(image)
    step = max(1, int(np.ceil(max(a.shape) / _MAX_THUMB_PX)))
    return np.asarray(a[::step, ::step], dtype=np.float32), step


def _draw_image(ax, image, result) -> None:
    thumb, step = _thumbnail(image)
    lo, hi = np.percentile(thumb, [0.5, 99.5])
    ax.imshow(thumb, cmap="gray", vmin=lo, vmax=hi if hi > lo else lo + 1, interpolation="nearest")
    for k, e in enumerate(result.edges):
        x0, y0, x1, y1 = e.candidate.roi
        ax.add_patch(
            Rectangle(
                (x0 / step - 0.5, y0 / step - 0.5),
                (x1 - x0) / step,
                (y1 - y0) / step,
                fill=False,
                color=_COLOR[e.direction],
                lw=1,
            )
        )
        ax.text(x0 / step, y0 / step - 1, str(k), color=_COLOR[e.direction], fontsize=7, va="bottom")
    for r in result.rejected:
        ax.plot(r.center_xy[0] / step, r.center_xy[1] / step, "x", color="orange", ms=4)
    ax.set_title("edges used (blue ACT, red ALT); x = rejected", fontsize=9)
    ax.set_xticks([])
    ax.set_yticks([])


def _draw_mtf(ax, result) -> None:
    for e, r in zip(result.edges, result.results, strict=False):
        ax.plot(r.f_cy_per_px, r.mtf, color=_COLOR[e.direction], lw=0.5, alpha=0.35)
    for d, c in result.combined.items():
        f, m, s = np.asarray(c.f_cy_per_px), np.asarray(c.mtf), np.asarray(c.sigma)
        ax.fill_between(f, m - 2 * s, m + 2 * s, color=_COLOR[d], alpha=0.25, lw=0)
        ax.plot(
            f,
            m,
            color=_COLOR[d],
            lw=2,
            label=f"{d}: {c.n_edges} edge(s), Nyquist {c.mtf_at_nyquist:.3f} +- {c.mtf_at_nyquist_sigma:.3f}",
        )
    ax.axvline(0.5, color="gray", lw=1)
    ax.text(0.5, 1.08, " Nyquist", color="gray", va="top", fontsize=8)
    ax.set_xlim(0, 1.0)
    ax.set_ylim(0, 1.1)
    ax.set_xlabel("spatial frequency f / f_s (cy/px)")
    ax.set_ylabel("MTF (band: +- 2 sigma; thin: single edges)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)


def plot_find(result, path: str | Path, *, image=None, title: str = "") -> None:
    """Combined ACT / ALT MTF (with +-2 sigma bands and the single edges) of a
    :class:`~satchain.measure.find_mtf.FindResult`; with ``image``, also the image with the ROIs used."""
    if image is not None:
        fig = Figure(figsize=(13, 5.2))
        ax0, ax1 = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1, 1.3]})
        _draw_image(ax0, image, result)
    else:
        fig = Figure(figsize=(7.5, 5.0))
        ax1 = fig.subplots()
    _draw_mtf(ax1, result)
    fig.suptitle((f"{title}: " if title else "") + "MTF from the slanted edges found (no truth file)")
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
