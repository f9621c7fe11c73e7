"""Exact time-domain renders of a slanted edge under line-of-sight motion during a TDI window (independent of
satchain).

Row ``i`` of a pushbroom TDI image integrates over its window ``[i dt, i dt + T]`` (``T = N dt``); a
line-of-sight path ``x(t)`` (px, along the rows) moves the edge of that row by ``x(t)`` while it integrates.
Each row is therefore the time mean, over its window, of an exact static render
(:func:`_render_jitter.render_wobbly_edge`: a Gaussian-blurred step integrated over the square pixel, the edge
of each row at its own position): Gauss-Legendre nodes in time, exact for the smooth sinusoidal paths used
here to rounding.  A path is a sum of sinusoids ``A sin(2 pi f t + phase)`` (a band of jitter is many of them
with random phases).

:func:`motion_factors` gives, from the same path, the two transfer factors the image carries: about each row's
window mean (``per_row``: every row located) and about one straight line through the rows' window means
(``as_imaged``: ISO 12233's straight fit, the rows' displacements folded in).
"""

from __future__ import annotations

import numpy as np
from _render_jitter import _g, render_wobbly_edge

_NODES = 24


def _time_nodes(window_s: float):
    x, w = np.polynomial.legendre.leggauss(_NODES)
    return 0.5 * window_s * (x + 1.0), 0.5 * w


def render_tdi_edge(n_lines, width, *, angle_deg, x0, amp_px, freq_hz, phase_rad, line_time_s, stages,
                    blur_px=0.5, levels=(0.2, 0.8), noise=0.0, seed=0):  # fmt: skip
    """The image (rows = lines in time) of an edge whose position moves by ``sum A sin(2 pi f t + p)`` px."""
    s_k, w_k = _time_nodes(stages * line_time_s)
    img = 0.0
    for s, w in zip(s_k, w_k, strict=True):
        ph = [p + 2 * np.pi * f * s for f, p in zip(freq_hz, phase_rad, strict=True)]
        one, _ = render_wobbly_edge(
            n_lines, width, angle_deg=angle_deg, x0=x0, amp_px=amp_px, freq_hz=freq_hz, phase_rad=ph,
            line_time_s=line_time_s, blur_px=blur_px, levels=levels,
        )  # fmt: skip
        img = img + w * one
    if noise > 0:
        img = img + np.random.default_rng(seed).normal(0.0, noise, img.shape)
    return img


def path_px(n_lines, *, amp_px, freq_hz, phase_rad, line_time_s, stages):
    """(lines, time nodes) of the path at each row's window nodes, and the nodes' weights."""
    s_k, w_k = _time_nodes(stages * line_time_s)
    t = np.arange(n_lines)[:, None] * line_time_s + s_k[None, :]
    x = sum(a * np.sin(2 * np.pi * f * t + p) for a, f, p in zip(amp_px, freq_hz, phase_rad, strict=True))
    return x, w_k


def motion_factors(f_normal, angle_deg, **path):
    """(per_row, as_imaged): ``|mean_i mean_t exp(2 pi i nu (x_i(t) - ref_i))|`` at ``nu = f cos(tilt)`` (the
    motion along the row seen on the normal), ``ref_i`` each row's window mean, or the straight least-squares
    line through those means."""
    x, w = path_px(**path)
    d = x @ w
    rows = np.arange(d.size)
    line = np.polyval(np.polyfit(rows, d, 1), rows)
    nu = np.asarray(f_normal, float) * np.cos(np.radians(angle_deg))
    out = []
    for ref in (d, line):
        e = np.exp(2j * np.pi * nu[:, None, None] * (x - ref[:, None])[None])
        out.append(np.abs(np.mean(e @ w, axis=1)))
    return out[0], out[1]


def render_tdi_alt_edge(n_rows, n_cols, *, angle_deg, amp_px, freq_hz, phase_rad, line_time_s, stages, blur_px=0.35):
    """A near-horizontal (ALT) edge whose rows the path moves along y while they integrate (each row's pixels
    integrated over their height; the tilt inside a pixel left out): (image, each row's window-mean shift)."""
    s_k, w_k = _time_nodes(stages * line_time_s)
    i = np.arange(n_rows)[:, None]
    ye = n_rows / 2 + 0.3 + np.arange(n_cols)[None, :] * np.tan(np.radians(angle_deg))
    img, shift = 0.0, 0.0
    for s, w in zip(s_k, w_k, strict=True):
        o = sum(a * np.sin(2 * np.pi * f * (i * line_time_s + s) + p)
                for a, f, p in zip(amp_px, freq_hz, phase_rad, strict=True))  # fmt: skip
        e = ye - o
        img = img + w * blur_px * (_g((i + 0.5 - e) / blur_px) - _g((i - 0.5 - e) / blur_px))
        shift = shift + w * o[:, 0]
    return 0.2 + 0.6 * img, shift
