"""Exact Gaussian-PSF edges integrated over the pixel area (issue 18 point 7 audit; independent of satchain).

A unit step convolved with a Gaussian PSF of standard deviation ``sigma_px`` has the ESF ``Phi(d / sigma)`` at
signed distance ``d`` from the edge (for a circle of radius R >> sigma the same formula in the distance to the
circle, exact to O(sigma^2 / R)).  Each pixel value is the mean of that ESF over ``sub x sub`` points spread
evenly over the pixel's square (a 100 % fill-factor detector); 16 x 16 points integrate it to ~1e-4.

Along the normal of a straight edge at angle ``t`` the system MTF is the Gaussian's times the transform of the
square pixel projected on the normal, a box of width cos t convolved with one of width sin t:
``exp(-2 pi^2 sigma^2 f^2) |sinc(f cos t) sinc(f sin t)|``  (:func:`truth_mtf`).
"""

from __future__ import annotations

import numpy as np
from scipy.special import ndtr


def edge_distance(y, x, angle_deg: float, *, xc: float, yc: float, radius_px: float | None = None):
    """Signed distance of points (y, x) to a line through (xc, yc) at ``angle_deg`` from the y axis (bright side
    positive, normal (cos t, -sin t)), or to a circle of ``radius_px`` tangent to that line at (xc, yc) whose
    centre lies on the dark side."""
    t = np.deg2rad(angle_deg)
    if radius_px is None:
        return (x - xc) * np.cos(t) - (y - yc) * np.sin(t)
    cx, cy = xc - radius_px * np.cos(t), yc + radius_px * np.sin(t)
    return np.hypot(x - cx, y - cy) - radius_px


def render_gauss_edge(
    shape,
    angle_deg: float,
    *,
    sigma_px: float,
    phase_px: float = 0.0,
    radius_px: float | None = None,
    low: float = 0.0,
    high: float = 1.0,
    sub: int = 16,
):
    """``low -> high`` edge through a Gaussian PSF, each pixel the mean over ``sub x sub`` points of its area.

    The edge passes ``phase_px`` right of the region's centre (a free grid phase)."""
    ny, nx = shape
    off = (np.arange(sub) + 0.5) / sub - 0.5
    y, x = np.mgrid[0:ny, 0:nx].astype(float)
    xc, yc = (nx - 1) / 2 + phase_px, (ny - 1) / 2
    acc = np.zeros(shape)
    for oy in off:
        d = edge_distance(
            y[:, :, None] + oy, x[:, :, None] + off[None, None, :], angle_deg, xc=xc, yc=yc, radius_px=radius_px
        )
        acc += ndtr(d / sigma_px).mean(axis=2)
    return low + (high - low) * acc / sub


def truth_mtf(f, angle_deg: float, sigma_px: float):
    """MTF along the normal of a straight edge: Gaussian x the square pixel projected on the normal."""
    f = np.asarray(f, dtype=float)
    t = np.deg2rad(angle_deg)
    return np.exp(-2 * np.pi**2 * sigma_px**2 * f**2) * np.abs(np.sinc(f * np.cos(t)) * np.sinc(f * np.sin(t)))
