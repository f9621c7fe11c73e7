"""Staggered arrays (SPOT-5's "supermode"): two arrays of pitch ``p`` offset by half a pixel along and across
track, combined onto the grid of pitch ``p / 2``.

The two arrays sample the focal-plane image on a quincunx lattice: basis ``(p, 0)`` and ``(p/2, p/2)``, half the
points of the ``p / 2`` grid (those with ``i + j`` even, ``(i, j)`` the ``p / 2`` grid's indices). Its reciprocal
lattice is spanned by ``(1/p, -1/p)`` and ``(0, 2/p)``: the nearest alias copies sit at ``(+-1/p, +-1/p)``, so the
unaliased band is the diamond ``|f_x| + |f_y| <= 1/p``: the Nyquist along each axis is ``1/p`` (twice a single
array's ``1/(2p)``), along the diagonals ``1/(sqrt(2) p)`` radially. The pixel's own aperture stays ``p`` wide: its
sinc is 0 at ``1/p`` (100 % fill), so the combined image gains resolution between ``1/(2p)`` and ``1/p``, not at
``1/p`` itself (Latry & Rouge 2003, "Super resolution: quincunx sampling and fusion processing", IGARSS).

The combination stated here fills each missing point of the ``p / 2`` grid with the mean of its four lattice
neighbours (``(+-p/2, 0)``, ``(0, +-p/2)``) and keeps the measured points as they are ("quincunx bilinear").
Its transfer function on the combined grid, for a signal band-limited inside the diamond, is

    ``H(f) = 1/2 + cos(pi p f_x) / 4 + cos(pi p f_y) / 4``

(half the points pass unchanged, half are the four-neighbour mean), 1 at ``f = 0``, 1/2 at ``(1/p, 0)``; SPOT-5
followed it with a restoration filter, left to the user here. Frequencies are on the focal plane in cy/mm, as
in :mod:`satchain.tf.detector`.
"""

from __future__ import annotations

import math

import numpy as np

from satchain._validate import check_range
from satchain.units import MM_PER_M

__all__ = [
    "COMBINATIONS",
    "alias_offsets_cy_per_mm",
    "combination_otf",
    "nyquist_cy_per_mm",
    "unaliased",
]

#: the combinations of the two arrays onto the half-pitch grid that satchain models
COMBINATIONS = ("quincunx_bilinear",)


def _p_mm(pitch_m: float) -> float:
    return check_range("pitch_m", pitch_m, 0, None, lo_open=True) * MM_PER_M


def nyquist_cy_per_mm(pitch_m: float, *, direction: str = "axis") -> float:
    """The combined sampling's Nyquist (the edge of the unaliased diamond): ``1/p`` along an axis (ACT or ALT),
    ``1/(sqrt(2) p)`` radially along a diagonal.

    Examples
    --------
    >>> round(nyquist_cy_per_mm(5.88e-6), 2)      # twice a single 5.88 um array's 85.03 cy/mm
    170.07
    >>> round(nyquist_cy_per_mm(5.88e-6, direction="diagonal"), 2)
    120.26
    """
    if direction not in ("axis", "diagonal"):
        raise ValueError(f"direction = {direction!r}: must be 'axis' or 'diagonal'")
    n = 1.0 / _p_mm(pitch_m)
    return n if direction == "axis" else n / math.sqrt(2.0)


def alias_offsets_cy_per_mm(pitch_m: float, *, order: int = 1) -> np.ndarray:
    """The reciprocal lattice of the quincunx sampling (cy/mm, ``(f_x, f_y)`` rows), without the origin: every
    ``m (1/p, -1/p) + n (0, 2/p)`` with ``|m|, |n| <= order`` -- where a frequency ``f`` appears again as
    ``f - k``. Sorted by distance from the origin.

    Examples
    --------
    >>> k = alias_offsets_cy_per_mm(1e-3)          # p = 1 mm: the nearest copies at (+-1, +-1) cy/mm
    >>> sorted(map(tuple, k[:4].round(6).tolist()))
    [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)]
    """
    p = _p_mm(pitch_m)
    b1, b2 = np.array([1.0 / p, -1.0 / p]), np.array([0.0, 2.0 / p])
    pts = [m * b1 + n * b2 for m in range(-order, order + 1) for n in range(-order, order + 1) if (m, n) != (0, 0)]
    out = np.array(pts)
    return out[np.argsort(np.hypot(out[:, 0], out[:, 1]), kind="stable")]


def unaliased(fx_cy_per_mm, fy_cy_per_mm, *, pitch_m: float) -> np.ndarray:
    """True where ``(f_x, f_y)`` lies inside the combined sampling's unaliased diamond ``|f_x| + |f_y| < 1/p``."""
    p = _p_mm(pitch_m)
    fx, fy = np.broadcast_arrays(np.asarray(fx_cy_per_mm, float), np.asarray(fy_cy_per_mm, float))
    return np.abs(fx) + np.abs(fy) < 1.0 / p


def combination_otf(fx_cy_per_mm, fy_cy_per_mm, *, pitch_m: float, method: str = "quincunx_bilinear") -> np.ndarray:
    """The transfer function of combining the two arrays onto the ``p / 2`` grid (``method`` in
    :data:`COMBINATIONS`): ``1/2 + cos(pi p f_x)/4 + cos(pi p f_y)/4`` for the quincunx bilinear fill.

    Examples
    --------
    >>> float(combination_otf(0.0, 0.0, pitch_m=1e-3))
    1.0
    >>> float(combination_otf(1.0, 0.0, pitch_m=1e-3))     # at the combined Nyquist along x (1/p)
    0.5
    """
    if method not in COMBINATIONS:
        raise ValueError(f"method = {method!r}: must be one of {', '.join(COMBINATIONS)}")
    p = _p_mm(pitch_m)
    fx, fy = np.broadcast_arrays(np.asarray(fx_cy_per_mm, float), np.asarray(fy_cy_per_mm, float))
    return 0.5 + 0.25 * np.cos(np.pi * p * fx) + 0.25 * np.cos(np.pi * p * fy)
