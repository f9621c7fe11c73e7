"""MTF Mapper-like test chart: dark rotated squares on a bright background, Gaussian x square-pixel blur.

Independent of ``satchain.measure`` and ``satchain.tf``.  A pixel at signed distance ``d`` (inwards) from one
side of a square sees the exact edge spread function of that side,

    ESF_n(d) = 1/2 + integral_0^fmax OTF_n(f) sin(2 pi f d) / (pi f) df,
    OTF_n(f) = exp(-2 pi^2 sigma_n^2 f^2) sinc(f cos t) sinc(f sin t),   sigma_n^2 = sx^2 nx^2 + sy^2 ny^2,

(an anisotropic Gaussian PSF with standard deviations ``sx`` (ACT, x) and ``sy`` (ALT, y) projected on the
side's unit normal n = (nx, ny), times the 100 %-fill square pixel).  The square's coverage is the minimum of
its four sides' ESFs: exact wherever at most one side is within the blur's reach (everywhere except within
~3 px of the corners, which the edge finder must avoid anyway).  The true ACT MTF is
``exp(-2 pi^2 sx^2 f^2) |sinc(f)|``, the ALT one the same with ``sy``.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy.interpolate import CubicSpline


@lru_cache(maxsize=1)
def _nodes(n: int = 300):
    return np.polynomial.legendre.leggauss(n)


def esf_table(sigma_n: float, tilt_deg: float):
    """Cubic spline of the exact ESF (unit step) on [-12, 12] px; constant 0 / 1 beyond."""
    t = np.deg2rad(tilt_deg)
    fmax = np.sqrt(40.0 / (2 * np.pi**2 * sigma_n**2)) if sigma_n > 0 else 50.0
    x, w = _nodes()
    f, w = 0.5 * fmax * (x + 1), 0.5 * fmax * w
    otf = np.exp(-2 * np.pi**2 * sigma_n**2 * f**2) * np.sinc(f * np.cos(t)) * np.sinc(f * np.sin(t))
    d = np.arange(-12.0, 12.0 + 1e-9, 0.02)
    esf = 0.5 + (2 * d[:, None] * np.sinc(2 * f[None, :] * d[:, None])) @ (w * otf)
    return CubicSpline(d, esf)


def true_mtf(f, sigma_px: float):
    """Axis MTF: Gaussian x square pixel."""
    f = np.asarray(f, dtype=float)
    return np.exp(-2 * np.pi**2 * sigma_px**2 * f**2) * np.abs(np.sinc(f))


def square_sides(center_xy, side_px: float, rot_deg: float):
    """Inward unit normals (nx, ny) and offsets c of the four sides: inside <=> n . (p - centre) + c >= 0."""
    r = np.deg2rad(rot_deg)
    out = []
    for k in range(4):
        a = r + k * np.pi / 2
        out.append((-np.cos(a), -np.sin(a), side_px / 2))
    return out


def render_chart(shape, squares, *, sx: float, sy: float, low=0.15, high=0.85, noise=0.0, rng=None):
    """Image of dark squares ``squares = [(cx, cy, side_px, rot_deg), ...]`` on a bright background."""
    ny, nx = shape
    yy, xx = np.mgrid[0:ny, 0:nx].astype(float)
    img = np.full(shape, float(high))
    for cx, cy, side, rot in squares:
        cover = np.ones(shape)
        for ncx, ncy, c in square_sides((cx, cy), side, rot):
            d = ncx * (xx - cx) + ncy * (yy - cy) + c
            sig = np.sqrt(sx**2 * ncx**2 + sy**2 * ncy**2)
            tilt = np.degrees(np.arctan2(min(abs(ncx), abs(ncy)), max(abs(ncx), abs(ncy))))
            e = (d > 0).astype(float)
            near = np.abs(d) < 12
            e[near] = esf_table(sig, tilt)(d[near])
            cover = np.minimum(cover, e)
        img -= (high - low) * cover
    if noise:
        img = img + (rng or np.random.default_rng(0)).normal(0.0, noise, shape)
    return img


def expected_edges(squares):
    """Truth per side: (centre x, centre y, angle_deg from the y axis in (-90, 90], direction)."""
    out = []
    for cx, cy, side, rot in squares:
        for ncx, ncy, c in square_sides((cx, cy), side, rot):
            px, py = cx - ncx * c, cy - ncy * c  # side's midpoint
            ux, uy = -ncy, ncx  # along the side
            if uy < 0 or (uy == 0 and ux < 0):
                ux, uy = -ux, -uy
            ang = float(np.degrees(np.arctan2(ux, uy)))
            ang = ang - 180 if ang > 90 else ang
            out.append((px, py, ang, "ACT" if abs(ang) < 45 else "ALT"))
    return out
