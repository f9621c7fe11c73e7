"""The one place where focal-plane, ground and pixel scales meet.

Spatial frequency in satchain always says where it lives:

* ``f_cy_per_mm`` -- cycles per millimetre in the focal plane (the optics convention);
* ``f_cy_per_m_ground`` -- cycles per metre on the ground;
* ``f_cy_per_px`` -- cycles per detector pixel (or per output sample).

A *cycle* and a *line pair* are the same thing (one bright and one dark bar); a *line* is half a
cycle. The reference paper mixes "L/mm" and "LP/m" in its Table 1 (see the README): functions that
deal in lines say so in their name, and nothing else in satchain accepts lines.

Geometry is the nadir pinhole mapping: a length ``x_fp`` in the focal plane images a ground length
``x_ground = x_fp * range_m / focal_length_m``, so frequencies scale the other way.

Examples
--------
>>> round(float(ground_to_focal_cy_per_mm(1.0, focal_length_m=6.804, range_m=567e3)), 3)
83.333
>>> round(nyquist_cy_per_mm(5.88e-6), 2)
85.03
"""

from __future__ import annotations

import numpy as np

from satchain._validate import check_positive

MM_PER_M = 1e3
M_PER_INCH = 0.0254

__all__ = [
    "cy_per_mm_to_cy_per_px",
    "cy_per_px_to_cy_per_mm",
    "cy_per_m_ground_to_cy_per_px",
    "cy_per_px_to_cy_per_m_ground",
    "focal_to_ground_cy_per_m",
    "ground_to_focal_cy_per_mm",
    "gsd_m",
    "inches_to_m",
    "line_pairs_to_lines",
    "lines_to_line_pairs",
    "m_to_inches",
    "nyquist_cy_per_mm",
    "period_m_to_cy_per_m",
]


def focal_to_ground_cy_per_m(f_cy_per_mm, *, focal_length_m: float, range_m: float):
    """Focal-plane frequency (cy/mm) -> ground frequency (cy/m).

    ``f_ground = f_focal * focal_length / range``: a focal-plane period of ``p`` mm is a ground
    period of ``p * 1e-3 * range / focal_length`` m.

    Examples
    --------
    >>> round(float(focal_to_ground_cy_per_m(83.3333, focal_length_m=6.804, range_m=567e3)), 4)
    1.0
    """
    check_positive("focal_length_m", focal_length_m)
    check_positive("range_m", range_m)
    return np.asarray(f_cy_per_mm, dtype=float) * MM_PER_M * focal_length_m / range_m


def ground_to_focal_cy_per_mm(f_cy_per_m_ground, *, focal_length_m: float, range_m: float):
    """Ground frequency (cy/m) -> focal-plane frequency (cy/mm); inverse of :func:`focal_to_ground_cy_per_m`.

    Examples
    --------
    >>> round(float(ground_to_focal_cy_per_mm(0.5, focal_length_m=6.804, range_m=567e3)), 3)
    41.667
    """
    check_positive("focal_length_m", focal_length_m)
    check_positive("range_m", range_m)
    return np.asarray(f_cy_per_m_ground, dtype=float) * range_m / focal_length_m / MM_PER_M


def cy_per_mm_to_cy_per_px(f_cy_per_mm, *, pitch_m: float):
    """Focal-plane cy/mm -> cycles per pixel of the given pitch.

    Examples
    --------
    >>> float(cy_per_mm_to_cy_per_px(85.0340, pitch_m=5.88e-6).round(4))
    0.5
    """
    check_positive("pitch_m", pitch_m)
    return np.asarray(f_cy_per_mm, dtype=float) * MM_PER_M * pitch_m


def cy_per_px_to_cy_per_mm(f_cy_per_px, *, pitch_m: float):
    """Cycles per pixel -> focal-plane cy/mm (inverse of :func:`cy_per_mm_to_cy_per_px`).

    Examples
    --------
    >>> round(float(cy_per_px_to_cy_per_mm(0.5, pitch_m=5.88e-6)), 3)
    85.034
    """
    check_positive("pitch_m", pitch_m)
    return np.asarray(f_cy_per_px, dtype=float) / (MM_PER_M * pitch_m)


def cy_per_m_ground_to_cy_per_px(f_cy_per_m_ground, *, gsd_m: float):
    """Ground cy/m -> cycles per pixel for a ground sample distance ``gsd_m``.

    Examples
    --------
    >>> float(cy_per_m_ground_to_cy_per_px(1.0, gsd_m=0.5))
    0.5
    """
    check_positive("gsd_m", gsd_m)
    return np.asarray(f_cy_per_m_ground, dtype=float) * gsd_m


def cy_per_px_to_cy_per_m_ground(f_cy_per_px, *, gsd_m: float):
    """Cycles per pixel -> ground cy/m (inverse of :func:`cy_per_m_ground_to_cy_per_px`).

    Examples
    --------
    >>> float(cy_per_px_to_cy_per_m_ground(0.5, gsd_m=0.5))
    1.0
    """
    check_positive("gsd_m", gsd_m)
    return np.asarray(f_cy_per_px, dtype=float) / gsd_m


def lines_to_line_pairs(n_lines):
    """Lines (half periods) -> line pairs = cycles. ``L/mm -> lp/mm`` divides by two.

    Examples
    --------
    >>> float(lines_to_line_pairs(170.0))
    85.0
    """
    return np.asarray(n_lines, dtype=float) / 2.0


def line_pairs_to_lines(n_line_pairs):
    """Line pairs (= cycles) -> lines (half periods): multiplies by two.

    Examples
    --------
    >>> float(line_pairs_to_lines(85.0))
    170.0
    """
    return np.asarray(n_line_pairs, dtype=float) * 2.0


def period_m_to_cy_per_m(period_m):
    """A spatial period (one line pair, m) -> frequency (cy/m). Its own inverse.

    Examples
    --------
    >>> float(period_m_to_cy_per_m(16.0))
    0.0625
    """
    p = np.asarray(period_m, dtype=float)
    if np.any(p <= 0) or not np.all(np.isfinite(p)):
        from satchain.errors import ConfigError

        raise ConfigError(f"period_m = {period_m!r}: must be finite and > 0")
    return 1.0 / p


def nyquist_cy_per_mm(pitch_m: float) -> float:
    """Detector Nyquist frequency ``1 / (2 pitch)`` in focal-plane cy/mm.

    Examples
    --------
    >>> round(nyquist_cy_per_mm(5.88e-6), 3)
    85.034
    """
    return 1.0 / (2.0 * check_positive("pitch_m", pitch_m) * MM_PER_M)


def gsd_m(pitch_m: float, *, focal_length_m: float, range_m: float) -> float:
    """Ground sample distance of a detector pitch at nadir: ``pitch * range / focal_length``.

    Examples
    --------
    >>> round(gsd_m(5.88e-6, focal_length_m=6.804, range_m=567e3), 4)
    0.49
    """
    return (
        check_positive("pitch_m", pitch_m)
        * check_positive("range_m", range_m)
        / check_positive("focal_length_m", focal_length_m)
    )


def m_to_inches(length_m):
    """Metres -> inches (GIQE equations take GSD in inches).

    Examples
    --------
    >>> round(float(m_to_inches(0.0254)), 12)
    1.0
    """
    return np.asarray(length_m, dtype=float) / M_PER_INCH


def inches_to_m(length_in):
    """Inches -> metres.

    Examples
    --------
    >>> float(inches_to_m(100.0))
    2.54
    """
    return np.asarray(length_in, dtype=float) * M_PER_INCH
