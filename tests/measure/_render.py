"""Exact renderers of measurement targets with known transfer functions (test and benchmark helper).

Independent of ``satchain.measure`` and ``satchain.tf``: the closed forms are written out here.

Edges.  For a straight edge with unit step, the value of a pixel whose centre lies at signed
distance ``d`` from the edge (along the edge normal ``n``) is

    ESF_n(d) = 1/2 + integral_0^inf OTF_n(f) sin(2 pi f d) / (pi f) df,

where ``OTF_n`` is the system OTF cut along ``n``.  The pixel aperture is part of the OTF, so sampling
``ESF_n`` at pixel centres is exact (no numerical pixel integration).  For diffraction by an annular
pupil (O'Neill 1956) times a 100 %-fill square pixel, ``OTF_n(f) = MTF_opt(f) sinc(f cos t) sinc(f sin t)``
(signed sinc product, positive optics term) and the integral stops at the optical cutoff.

The angle convention is the one of ``satchain.measure.edge``: ``angle_deg`` is the angle of the edge line
from the image y axis (ALT); the unit normal is ``n = (cos t, -sin t)`` in (x, y), so
``d = (x - xc) cos t - (y - yc) sin t``; pixel centres are at integer (x = col, y = row).
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline


def annular_mtf(nu, eps: float):
    """O'Neill (1956) diffraction MTF of an annular pupil; ``nu = f / f_cutoff``, obscuration ``eps``."""
    nu = np.abs(np.asarray(nu, dtype=float))
    out = np.zeros_like(nu)
    m = nu < 1.0
    v = nu[m]
    a = (2 / np.pi) * (np.arccos(v) - v * np.sqrt(1 - v * v))
    b = np.zeros_like(v)
    c = np.zeros_like(v)
    if eps > 0:
        mb = v <= eps
        ve = v[mb] / eps
        b[mb] = (2 * eps**2 / np.pi) * (np.arccos(ve) - ve * np.sqrt(1 - ve * ve))
        lo, hi = (1 - eps) / 2, (1 + eps) / 2
        c[v <= lo] = -2 * eps**2
        mc = (v > lo) & (v < hi)
        phi = np.arccos(np.clip((1 + eps**2 - 4 * v[mc] ** 2) / (2 * eps), -1, 1))
        c[mc] = (
            (2 * eps / np.pi) * np.sin(phi)
            + ((1 + eps**2) / np.pi) * phi
            - (2 * (1 - eps**2) / np.pi) * np.arctan((1 + eps) / (1 - eps) * np.tan(phi / 2))
            - 2 * eps**2
        )
    out[m] = (a + b + c) / (1 - eps**2)
    return out


def otf_normal(f_cy_per_px, angle_deg: float, *, q: float, eps: float):
    """Signed OTF cut along the edge normal: annular diffraction (cutoff 1/q cy/px) x square 100 % pixel."""
    f = np.asarray(f_cy_per_px, dtype=float)
    t = np.deg2rad(angle_deg)
    return annular_mtf(f * q, eps) * np.sinc(f * np.cos(t)) * np.sinc(f * np.sin(t))


def _freq_nodes(fc: float, eps: float, n_per_panel: int = 250):
    """Gauss-Legendre nodes/weights on [0, fc], panels split at the kinks of the annular MTF."""
    cuts = sorted({0.0, fc, *(k * fc for k in (eps, (1 - eps) / 2, (1 + eps) / 2) if 0 < k < 1)})
    x, w = np.polynomial.legendre.leggauss(n_per_panel)
    fs, ws = [], []
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        fs.append(0.5 * (b - a) * x + 0.5 * (a + b))
        ws.append(0.5 * (b - a) * w)
    return np.concatenate(fs), np.concatenate(ws)


def esf_normal(d_px, angle_deg: float, *, q: float, eps: float):
    """Exact ESF along the normal at distances ``d_px`` (unit step, 0 -> 1)."""
    d = np.asarray(d_px, dtype=float)
    f, w = _freq_nodes(1.0 / q, eps)
    g = w * otf_normal(f, angle_deg, q=q, eps=eps) * 2.0
    out = np.empty(d.size)
    flat = d.ravel()
    for i in range(0, flat.size, 2000):
        dd = flat[i : i + 2000, None]
        # sin(2 pi f d) / (pi f) = 2 d sinc(2 f d)
        out[i : i + 2000] = 0.5 + (dd[:, 0] * (np.sinc(2 * f[None, :] * dd) @ g))
    return out.reshape(d.shape)


def _distances(shape, angle_deg, offset_px):
    ny, nx = shape
    y, x = np.mgrid[0:ny, 0:nx].astype(float)
    t = np.deg2rad(angle_deg)
    xc, yc = (nx - 1) / 2 + offset_px, (ny - 1) / 2
    return (x - xc) * np.cos(t) - (y - yc) * np.sin(t)


def render_edge(shape, angle_deg: float, *, q: float, eps: float, offset_px: float = 0.137, low=0.0, high=1.0):
    """Diffraction (annular) x square-pixel edge, exact at pixel centres (dense table + cubic spline)."""
    d = _distances(shape, angle_deg, offset_px)
    lim = np.abs(d).max() + 1.0
    grid = np.arange(-lim, lim + 0.04, 0.04)
    table = CubicSpline(grid, esf_normal(grid, angle_deg, q=q, eps=eps))
    return low + (high - low) * table(d)


def render_pixel_edge(shape, angle_deg: float, *, offset_px: float = 0.137, low=0.0, high=1.0):
    """Ideal edge seen by a 100 %-fill square pixel: exact area coverage (trapezoid CDF along the normal)."""
    d = _distances(shape, angle_deg, offset_px)
    return low + (high - low) * pixel_esf(d, angle_deg)


def pixel_esf(d, angle_deg: float):
    """Fraction of a unit square centred at signed distance d on the bright side of a line at angle t."""
    t = np.deg2rad(angle_deg)
    c, s = abs(np.cos(t)), abs(np.sin(t))
    a, b = (abs(c - s)) / 2, (c + s) / 2  # flat top half-width, support half-width
    h = 1.0 / max(c, s)
    d = np.asarray(d, dtype=float)
    x = np.clip(d, -b, b)
    if b - a < 1e-12:  # axis-aligned: uniform density
        return np.clip(d + 0.5, 0, 1)
    ramp = b - a

    def cdf_pos(u):  # mass in [0, u] for 0 <= u <= b
        u1 = np.minimum(u, a)
        m = h * u1
        u2 = np.clip(u - a, 0, ramp)
        return m + h * (u2 - u2**2 / (2 * ramp))

    return 0.5 + np.sign(x) * cdf_pos(np.abs(x))


def pixel_rer(angle_deg: float) -> float:
    """Closed-form RER = ESF(+1/2) - ESF(-1/2) of the ideal edge seen by a square pixel."""
    t = np.deg2rad(angle_deg)
    c, s = abs(np.cos(t)), abs(np.sin(t))
    c, s = max(c, s), min(c, s)
    if s == 0:
        return 1.0
    return 1.0 - (c + s - 1.0) ** 2 / (4 * s * c)


def gaussian_mtf(f, sigma_px: float):
    """MTF of a Gaussian PSF of standard deviation ``sigma_px``."""
    return np.exp(-2 * np.pi**2 * sigma_px**2 * np.asarray(f, dtype=float) ** 2)
