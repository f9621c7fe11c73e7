"""Exact renders of real dark targets that reach 0 DN (issue 19: what a zero fill must never be taken for).

A straight edge, or a dark bar across the image, at ``angle_deg`` from the y axis, between a dark level (at or
below 0: ``dark < 0`` is clipped at 0) and ``bright``, imaged with a Gaussian PSF of ``blur_px`` and a square
pixel aperture, then quantised (optionally with noise) to an unsigned integer type and clipped at 0.

With ``u`` the signed distance from the edge line, a Gaussian-blurred step is ``Phi(u / blur)``: the pixel
aperture is integrated by ``sub`` x ``sub`` midpoint sub-samples, so the render is exact to the sub-sampling.
Independent of satchain.measure.
"""

from __future__ import annotations

import numpy as np
from scipy.special import ndtr


def render_dark_target(
    *,
    kind: str = "edge",
    angle_deg: float = 0.0,
    blur_px: float = 0.5,
    dark: float = -500.0,
    bright: float = 1000.0,
    offset_px: float = 0.0,
    bar_px: float = 12.0,
    size: int = 64,
    noise: float = 0.0,
    seed: int = 0,
    dtype=np.uint16,
    sub: int = 8,
) -> np.ndarray:
    """A dark target clipped at 0: ``kind`` "edge" (dark for u < 0), "bar" (dark for 0 < u < ``bar_px``) or
    "bars" (three dark bars ``bar_px`` wide, ``bar_px`` apart, from beyond the image's top end (v < 0) to
    ``v = 2 bar_px``: their ends are corners).

    The line passes ``offset_px`` from the image centre along its normal; ``noise`` is a Gaussian std (DN).
    """
    t = np.deg2rad(angle_deg)
    o = (np.arange(sub) + 0.5) / sub - 0.5
    yy, xx = np.mgrid[0:size, 0:size].astype(float)
    c = (size - 1) / 2
    x = xx[..., None, None] + o[None, None, None, :] - c
    y = yy[..., None, None] + o[None, None, :, None] - c
    u = x * np.cos(t) - y * np.sin(t) - offset_px  # normal of a line at angle t from the y axis
    v = x * np.sin(t) + y * np.cos(t) - offset_px  # along the line
    if kind == "edge":
        step = ndtr(u / blur_px)
    elif kind == "bar":
        step = 1.0 - (ndtr(u / blur_px) - ndtr((u - bar_px) / blur_px))
    elif kind == "bars":
        along = ndtr(-(v - 2 * bar_px) / blur_px)  # v < 2 bar_px (the top end lies outside the image)
        across = sum(
            ndtr((u - k * bar_px) / blur_px) - ndtr((u - (k + 1) * bar_px) / blur_px) for k in (-2.5, -0.5, 1.5)
        )
        step = 1.0 - along * across
    else:
        raise ValueError(f"kind = {kind!r}: must be 'edge', 'bar' or 'bars'")
    img = (dark + (bright - dark) * step).mean(axis=(2, 3))
    if noise:
        img = img + np.random.default_rng(seed).normal(0.0, noise, img.shape)
    return np.clip(np.round(img), 0, np.iinfo(dtype).max).astype(dtype)
