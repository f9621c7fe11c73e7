"""Exact renders for the clipping tests and benchmark: edges, gratings and stars integrated over each pixel
(Gauss-Legendre), so their plateaus are exactly flat only where the target is."""

from __future__ import annotations

import numpy as np
from scipy.special import ndtr

_U, _W = np.polynomial.legendre.leggauss(8)
_U, _W = _U / 2, _W / 2  # nodes and weights on one pixel, [-1/2, 1/2]


def render_edge(angle_deg, blur_px, phase, *, lo=0.05, hi=0.8, shape=(80, 80)):
    """Edge through the centre + ``phase`` with normal (cos t, -sin t), Gaussian blur ``blur_px``, pixel
    integrated; dark ``lo``, bright ``hi``."""
    ny, nx = shape
    t = np.deg2rad(angle_deg)
    y, x = np.mgrid[0:ny, 0:nx].astype(float)
    xc, yc = (nx - 1) / 2 + phase[0], (ny - 1) / 2 + phase[1]
    acc = np.zeros(shape)
    for ux, wx in zip(_U, _W, strict=True):
        for uy, wy in zip(_U, _W, strict=True):
            acc += wx * wy * ndtr(((x + ux - xc) * np.cos(t) - (y + uy - yc) * np.sin(t)) / blur_px)
    return lo + (hi - lo) * acc


def render_grating(period_px, blur_px, phase, *, lo=0.1, hi=0.7, shape=(20, 96)):
    """Square wave along x (bright bars ``[phase + k p, phase + (k + 1/2) p)``), Gaussian blur, pixel
    integrated along x; the bars run along y."""
    x = np.arange(shape[1], dtype=float)
    prof = np.zeros(shape[1])
    for u, w in zip(
        np.polynomial.legendre.leggauss(16)[0] / 2, np.polynomial.legendre.leggauss(16)[1] / 2, strict=True
    ):
        for k in range(-2, int(shape[1] / period_px) + 3):
            a = phase + k * period_px
            prof += w * (ndtr((x + u - a) / blur_px) - ndtr((x + u - a - period_px / 2) / blur_px))
    return np.tile(lo + (hi - lo) * prof, (shape[0], 1))


def render_star(n, center, blur_px, *, mean=100.0, amp=40.0, size=81):
    """Sinusoidal star of ``n`` cycles whose local grating (n / 2 pi r cy/px) is attenuated by a Gaussian MTF."""
    y, x = np.mgrid[0:size, 0:size].astype(float)
    dx, dy = x - center[0], y - center[1]
    r, th = np.hypot(dx, dy), np.arctan2(dy, dx)
    f = n / (2 * np.pi * np.maximum(r, 1e-9))
    return mean + amp * np.exp(-2 * np.pi**2 * blur_px**2 * f**2) * np.cos(n * th)
