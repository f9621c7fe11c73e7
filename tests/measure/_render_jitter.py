"""Exact renders of a straight edge whose position wobbles line by line (independent of satchain).

A pushbroom camera forms each image line at its own instant: a line-of-sight oscillation shifts whole lines.
The edge of line ``y`` (row, or column for an ALT edge) crosses it at

    x_e(y) = x0 + y tan(theta) + A sin(2 pi f y line_time + phase),

and each pixel is the exact area average over its unit square of a Gaussian-blurred step (normal blur
``blur_px``, so ``sigma_x = blur_px / cos theta`` along the line) centred on that line's edge, tilted by
``theta`` inside the pixel.  With ``G(z) = z Phi(z) + phi(z)`` (the antiderivative of Phi) and
``H(z) = ((z^2 + 1) Phi(z) + z phi(z)) / 2`` (that of G):

    mean over x in [k - 1/2, k + 1/2] of Phi((x - e) / s) = s [G((k + 1/2 - e) / s) - G((k - 1/2 - e) / s)],

and the mean of that over the pixel's height (``e`` linear in y' with slope tan theta) is a second difference of
``H`` divided by ``tan theta``.  A line's edge profile is symmetric about ``x_e(y)``: the true position.
"""

from __future__ import annotations

import numpy as np
from scipy.special import ndtr


def _g(z):
    return z * ndtr(z) + np.exp(-0.5 * z * z) / np.sqrt(2 * np.pi)


def _h(z):
    return 0.5 * ((z * z + 1.0) * ndtr(z) + z * np.exp(-0.5 * z * z) / np.sqrt(2 * np.pi))


def edge_truth(n_lines: int, *, angle_deg: float, x0: float, amp_px=(), freq_hz=(), phase_rad=(), line_time_s=1e-3):
    """The true edge position of every line (px, line index = time / line_time)."""
    y = np.arange(n_lines, dtype=float)
    x = x0 + y * np.tan(np.radians(angle_deg))
    for a, f, p in zip(amp_px, freq_hz, phase_rad, strict=True):
        x = x + a * np.sin(2 * np.pi * f * y * line_time_s + p)
    return x


def render_wobbly_edge(
    n_lines: int,
    width: int,
    *,
    angle_deg: float,
    x0: float,
    amp_px=(),
    freq_hz=(),
    phase_rad=(),
    line_time_s: float = 1e-3,
    blur_px: float = 0.6,
    levels=(0.2, 0.8),
    noise: float = 0.0,
    seed: int = 0,
    transpose: bool = False,
):
    """(image, true positions): the edge rises from ``levels[0]`` to ``levels[1]`` along +x; rows are lines.

    ``transpose`` returns the image transposed (a near-horizontal, ALT edge whose lines are the columns).
    """
    xe = edge_truth(
        n_lines, angle_deg=angle_deg, x0=x0, amp_px=amp_px, freq_hz=freq_hz, phase_rad=phase_rad,
        line_time_s=line_time_s,
    )  # fmt: skip
    tan_t = np.tan(np.radians(angle_deg))
    s = blur_px / np.cos(np.radians(angle_deg))
    k = np.arange(width, dtype=float)[None, :]
    e = xe[:, None]  # edge position at the line's centre; inside the pixel it moves by tan_t per px of y
    if abs(tan_t) < 1e-6:
        frac = s * (_g((k + 0.5 - e) / s) - _g((k - 0.5 - e) / s))
    else:
        d2 = 0.0
        for sx, sy in ((0.5, -0.5), (-0.5, 0.5), (-0.5, -0.5), (0.5, 0.5)):
            sign = 1.0 if (sx > 0) == (sy < 0) else -1.0
            d2 = d2 + sign * _h((k + sx - e - sy * tan_t) / s)
        frac = s * s / tan_t * d2
    img = levels[0] + (levels[1] - levels[0]) * frac
    if noise > 0:
        img = img + np.random.default_rng(seed).normal(0.0, noise, img.shape)
    return (img.T if transpose else img), xe
