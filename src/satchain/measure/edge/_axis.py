"""Where a slanted-edge measurement puts its edge line and its frequency axis (used by
:mod:`satchain.measure.edge`).

Edge line.  A known line (a point and an angle, e.g. the joint line of two collinear halves of one target edge,
fitted over twice the baseline) can replace the line fitted in the region: the ESF is then projected on it.

Frequency axis.  satchain measures the MTF along the edge normal (``"normal"``, ISO 12233).  MTF_Estimator
(FidMTF, the QGIS plugin used in CEOS work) projects the pixels on the image row instead (``"row"``: the
horizontal distance ``x - x_edge(y)`` for a near-vertical edge, the vertical one for a near-horizontal edge).
For an edge tilted by ``t`` from the nearest pixel axis the row distance is ``x = d / cos t`` (``d`` along the
normal), so the row ESF is ``E_row(x) = E(x cos t)`` and its MTF is

    MTF_row(f) = MTF_normal(f / cos t),      i.e.  MTF_row(f cos t) = MTF_normal(f):

the row axis is the normal axis scaled by ``cos t``; a feature at ``f`` cy/px along the normal appears at
``f cos t`` along the row.  At the Baotou target's 16.8 deg, ``cos t = 0.957``: the row axis is 4.3 % shorter, and
the row MTF at Nyquist is the normal MTF at 0.5 / 0.957 = 0.522 cy/px (lower, where the MTF falls).
"""

from __future__ import annotations

import math

import numpy as np

from satchain.errors import InputError

__all__ = ["FREQUENCY_AXES", "check_axis", "line_coef", "on_axis", "oversampled_f_max"]

#: The frequency axes of :func:`satchain.measure.edge.measure_edge` (``frequency_axis``).
FREQUENCY_AXES = ("normal", "row")
_STEP = 0.005  # the output frequency step (cy/px), as edge.py's


def check_axis(frequency_axis: str) -> str:
    """``frequency_axis`` checked: one of :data:`FREQUENCY_AXES`."""
    axis = str(frequency_axis).strip().lower()
    if axis not in FREQUENCY_AXES:
        raise InputError(f"frequency_axis = {frequency_axis!r}: must be one of {', '.join(FREQUENCY_AXES)}")
    return axis


def oversampled_f_max(f_max: float, axis: str, limit: float) -> float:
    """The normal-axis band to measure so that the row axis reaches ``f_max`` at any tilt up to 45 deg."""
    return f_max if axis == "normal" else min(f_max * math.sqrt(2.0), limit)


def line_coef(edge_line, roi, transposed: bool) -> np.ndarray:
    """The edge line ``(x, y, angle_deg)`` (a point in the image, ``roi`` offset included, and the angle from
    the y axis as :func:`~satchain.measure.edge.measure_edge` gives it) as the degree-1 polynomial
    ``c = s a + b`` of the oriented region (``a`` along the edge: y for ACT, x for ALT; ``c`` across it)."""
    try:
        x, y, ang = (float(v) for v in edge_line)
    except (TypeError, ValueError):
        raise InputError(f"edge_line = {edge_line!r}: must be (x, y, angle_deg)") from None
    if not all(map(math.isfinite, (x, y, ang))):
        raise InputError(f"edge_line = {edge_line!r}: must be finite")
    if hasattr(roi, "to_roi"):
        roi = roi.to_roi()
    x0, y0 = (0, 0) if roi is None else (int(roi[0]), int(roi[1]))
    t = math.radians(ang)
    if transposed:  # ALT: a = x, c = y, dy/dx = cos t / sin t
        a, c, s = x - x0, y - y0, math.cos(t) / math.sin(t) if math.sin(t) != 0 else math.inf
    else:  # ACT: a = y, c = x, dx/dy = tan t
        a, c, s = y - y0, x - x0, math.tan(t)
    if not abs(s) <= 1.0 + 1e-9:
        raise InputError(
            f"edge_line = {edge_line!r}: the angle is more than 45 deg from the region's "
            f"{'ALT' if transposed else 'ACT'} edge"
        )
    return np.array([s, c - s * a])


def on_axis(f, mtf, sigma, slope: float, axis: str, f_max: float):
    """The normal-axis MTF (and its 1-sigma) on ``axis``: (f, mtf, sigma, scale), ``f_row = scale f_normal``.

    ``slope`` is the edge's slope against its nearest pixel axis (``tan t``); ``scale = cos t`` (1 on the
    normal axis).  The row axis keeps the output step and stops at ``f_max`` or where ``f / cos t`` leaves the
    measured normal band.
    """
    if axis == "normal":
        return f, mtf, sigma, 1.0
    scale = 1.0 / math.hypot(1.0, slope)
    top = min(f_max, float(f[-1]) * scale)
    fr = np.arange(0.0, top + _STEP / 2, _STEP)
    fr = fr[fr <= top + 1e-12]
    return fr, np.interp(fr / scale, f, mtf), np.interp(fr / scale, f, sigma), scale
