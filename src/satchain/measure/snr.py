"""The GIQE contrast SNR measured on an image alone, with the scene's truth record saying where things are.

SNR = gain (0.15 - 0.07) / noise(0.15): GIQE's contrast between reflectances 0.15 and 0.07 over the noise at
reflectance 0.15 (as :func:`satchain.radiometry.contrast_snr` predicts it).

* gain (image units per unit reflectance): the step between each slanted edge's plateaus (medians >= 4 px
  from the edge) over its truth reflectance step; the median over the edges.
* noise of a flat region: the robust sigma of horizontal pixel differences over sqrt 2 (scene shading
  cancels). The background's is the median over all target-free 16 x 16 px patches (their minimum, used
  before, is biased low by ~15 % with ~15 patches).
* noise at 0.15: a straight line fitted to variance against level through the background and the edge
  plateaus (shot noise grows linearly with the signal, read and quantisation noise are constant), evaluated
  at the background level + gain (0.15 - background reflectance). The background is at 0.2 in satchain's
  scenes, where shot-limited noise is sqrt(0.2 / 0.15) = 1.15 x that at 0.15: taking it as is would bias
  the SNR ~13 % low. Without plateaus of distinct levels the background's sigma is used.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from satchain._validate import as_float_array, check_positive
from satchain.measure._common import ResultMixin, robust_sigma
from satchain.scene.targets import SlantedEdge

if TYPE_CHECKING:
    from satchain.scene.truth import Truth

__all__ = ["GIQE_CONTRAST", "GIQE_REFLECTANCE", "SnrResult", "measure_snr"]

#: The reflectance difference GIQE's SNR is defined for (0.15 - 0.07), and the reflectance of its noise.
GIQE_CONTRAST = 0.15 - 0.07
GIQE_REFLECTANCE = 0.15
_PATCH_PX = 16
_PLATEAU_PX = 4.0
_MIN_PLATEAU_SAMPLES = 20


@dataclass(frozen=True)
class SnrResult(ResultMixin):
    """``snr``: GIQE contrast SNR (NaN when not measurable, ``reason`` says why); ``noise_dn``: noise sigma of one
    pixel (image units); ``gain_dn_per_reflectance``: image units per unit reflectance; ``n_edges``: edges the
    gain came from."""

    snr: float
    noise_dn: float | None
    gain_dn_per_reflectance: float | None
    n_edges: int
    reason: str | None = None


def _plateau_noise(block: np.ndarray, mask: np.ndarray) -> tuple[float, float] | None:
    """(level, noise sigma) of a flat region: median, and robust sigma of horizontal differences / sqrt 2."""
    pairs = mask[:, 1:] & mask[:, :-1]
    if pairs.sum() < 2 * _MIN_PLATEAU_SAMPLES:
        return None
    diffs = np.diff(block, axis=1)[pairs]
    return float(np.median(block[mask])), robust_sigma(diffs) / math.sqrt(2)


def _edge_plateaus(image: np.ndarray, it: Mapping[str, Any], pixel_m: float):
    """The gain (image units per unit reflectance) from one edge's two plateaus, and their (level, sigma)."""
    x0, y0, x1, y1 = it["bbox_m"]
    r0, r1 = max(int(np.ceil(y0 / pixel_m)) + 2, 0), min(int(y1 / pixel_m) - 2, image.shape[0])
    c0, c1 = max(int(np.ceil(x0 / pixel_m)) + 2, 0), min(int(x1 / pixel_m) - 2, image.shape[1])
    if r1 - r0 < 8 or c1 - c0 < 8:
        return None, []
    yy, xx = np.mgrid[r0:r1, c0:c1]
    (px, py), (nx, ny) = it["edge_point_m"], it["normal_to_bright"]
    d = ((xx + 0.5) * pixel_m - px) * nx + ((yy + 0.5) * pixel_m - py) * ny
    block = image[r0:r1, c0:c1]
    far = _PLATEAU_PX * pixel_m
    if (d > far).sum() <= _MIN_PLATEAU_SAMPLES or (d < -far).sum() <= _MIN_PLATEAU_SAMPLES:
        return None, []
    gain = float((np.median(block[d > far]) - np.median(block[d < -far])) / (it["bright"] - it["dark"]))
    levels = [p for p in (_plateau_noise(block, d > far), _plateau_noise(block, d < -far)) if p is not None]
    return gain, levels


