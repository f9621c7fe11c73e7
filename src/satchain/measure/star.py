"""Siemens-star MTF (sinusoidal star, ISO 12233:2017 s-SFR style).

A sinusoidal star of ``cycles`` periods per revolution has, at radius ``r`` px, the local spatial frequency
``f = cycles / (2 pi r)`` cy/px along the tangent.  The pixels whose centres fall in an annulus of width
``annulus_px`` around ``r`` are fitted, by least squares at their exact polar angles (no interpolation, which
would add its own blur), with ``a + b cos(n th) + c sin(n th)``; the modulation is ``sqrt(b^2 + c^2) / a`` and
the MTF is modulation / input modulation.

Directions.  The fit is done separately in pairs of opposite 45-deg sectors, one pair per direction of the
*frequency* (the tangent): ``ACT`` (x; sectors above and below the centre), ``ALT`` (y; sectors left and
right), ``D45`` (the diagonal along which x and y increase together) and ``D135`` (the other diagonal).
Angles are measured in image axes (x = column to the right, y = row downwards).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from satchain._validate import check_positive, check_range
from satchain.errors import InputError
from satchain.measure._common import ResultMixin, crop_roi
from satchain.units import cy_per_px_to_cy_per_m_ground

__all__ = ["StarResult", "measure_star", "STAR_DIRECTIONS"]

#: Frequency direction (deg from +x, y downwards) of each reported MTF.
STAR_DIRECTIONS = {"ACT": 0.0, "D45": 45.0, "ALT": 90.0, "D135": 135.0}


@dataclass(frozen=True)
class StarResult(ResultMixin):
    """MTF per direction against frequency (ascending), from a sinusoidal Siemens star.

    ``mtf`` maps each of ``ACT, ALT, D45, D135`` to an array aligned with ``f_cy_per_px``; ``mtf_all`` uses
    every angle.  ``mtf_at_nyquist`` per direction is None where the star does not reach 0.5 cy/px.
    """

    f_cy_per_px: np.ndarray
    radius_px: np.ndarray
    mtf: dict
    mtf_all: np.ndarray
    mtf_at_nyquist: dict
    input_modulation: float
    center_xy_px: tuple[float, float]
    cycles: int
    f_cy_per_m_ground: np.ndarray | None = None


def _extrapolated_modulation(f: np.ndarray, mod: np.ndarray) -> float:
    """Modulation at zero frequency: a straight line through the lowest-frequency points (>= 3)."""
    ok = np.isfinite(mod)
    f, mod = f[ok], mod[ok]
    if f.size < 3:
        return float(np.median(mod)) if f.size else float("nan")
    low = f <= 2.5 * f.min()
    if np.count_nonzero(low) < 3:
        low = np.argsort(f)[:3]
    slope, intercept = np.polyfit(f[low], mod[low], 1)
    return float(intercept) if slope <= 0 else float(np.median(mod[low]))


def measure_star(
    image,
    *,
    cycles: int,
    center=None,
    radius_px: float | None = None,
    roi=None,
    input_modulation: float | None = None,
    annulus_px: float = 1.0,
    f_max_cy_per_px: float = 0.75,
    pixel_m: float | None = None,
) -> StarResult:
    """Measure the MTF per direction from a sinusoidal Siemens star.

    Parameters
    ----------
    image : array_like, 2-D
    cycles : int
        Periods per revolution of the star (>= 4).
    center : (x, y), optional
        Star centre in pixels of the (cropped) image; its geometric centre by default.
    radius_px : float, optional
        Outer radius used; the largest circle inside the region by default.
    roi : (x0, y0, x1, y1), optional
    input_modulation : float, optional
        Modulation (max - min) / (max + min) of the star itself. When not given it is estimated by
        extrapolating the all-direction modulation of the outer radii (the lowest frequencies, up to 2.5 times
        the lowest) linearly to zero frequency -- the MTF of a band-limited system falls linearly there -- so
        the blur at the outer radius does not inflate the whole curve.
    annulus_px : float
        Radial width of the annuli whose pixels are fitted together.
    f_max_cy_per_px : float
        Smallest radius used is ``cycles / (2 pi f_max)``.
    pixel_m : float, optional
        Ground sample distance; adds ``f_cy_per_m_ground``.

    Examples
    --------
    >>> y, x = np.mgrid[0:121, 0:121] - 60.0
    >>> star = 100 + 50 * np.cos(16 * np.arctan2(y, x))
    >>> r = measure_star(star, cycles=16)
    >>> round(float(r.mtf["ACT"][0]), 3), round(r.input_modulation, 6)
    (1.0, 0.5)
    """
    n = int(check_range("cycles", cycles, 4, 10000))
    check_positive("annulus_px", annulus_px)
    f_max = check_range("f_max_cy_per_px", f_max_cy_per_px, 0.0, 2.0, lo_open=True)
    data = crop_roi(image, roi, min_size=16)
    if data.max() == data.min():
        raise InputError(f"image: the region is flat (every pixel = {data.min():g}); no star to measure")
    ny, nx = data.shape
    xc, yc = ((nx - 1) / 2, (ny - 1) / 2) if center is None else (float(center[0]), float(center[1]))
    r_out = min(xc, yc, nx - 1 - xc, ny - 1 - yc) if radius_px is None else float(radius_px)
    r_in = max(n / (2 * np.pi * f_max), 2.0)
    if not r_out > r_in + 3 * annulus_px:
        raise InputError(
            f"radius_px = {r_out:g}: the star must extend beyond {r_in + 3 * annulus_px:g} px "
            f"(the radius where {n} cycles reach f_max = {f_max:g} cy/px)"
        )
    y, x = np.mgrid[0:ny, 0:nx]
    rr = np.hypot(x - xc, y - yc).ravel()
    th = np.arctan2(y - yc, x - xc).ravel()
    v = data.ravel()
    radii = np.arange(r_out - annulus_px / 2, r_in, -annulus_px)
    # position angle of the sectors: tangent (frequency direction) = position + 90 deg
    sector = {k: np.deg2rad(a + 90.0) for k, a in STAR_DIRECTIONS.items()}
    mods = {k: np.empty(radii.size) for k in [*STAR_DIRECTIONS, "all"]}
    for i, r in enumerate(radii):
        sel = np.abs(rr - r) <= annulus_px / 2
        t, val = th[sel], v[sel]
        mods["all"][i] = _modulation(t, val, n)
        for k, a in sector.items():
            dist = np.abs(np.angle(np.exp(2j * (t - a)))) / 2  # angle to the sector axis, both opposite sides
            m = dist <= np.pi / 8
            mods[k][i] = _modulation(t[m], val[m], n) if np.count_nonzero(m) >= 8 else np.nan
    if input_modulation is None:
        m0 = _extrapolated_modulation(n / (2 * np.pi * radii), mods["all"])
    else:
        m0 = check_range("input_modulation", input_modulation, 0.0, None, lo_open=True)
    if not m0 > 1e-4:
        raise InputError("image: no star modulation found at the outer radii (flat region or wrong cycles?)")
    f = n / (2 * np.pi * radii)
    order = np.argsort(f)
    f = f[order]
    mtf = {k: mods[k][order] / m0 for k in STAR_DIRECTIONS}
    nyq = {k: (float(np.interp(0.5, f, m)) if f[0] <= 0.5 <= f[-1] else None) for k, m in mtf.items()}
    return StarResult(
        f_cy_per_px=f,
        radius_px=radii[order],
        mtf=mtf,
        mtf_all=mods["all"][order] / m0,
        mtf_at_nyquist=nyq,
        input_modulation=m0,
        center_xy_px=(xc, yc),
        cycles=n,
        f_cy_per_m_ground=None if pixel_m is None else cy_per_px_to_cy_per_m_ground(f, gsd_m=pixel_m),
    )


def _modulation(theta: np.ndarray, values: np.ndarray, n: int) -> float:
    """Least-squares ``a + b cos(n th) + c sin(n th)``; returns ``sqrt(b^2 + c^2) / a``."""
    design = np.column_stack([np.ones_like(theta), np.cos(n * theta), np.sin(n * theta)])
    (a, b, c), *_ = np.linalg.lstsq(design, values, rcond=None)
    if a <= 0:
        raise InputError("image: the star's mean level must be positive to define a modulation")
    return float(np.hypot(b, c) / a)
