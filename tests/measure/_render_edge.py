"""Exact isotropic edge renders for the slanted-edge tests and benchmark (independent of satchain.measure).

With an isotropic system OTF (annular diffraction x Gaussian blur, point-sampled: no pixel aperture), the
value at a pixel centre at signed distance ``d`` from a straight edge is exactly

    ESF(d) = 1/2 + integral_0^fc OTF(f) sin(2 pi f d) / (pi f) df,

and for a circular edge of radius R >> blur the same formula in the signed distance to the circle is exact
to O(blur^2 / R).  The MTF along any normal is OTF(f); ``truth_mtf`` gives it.
"""

from __future__ import annotations

import numpy as np
from _render import _freq_nodes, annular_mtf
from scipy.interpolate import CubicSpline
from scipy.special import ndtr


def truth_mtf(f, *, q: float | None, eps: float = 0.33, blur_px: float = 0.0):
    """Isotropic OTF: annular diffraction (cutoff 1/q cy/px; None: no optics) x Gaussian(blur_px)."""
    f = np.asarray(f, dtype=float)
    out = np.exp(-2 * np.pi**2 * blur_px**2 * f**2)
    if q is not None:
        out = out * annular_mtf(f * q, eps)
    return out


def iso_esf(d, *, q: float | None, eps: float = 0.33, blur_px: float = 0.0):
    """Exact unit-step ESF of :func:`truth_mtf` at distances ``d`` (px)."""
    d = np.asarray(d, dtype=float)
    if q is None:
        return ndtr(d / blur_px)
    nodes, w = _freq_nodes(1.0 / q, eps)
    g = 2.0 * w * truth_mtf(nodes, q=q, eps=eps, blur_px=blur_px)
    flat = d.ravel()
    out = np.empty(flat.size)
    for i in range(0, flat.size, 2000):
        dd = flat[i : i + 2000, None]
        out[i : i + 2000] = 0.5 + dd[:, 0] * (np.sinc(2 * nodes[None, :] * dd) @ g)
    return out.reshape(d.shape)


def edge_distance(shape, angle_deg: float, *, offset_px: float = 0.137, radius_px: float | None = None):
    """Signed distance (px) of the pixel centres to a line (or a circle of ``radius_px``) through the centre.

    Angle convention of ``satchain.measure.edge``: from the y axis, normal (cos t, -sin t); a circle bulges
    towards the bright side (its centre lies on the dark side, ``radius_px`` away along the normal).
    """
    ny, nx = shape
    y, x = np.mgrid[0:ny, 0:nx].astype(float)
    t = np.deg2rad(angle_deg)
    xc, yc = (nx - 1) / 2 + offset_px, (ny - 1) / 2
    if radius_px is None:
        return (x - xc) * np.cos(t) - (y - yc) * np.sin(t)
    cx, cy = xc - radius_px * np.cos(t), yc + radius_px * np.sin(t)
    return np.hypot(x - cx, y - cy) - radius_px


def render_iso_edge(shape, angle_deg, *, q=1.07, eps=0.33, blur_px=0.0, offset_px=0.137, radius_px=None):
    """Unit-step edge (0 -> 1) through the isotropic system, exact at pixel centres (dense spline table)."""
    d = edge_distance(shape, angle_deg, offset_px=offset_px, radius_px=radius_px)
    lim = np.abs(d).max() + 1.0
    grid = np.arange(-lim, lim + 0.03, 0.03)
    return CubicSpline(grid, iso_esf(grid, q=q, eps=eps, blur_px=blur_px))(d)