def _background_noise(image: np.ndarray, items, pixel_m: float) -> tuple[float, float] | None:
    """(level, noise sigma) of the background: medians over all target-free 16 x 16 px patches."""
    occupied = np.zeros(image.shape, bool)
    for it in items:
        x0, y0, x1, y1 = it["bbox_m"]
        occupied[
            max(int(y0 / pixel_m) - 2, 0) : int(y1 / pixel_m) + 3,
            max(int(x0 / pixel_m) - 2, 0) : int(x1 / pixel_m) + 3,
        ] = True
    n, sigmas, levels = _PATCH_PX, [], []
    for r in range(0, image.shape[0] - n + 1, n):
        for c in range(0, image.shape[1] - n + 1, n):
            if not occupied[r : r + n, c : c + n].any():
                patch = image[r : r + n, c : c + n]
                sigmas.append(robust_sigma(np.diff(patch, axis=1).ravel()) / math.sqrt(2))
                levels.append(float(np.median(patch)))
    return (float(np.median(levels)), float(np.median(sigmas))) if sigmas else None


def _noise_at(level: float, background: tuple[float, float], plateaus: list[tuple[float, float]]) -> float:
    """Noise sigma at ``level``: a straight-line fit of variance against level (shot noise is linear in the
    signal, read and quantisation noise constant) through the background and the edge plateaus; the
    background's sigma when the plateaus do not span a range of levels (or the fit is not increasing)."""
    pts = np.array([background, *plateaus], float)
    if len(pts) < 3 or np.ptp(pts[:, 0]) <= 0:
        return background[1]
    slope, intercept = np.polyfit(pts[:, 0], pts[:, 1] ** 2, 1)
    var = slope * level + intercept
    return float(math.sqrt(var)) if slope >= 0 and var > 0 else background[1]


def measure_snr(image, truth: Mapping[str, Any] | Truth, *, pixel_m: float) -> SnrResult:
    """GIQE contrast SNR of ``image`` (see the module docstring).

    Parameters
    ----------
    image : array_like, 2-D
        The image (any linear unit: DN, electrons, ...), its top-left pixel at the scene origin.
    truth : mapping or Truth
        The scene's truth record (``items`` with ``bbox_m``; slanted edges with ``edge_point_m``,
        ``normal_to_bright``, ``bright``, ``dark``).
    pixel_m : float
        Ground size of the image's pixels, m.

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> truth = {"items": [{"kind": "slanted_edge", "bbox_m": [0, 0, 40, 40], "edge_point_m": [20, 20],
    ...                     "normal_to_bright": [1.0, 0.0], "bright": 0.6, "dark": 0.1}]}
    >>> img = 100 + 1000 * np.where(np.arange(40) >= 20, 0.6, 0.1) * np.ones((96, 1))
    >>> img = np.hstack([img, np.full((96, 56), 300.0)]) + rng.normal(0, 2.0, (96, 96))
    >>> r = measure_snr(img, truth, pixel_m=1.0)
    >>> abs(r.snr / (1000 * 0.08 / 2.0) - 1) < 0.1
    True
    """
    a = as_float_array("image", image, ndim=2)
    pixel_m = check_positive("pixel_m", pixel_m)
    truth = truth.to_dict() if hasattr(truth, "to_dict") else truth  # a satchain.scene.truth.Truth
    items = list(truth.get("items", []))
    gains, plateaus = [], []
    for it in items:
        if it.get("kind") == SlantedEdge.kind:
            g, levels = _edge_plateaus(a, it, pixel_m)
            if g:
                gains.append(g)
                plateaus += levels
    bg = _background_noise(a, items, pixel_m)
    gain = float(np.median(gains)) if gains else None
    if gain is None:
        reason = "no slanted edge with plateaus on both sides inside the image (the gain needs one)"
    elif bg is None:
        reason = f"no {_PATCH_PX}x{_PATCH_PX} px background patch free of targets (the noise needs one)"
    elif bg[1] <= 0:
        reason = "the background has no measurable noise (noise-free image?)"
    else:
        r_bg = float(truth.get("background", GIQE_REFLECTANCE))
        noise = _noise_at(bg[0] + gain * (GIQE_REFLECTANCE - r_bg), bg, plateaus)
        return SnrResult(gain * GIQE_CONTRAST / noise, noise, gain, len(gains))
    return SnrResult(float("nan"), None if bg is None else bg[1], gain, len(gains), reason)
