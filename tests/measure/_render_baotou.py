"""Exact render of a Baotou-like flight crop (issue 19), independent of satchain.measure.

A 2 x 2 knife-edge target (a checkerboard of squares of half-size ``half_px`` at 9300 / 1850 / 3800 / 1850 DN,
background 3800 DN) rotated by ``angle_deg``, imaged with a non-Gaussian PSF -- a sharp core with a halo,
``PSF = (1 - a) G(s1) + a G(s2)`` -- and a square pixel aperture, with signal-dependent noise
``sigma = sqrt(read**2 + gain * signal)`` (40 DN at 1850, 66 DN at 9300), quantised to uint16, and the
pixels outside a rotated square area of interest set to 0 (35 % of the image).

The scene is a sum of axis-aligned squares in the target frame (u, v); an isotropic Gaussian of a square is
separable there, ``(Phi(u / s) - Phi((u - L) / s)) (Phi(v / s) - Phi((v - L) / s))``, so the blurred scene
is exact.  The pixel aperture is integrated by ``sub`` x ``sub`` midpoint sub-samples.  The MTF along an
edge normal at angle ``t`` from the pixel axes is :func:`truth_mtf`.
"""

from __future__ import annotations

import numpy as np
from scipy.special import ndtr

SIZE = 101
LEVELS = {"bright": 9300.0, "dark": 1850.0, "mid": 3800.0}
READ_DN = 30.25
GAIN_DN = 0.37  # sigma^2 = read^2 + gain * signal: 40 DN at 1850, 66 DN at 9300


def truth_mtf(f, angle_deg: float, *, s1: float = 0.5, s2: float = 3.0, a: float = 0.1):
    """MTF along the normal of an edge at ``angle_deg`` from a pixel axis: PSF x square pixel aperture."""
    f = np.asarray(f, dtype=float)
    t = np.deg2rad(angle_deg)
    psf = (1 - a) * np.exp(-2 * np.pi**2 * s1**2 * f**2) + a * np.exp(-2 * np.pi**2 * s2**2 * f**2)
    return psf * np.abs(np.sinc(f * np.cos(t)) * np.sinc(f * np.sin(t)))


def _square_blur(u, v, u0, u1, v0, v1, s):
    return (ndtr((u - u0) / s) - ndtr((u - u1) / s)) * (ndtr((v - v0) / s) - ndtr((v - v1) / s))


def render_baotou(
    *,
    angle_deg: float = 16.8,
    phase=(0.0, 0.0),
    s1: float = 0.5,
    s2: float = 3.0,
    a: float = 0.1,
    half_px: float = 44.0,
    aoi_px: float | None = None,
    fill_fraction: float = 0.35,
    seed: int | None = 0,
    sub: int = 12,
):
    """(uint16 image, valid mask) of the Baotou-like target; ``seed`` None: noise-free, not quantised.

    ``phase`` shifts the target centre (px) from the image centre; ``aoi_px`` is the side of the rotated
    square area of interest (default: ``fill_fraction`` of the image outside it).
    """
    t = np.deg2rad(angle_deg)
    c, s = np.cos(t), np.sin(t)
    cx, cy = (SIZE - 1) / 2 + phase[0], (SIZE - 1) / 2 + phase[1]
    o = (np.arange(sub) + 0.5) / sub - 0.5
    yy, xx = np.mgrid[0:SIZE, 0:SIZE].astype(float)
    x = (xx[..., None, None] + o[None, None, None, :]) - cx
    y = (yy[..., None, None] + o[None, None, :, None]) - cy
    u, v = x * c + y * s, -x * s + y * c  # target frame: the edges are u = 0 and v = 0
    bg = LEVELS["mid"]
    h = half_px
    squares = [
        ((0, h, 0, h), LEVELS["bright"]),
        ((-h, 0, 0, h), LEVELS["dark"]),
        ((-h, 0, -h, 0), LEVELS["mid"]),
        ((0, h, -h, 0), LEVELS["dark"]),
    ]
    val = np.full(u.shape, bg)
    for (u0, u1, v0, v1), level in squares:
        blur = (1 - a) * _square_blur(u, v, u0, u1, v0, v1, s1) + a * _square_blur(u, v, u0, u1, v0, v1, s2)
        val += (level - bg) * blur
    img = val.mean(axis=(2, 3))
    uc = (xx - cx) * c + (yy - cy) * s
    vc = -(xx - cx) * s + (yy - cy) * c
    if aoi_px is None:
        aoi_px = _aoi_for_fraction(uc, vc, fill_fraction)
    valid = (np.abs(uc) < aoi_px / 2) & (np.abs(vc) < aoi_px / 2)
    if seed is not None:
        rng = np.random.default_rng(seed)
        img = img + rng.normal(size=img.shape) * np.sqrt(READ_DN**2 + GAIN_DN * img)
        img = np.clip(np.round(img), 1, 65534).astype(np.uint16)
    img = np.where(valid, img, 0)
    return img, valid


def _aoi_for_fraction(uc, vc, frac: float) -> float:
    """Side of the rotated square that leaves ``frac`` of the image outside."""
    r = np.sort(np.maximum(np.abs(uc), np.abs(vc)).ravel())
    return float(2 * r[int(round((1 - frac) * r.size)) - 1] + 1e-9)
