"""The line of sight of a run formed in time (:mod:`satchain.engine.timepath`): the path over the scan and what
each image row saw of it (its window mean: the row's displacement). matplotlib's object API only (no pyplot)."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from satchain.report._save import save_figure
from satchain.report._style import axis_band_in, place_grid, title_band_in
from satchain.report.compare_plots import rc_for

__all__ = ["edge_tracks", "plot_line_of_sight", "row_displacements"]

_MAX_POINTS = 20000


def row_displacements(tp, n_rows: int) -> tuple[np.ndarray, np.ndarray]:
    """(dy, dx): each output row's window mean of the path, detector pixels (its displacement, drifts included).

    Examples
    --------
    >>> from satchain import load_preset
    >>> from satchain.engine.timepath import time_path
    >>> tp = time_path(load_preset("ankarasat3").replace({"motion.line_rate_error": 0.05}), 10)
    >>> dy, dx = row_displacements(tp, 10)
    >>> round(float(dy[1] - dy[0]), 6), float(dx.max())
    (0.05, 0.0)
    """
    from satchain.tf.pushbroom import window_means

    k, m = tp.window_samples, tp.samples_per_line
    dy, dx = (window_means(d[: (n_rows - 1) * m + k], m, k) for d in (tp.dy, tp.dx))
    return dy, dx


def _detrend(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``y`` less its least-squares straight line in ``x`` (the edge's tilt, the shear's steady part)."""
    return y - np.polyval(np.polyfit(x, y, 1), x)


def edge_tracks(edges: list[dict]) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """``(id, rows, x)`` of every near-vertical (ACT) edge of a run's summaries with per-line positions: where
    each image row crosses it, less the edge's straight line (what the line of sight moved it by)."""
    out = []
    for e in edges:
        lines, pos = e.get("lines"), e.get("edge_position_px")
        if e.get("direction") != "ACT" or not lines or not pos:
            continue
        rows = np.asarray(lines, float)
        x = np.asarray([np.nan if v is None else v for v in pos], float)
        ok = np.isfinite(x)
        if np.count_nonzero(ok) >= 8:
            out.append((str(e["id"]), rows[ok], _detrend(rows[ok], x[ok])))
    return out


def plot_line_of_sight(tp, n_rows: int, path: Path, edges: list[dict] | None = None) -> None:
    """The line of sight (ACT, ALT) against time over the scan, each row's displacement, and, given the run's
    edge summaries, where each row crosses every near-vertical edge against the ACT displacement predicted
    for those rows (both less their straight lines: an edge's position moves by the row's ACT displacement)."""
    t = (np.arange(tp.dy.size) + 0.5) * tp.line_time_s / tp.samples_per_line * 1e3  # ms
    step = max(1, tp.dy.size // _MAX_POINTS)
    dy, dx = row_displacements(tp, n_rows)
    rows = np.arange(n_rows)
    tracks = edge_tracks(edges or [])
    with matplotlib.rc_context(rc_for(9)):
        fig = Figure(figsize=(9, 8.5 if tracks else 6), dpi=100)  # a fixed layout in inches (_style.place_grid)
        axes = [fig.add_axes((0, 0, 1, 1)) for _ in range(3 if tracks else 2)]
        a, b = axes[0], axes[1]
        a.plot(t[::step], tp.dx[::step], lw=0.8, label="ACT (x)")
        a.plot(t[::step], tp.dy[::step], lw=0.8, label="ALT (y)")
        a.set_xlabel("time from the start of row 0's TDI window (ms)")
        a.set_ylabel("line of sight (px)")
        a.set_title(f"Line of sight over the scan ({tp.stages} TDI stages x {tp.line_time_s * 1e6:.1f} us lines)")
        a.grid(alpha=0.3)
        a.legend(loc="upper right")
        b.plot(rows, dx - rows * tp.drift_px[0], lw=1.0, label="ACT, less the Earth-rotation shear")
        b.plot(rows, dy - rows * tp.drift_px[1], lw=1.0, label="ALT, less the along-track scale")
        b.set_xlabel("image row")
        b.set_ylabel("row displacement (px)")
        b.set_title("What each row saw: the window mean of the line of sight (rows shift by it; the rest blurs)")
        b.grid(alpha=0.3)
        b.legend(loc="upper right")
        if tracks:
            c = axes[2]
            for ident, r, x in tracks:
                sel = r.astype(int)
                c.plot(r, x, ".", ms=3, label=f"edge {ident}: measured crossing")
                c.plot(r, -_detrend(r, dx[sel]), lw=1.0, label=f"edge {ident}: predicted (- ACT displacement)")
            c.set_xlabel("image row")
            c.set_ylabel("edge position, detrended (px)")
            c.set_title("Per-line edge positions of the near-vertical edges against the predicted line of sight")
            c.grid(alpha=0.3)
            c.legend(loc="upper right", ncols=2)
        band = axis_band_in()
        place_grid(fig, [[ax] for ax in axes], top=title_band_in(), bottom=band, vgap=band + title_band_in())
        save_figure(fig, path, dpi=100)
