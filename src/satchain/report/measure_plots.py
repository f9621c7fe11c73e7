"""Figures of image-quality measurements: edge ESF/LSF/MTF, star MTF per direction, bars CTF/MTF, wedge scan,
line-of-sight motion from an edge (jitter).

Each function takes the result object of :mod:`satchain.measure` and writes one PNG atomically.

Examples
--------
>>> import os, tempfile
>>> from satchain.measure import measure_edge
>>> y, x = np.mgrid[0:64, 0:64]
>>> img = 0.1 + 0.8 / (1 + np.exp(-((x - 31.6) * np.cos(0.1) - (y - 31.5) * np.sin(0.1)) / 0.6))
>>> path = os.path.join(tempfile.mkdtemp(), "edge.png")
>>> plot_edge(measure_edge(img), path)
>>> os.path.getsize(path) > 10_000
True
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from satchain.report._save import save_figure

__all__ = ["plot_bars", "plot_edge", "plot_jitter", "plot_star", "plot_wedge"]

_DIRECTION_STYLE: dict[str, dict[str, Any]] = {
    "ACT": dict(color="tab:blue"),
    "ALT": dict(color="tab:red"),
    "D45": dict(color="tab:green", linestyle="--"),
    "D135": dict(color="tab:purple", linestyle="--"),
}


def _title(prefix: str, default: str) -> str:
    return f"{prefix}: {default}" if prefix else default


def _nyquist(ax, top: float = 1.05) -> None:
    ax.axvline(0.5, color="gray", lw=1)
    ax.text(0.5, top, " Nyquist", color="gray", va="top", fontsize=8)


def plot_edge(result, path: str | Path, *, title: str = "", pixel_m: float | None = None) -> None:
    """ESF, LSF and MTF (along the edge normal) of an :class:`~satchain.measure.edge.EdgeResult` (in cycles per
    pixel; ``pixel_m`` is accepted so that every kind's figure has one signature)."""
    fig = Figure(figsize=(14, 4.2))
    axes = fig.subplots(1, 3)
    x = np.asarray(result.esf_x_px)
    near = np.abs(x) <= 12
    axes[0].plot(x[near], np.asarray(result.esf)[near], color="black")
    axes[0].set_xlabel("distance from the edge along its normal (px)")
    axes[0].set_ylabel("ESF (normalised)")
    axes[1].plot(x[near], np.asarray(result.lsf)[near], color="tab:blue")
    axes[1].set_xlabel("distance from the edge along its normal (px)")
    axes[1].set_ylabel("LSF (1/px)")
    f, m = np.asarray(result.f_cy_per_px), np.asarray(result.mtf)
    axes[2].plot(f, m, color="black", label=f"MTF ({result.direction})")
    axes[2].plot([0.5], [result.mtf_at_nyquist], "o", color="tab:red", label=f"at Nyquist {result.mtf_at_nyquist:.3f}")
    if result.mtf50_cy_per_px is not None:
        axes[2].plot(
            [result.mtf50_cy_per_px],
            [0.5],
            "s",
            color="tab:green",
            label=f"MTF50 {result.mtf50_cy_per_px:.3f}",
        )
    _nyquist(axes[2], top=max(1.05, float(np.max(m)) + 0.05))
    axes[2].set_xlim(0, f[-1])
    axes[2].set_ylim(0, max(1.1, float(np.max(m)) + 0.1))
    axes[2].set_xlabel("spatial frequency along the edge normal (cy/px)")
    axes[2].set_ylabel("MTF")
    axes[2].legend(fontsize=8)
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.suptitle(_title(title, f"slanted edge {result.angle_deg:.2f} deg ({result.direction}), RER {result.rer:.3f}"))
    fig.tight_layout()
    save_figure(fig, path, dpi=110)


def plot_star(result, path: str | Path, *, title: str = "", pixel_m: float | None = None) -> None:
    """MTF per direction (ACT, ALT, diagonals) of a :class:`~satchain.measure.star.StarResult` (in cycles per
    pixel; ``pixel_m`` is accepted so that every kind's figure has one signature)."""
    fig = Figure(figsize=(7, 4.6))
    ax = fig.subplots()
    f = np.asarray(result.f_cy_per_px)
    for k, m in result.mtf.items():
        ax.plot(f, np.asarray(m, dtype=float), label=k, **_DIRECTION_STYLE.get(k, {}))
    _nyquist(ax)
    ax.set_xlim(0, f.max())
    ax.set_ylim(0, 1.1)
    ax.set_xlabel("spatial frequency along the tangent (cy/px)")
    ax.set_ylabel("MTF")
    ax.set_title(_title(title, f"Siemens star, {result.cycles} cycles: MTF per direction"))
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    save_figure(fig, path, dpi=110)


def plot_bars(result, path: str | Path, *, title: str = "", pixel_m: float | None = None) -> None:
    """CTF per bar group and the MTF from the inverse Coltman series (a ``BarsResult``; in cycles per pixel,
    ``pixel_m`` is accepted so that every kind's figure has one signature)."""
    fig = Figure(figsize=(7, 4.6))
    ax = fig.subplots()
    f = np.asarray(result.f_cy_per_px)
    order = np.argsort(f)
    ax.plot(f[order], np.asarray(result.ctf)[order], "o-", color="tab:red", label="CTF (measured)")
    ax.plot(f[order], np.asarray(result.mtf)[order], "s--", color="black", label="MTF (inverse Coltman series)")
    _nyquist(ax)
    ax.set_xlim(0, max(0.55, float(f.max()) * 1.05))
    ax.set_ylim(0, 1.15)
    ax.set_xlabel("spatial frequency = 1 / period (cy/px)")
    ax.set_ylabel("CTF, MTF")
    ax.set_title(_title(title, f"bar target ({result.direction}): CTF and MTF"))
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    save_figure(fig, path, dpi=110)


def plot_wedge(result, path: str | Path, *, title: str = "", pixel_m: float | None = None) -> None:
    """The paper's contrast scan: contrast vs line width along the wedge, the threshold and the point found.

    The x axis is the line width (half a period) in metres when ``pixel_m`` is given, else in pixels, running
    from the wide end (left) to the narrow end, as the scan does.
    """
    scale, unit = (pixel_m, "m") if pixel_m else (1.0, "px")
    lw = np.asarray(result.line_width_px) * scale
    fig = Figure(figsize=(8, 4.6))
    ax = fig.subplots()
    ax.plot(lw, np.asarray(result.contrast), color="black", label="contrast across the stripes")
    ax.axhline(result.threshold, color="tab:red", lw=1, ls="--", label=f"threshold {result.threshold:.0%}")
    if result.resolved_line_width_px is not None:
        w = result.resolved_line_width_px * scale
        ax.axvline(w, color="tab:green", lw=1)
        ax.plot([w], [result.threshold], "o", color="tab:green", label=f"resolved line width {w:.3g} {unit}")
    ax.set_xlim(lw.max(), lw.min())
    ax.set_ylim(0, 1.05)
    ax.set_xlabel(f"line width along the wedge ({unit}); scan from the wide end")
    ax.set_ylabel("contrast (max - min) / (max + min)")
    ax.set_title(_title(title, f"hyperbolic wedge contrast scan ({result.direction} resolution)"))
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    save_figure(fig, path, dpi=110)


def plot_jitter(result, path: str | Path, *, title: str = "", pixel_m: float | None = None) -> None:
    """Edge positions against the line (the tilt removed) with the fitted sinusoids, and the periodogram with the
    detection limit, of a :class:`~satchain.measure.jitter.JitterResult` (``pixel_m``: the common signature)."""
    fig = Figure(figsize=(14, 4.4))
    axes = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.6, 1.0]})
    lines = np.asarray(result.lines, dtype=float)
    det = np.asarray(result.detrended_px, dtype=float)
    mdl = np.asarray(result.model_px, dtype=float)
    ok = np.isfinite(det)
    axes[0].plot(lines[ok], det[ok], ".", ms=2, color="0.45", label="edge position - tilt (px)")
    if result.peaks:
        axes[0].plot(lines[ok], mdl[ok], color="tab:red", lw=1.2, label="fitted sinusoids")
    axes[0].set_xlabel(f"image line (row; line time {result.line_time_s:.4g} s)")
    axes[0].set_ylabel(f"{result.direction} position, detrended (px)")
    axes[0].legend(fontsize=8, loc="upper right")
    f = np.asarray(result.periodogram_frequency_hz, dtype=float)
    axes[1].plot(f, np.asarray(result.periodogram_amplitude_px, dtype=float), color="black", lw=0.8)
    limit = f"detection limit {result.detection_limit_px:.3g} px (false alarm {result.false_alarm:g})"
    axes[1].axhline(result.detection_limit_px, color="tab:orange", ls="--", lw=1, label=limit)
    for p in result.peaks:
        axes[1].plot([p.frequency_hz], [p.amplitude_px], "v", color="tab:red")
        text = f"{p.frequency_hz:.4g} Hz\n{p.amplitude_px:.3g} px"
        axes[1].annotate(text, (p.frequency_hz, p.amplitude_px), fontsize=7, xytext=(4, 4), textcoords="offset points")
    axes[1].set_xlim(0, result.nyquist_hz)
    axes[1].set_yscale("log")
    top = max([result.detection_limit_px, *(p.amplitude_px for p in result.peaks)])
    if top > 0:  # near 0 Hz a sinusoid is nearly the tilt: its amplitude there is not a measurement
        axes[1].set_ylim(top=3.0 * top)
    axes[1].set_xlabel("frequency (Hz; right edge = line-rate Nyquist)")
    axes[1].set_ylabel("least-squares sinusoid amplitude (px)")
    axes[1].legend(fontsize=8)
    for ax in axes:
        ax.grid(alpha=0.3)
    head = ", ".join(f"{p.amplitude_px:.3g} px at {p.frequency_hz:.4g} Hz" for p in result.peaks) or "no peak"
    fig.suptitle(_title(title, f"line-of-sight motion from an edge ({result.direction}): {head}"))
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
