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


# ------------------------------------------------------------------------------------------------ bar groups
#
# Bars.  A bar group is a sum of bright strips [u0, u0 + P/2] on a dark plate; along the profile each strip is
# the difference of two unit steps, so a pixel centred at x reads
#
#     dark + (bright - dark) sum_bars [ESF(x - u0) - ESF(x - u0 - P/2)],
#
# with the ESF of the 1-D system OTF(f) = M_ann(q f) sinc(f) exp(-2 pi^2 s^2 f^2) (annular diffraction with
# cutoff 1/q cy/px, 100 %-fill square pixel, Gaussian blur of sigma s px), again exact at pixel centres:
#
#     ESF(d) = 1/2 + integral_0^f_max OTF(f) sin(2 pi f d) / (pi f) df.
#
# ``q = 0`` means no diffraction (Gaussian x pixel only, the system of tests/measure/test_bars.py).

#: Frequency beyond which the Gaussian term is below 1e-14 is ``_GAUSS_CUT / sigma`` (sqrt(ln 1e14 / 2 pi^2)).
_GAUSS_CUT = float(np.sqrt(np.log(1e14) / (2 * np.pi**2)))
#: The ESF tables cover |d| <= _BAR_DMAX px (the widest rendered group is well inside).
_BAR_DMAX = 256.0
_BAR_TABLES: dict = {}


def bar_mtf(f, *, q: float, eps: float, blur_sigma_px: float):
    """Signed 1-D OTF of the bar renderer: annular diffraction (cutoff 1/q; none if q = 0) x pixel sinc x Gaussian."""
    f = np.asarray(f, dtype=float)
    optics = annular_mtf(f * q, eps) if q > 0 else np.ones_like(f)
    return optics * np.sinc(f) * gaussian_mtf(f, blur_sigma_px)


def _bar_fmax(q: float, blur_sigma_px: float) -> float:
    cuts = ([1.0 / q] if q > 0 else []) + ([_GAUSS_CUT / blur_sigma_px] if blur_sigma_px > 0 else [])
    if not cuts:
        raise ValueError("bar renderer: need diffraction (q > 0) or a Gaussian blur (sigma > 0) to band-limit")
    return min(cuts)


def _bar_nodes(q: float, eps: float, blur_sigma_px: float, d_max: float):
    """Gauss-Legendre nodes on [0, f_max], panels at most 0.1 cy/px wide and split at the annular MTF's kinks;
    enough nodes per panel for sin(2 pi f d) up to |d| = d_max (pi d_max w + 30 per panel of width w)."""
    fmax = _bar_fmax(q, blur_sigma_px)
    kinks = [k / q for k in (eps, (1 - eps) / 2, (1 + eps) / 2) if q > 0 and 0 < k / q < fmax]
    cuts = np.unique(np.concatenate([np.linspace(0, fmax, int(np.ceil(fmax / 0.1)) + 1), kinks]))
    fs, ws = [], []
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        x, w = np.polynomial.legendre.leggauss(int(np.pi * d_max * (b - a)) + 30)
        fs.append(0.5 * (b - a) * x + 0.5 * (a + b))
        ws.append(0.5 * (b - a) * w)
    return np.concatenate(fs), np.concatenate(ws)


def bar_esf_exact(d_px, *, q: float, eps: float, blur_sigma_px: float, d_max: float = _BAR_DMAX):
    """ESF (unit step, 0 -> 1) of the bar renderer's system at distances ``d_px`` (|d| <= d_max), by quadrature."""
    d = np.asarray(d_px, dtype=float)
    if np.any(np.abs(d) > d_max):
        raise ValueError(f"bar_esf_exact: |d| up to {d_max} px")
    f, w = _bar_nodes(q, eps, blur_sigma_px, d_max)
    g = 2.0 * w * bar_mtf(f, q=q, eps=eps, blur_sigma_px=blur_sigma_px)
    flat = d.ravel()
    out = np.empty(flat.size)
    for i in range(0, flat.size, 1000):
        dd = flat[i : i + 1000, None]
        out[i : i + 1000] = 0.5 + dd[:, 0] * (np.sinc(2 * f[None, :] * dd) @ g)  # sin(2 pi f d)/(pi f) = 2d sinc(2fd)
    return out.reshape(d.shape)


