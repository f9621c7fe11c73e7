"""Exact converging-line (wedge) renders for the wedge noise tests and benchmark (independent of satchain).

Stripes run along x (the ``ALT`` layout of :func:`satchain.measure.wedge.measure_wedge`): across y, bright
and dark stripes of equal width ``w(x)`` whose edges sit at ``y = (phase + k) w(x)`` (lines converging on
``y = 0``, as the scene's wedge). Pixel ``[i, j]`` covers ``[j, j+1) x [i, i+1)``. Across the stripes the
pixel value is exact: the box integral over ``[i, i+1]`` of the square wave convolved with a Gaussian of
``blur`` px (the antiderivative of an erf step, ``s (t Phi(t) + phi(t))``); along the stripes it is the mean
of ``sub`` samples across the pixel (the width changes slowly along x). ``blur = 0`` is a sharp wedge.
"""

from __future__ import annotations

import numpy as np
from scipy.special import ndtr


def _step_integral(u, blur: float):
    """Antiderivative of the blurred unit step: ``int_-inf^u Phi(v / blur) dv`` (``max(u, 0)`` when sharp)."""
    if blur <= 0:
        return np.maximum(u, 0.0)
    t = u / blur
    return blur * (t * ndtr(t) + np.exp(-0.5 * t * t) / np.sqrt(2 * np.pi))


def hyperbolic(w0: float, x0: float):
    """Stripe width ``w0 x0 / (x0 + x)`` (px), the scene's hyperbolic wedge."""
    return lambda x: w0 * x0 / (x0 + np.asarray(x, dtype=float))


def linear(w0: float, rate: float):
    """Stripe width ``w0 - rate x`` (px)."""
    return lambda x: w0 - rate * np.asarray(x, dtype=float)


def render_wedge(width, *, rows=48, cols=160, blur=0.0, phase=0.0, dark=0.2, bright=0.8, sub=16) -> np.ndarray:
    """Noise-free wedge image (rows, cols); ``width(x)`` the stripe width in px at column coordinate ``x``."""
    xs = (np.arange(cols * sub) + 0.5) / sub
    w = width(xs)
    k = np.arange(-2, int(np.ceil((rows + 8 * blur + 2) / w.min())) + 2)
    edges = (phase + k[:, None]) * w[None, :]  # (edge, sample): up at even k, down at odd
    sign = np.where(k % 2 == 0, 1.0, -1.0)[:, None]
    y = np.arange(rows + 1, dtype=float)
    cum = np.sum(sign[None] * _step_integral(y[:, None, None] - edges[None], blur), axis=1)
    frac = np.diff(cum, axis=0).reshape(rows, cols, sub).mean(axis=2)  # bright fraction of each pixel
    return dark + (bright - dark) * frac


def widths_at_columns(width, cols: int) -> np.ndarray:
    """Stripe width at each column centre, as ``measure_wedge(line_width_px=...)`` takes it."""
    return np.asarray(width(np.arange(cols) + 0.5), dtype=float)