def bar_esf(q: float, eps: float, blur_sigma_px: float, d_max: float = _BAR_DMAX):
    """ESF(d) of annular diffraction (cutoff 1/q cy/px; q = 0: none) x pixel x Gaussian (sigma px), as a callable
    on |d| <= d_max (dense table every 0.025 px, odd about 1/2, cubic spline; cached per parameters)."""
    key = (float(q), float(eps), float(blur_sigma_px), float(d_max))
    wider = [k for k in _BAR_TABLES if k[:3] == key[:3] and k[3] >= key[3]]
    if wider:  # a table of the same system over a wider range serves
        key, d_max = min(wider), min(wider)[3]
    else:
        grid = np.linspace(0.0, d_max, int(round(d_max / 0.025)) + 1)
        half = bar_esf_exact(grid, q=q, eps=eps, blur_sigma_px=blur_sigma_px, d_max=d_max)
        full = np.concatenate([1.0 - half[:0:-1], half])  # ESF(-d) = 1 - ESF(d) (real, even OTF)
        _BAR_TABLES[key] = CubicSpline(np.concatenate([-grid[:0:-1], grid]), full)
    table = _BAR_TABLES[key]

    def esf(d):
        d = np.asarray(d, dtype=float)
        if np.any(np.abs(d) > d_max):
            raise ValueError(f"bar_esf: |d| up to {d_max} px")
        return table(d)

    return esf


def render_bar_group(
    period: float,
    phase: float,
    n_bars: int,
    *,
    q: float,
    eps: float,
    blur_sigma_px: float,
    rows: int = 4,
    dark: float = 40.0,
    bright: float = 160.0,
):
    """``n_bars`` bright bars (width P/2) on a dark plate seen through :func:`bar_esf`'s system, exact at pixel
    centres; geometry of tests/measure/test_bars._group: first bar edge at 3 P + phase, 3 P of plate after the
    last bar; region (x0, 0, x1, rows) holds the pixels from the first to the last bar centre.  Bars along y."""
    start = 3 * period + phase
    x = np.arange(int(np.ceil(start + (n_bars + 3) * period)), dtype=float)
    esf = bar_esf(q, eps, blur_sigma_px, d_max=max(32.0, 2.0 ** np.ceil(np.log2(x.size))))  # tables of 32, 64, ...
    v = np.full(x.size, dark)
    for k in range(n_bars):
        u0 = start + k * period
        v += (bright - dark) * (esf(x - u0) - esf(x - u0 - period / 2))
    c0, c1 = start + period / 4, start + (n_bars - 1) * period + period / 4
    roi = (int(np.ceil(c0 - 1e-9)), 0, int(np.floor(c1 + 1e-9)) + 1, rows)
    return np.tile(v, (rows, 1)), roi


def bar_coltman(f, *, q: float, eps: float, blur_sigma_px: float):
    """Coltman (1954) square-wave CTF: 4/pi sum_k odd (-1)^((k-1)/2) M(k f) / k, M = :func:`bar_mtf` (signed)."""
    f = np.atleast_1d(np.asarray(f, dtype=float))
    fmax = _bar_fmax(q, blur_sigma_px)
    k = np.arange(1, 2 * int(np.ceil(fmax / f.min())) + 3, 2)  # every harmonic below f_max
    m = bar_mtf(np.outer(f, k), q=q, eps=eps, blur_sigma_px=blur_sigma_px)
    out = 4 / np.pi * np.sum((-1.0) ** ((k - 1) // 2) * m / k, axis=1)
    return out if out.size > 1 else float(out[0])
