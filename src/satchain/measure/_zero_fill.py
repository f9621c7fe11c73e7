"""Is the 0 of an integer image a fill outside the data (a cal/val area-of-interest crop) or a dark scene?

Cal/val tools set the pixels outside a target's area of interest to 0.  Taken for data, that fill is "clipping"
and its border a strong edge; taken for a fill, a real dark area clipped at 0 would lose its edges.  The two
differ in what an optical image cannot do: every image of a scene passes through a PSF and a pixel aperture that
spread a step over >= 1 px, so a dark area clipped at 0 rises from 0 through intermediate values (its border
pixels sit low on a blurred ramp), while a fill cuts the finished image: the pixels bordering it hold the
scene's own values, as high as the pixels a few px further in.

Evidence, on the pixels that border the zeros (4-neighbours, "border pixels"):

1. **Gap**: their 1st percentile stands off 0 by ``max(10 sigma, 5 %)`` of the data's range (``sigma``: the
   pixel noise of the non-zero pixels, 0 on a noise-free image).  A clipped dark area at any tilt to the pixel
   grid, or one met by noise, has border pixels near 0.
2. **Clean step**: the median *shortfall* ``s = (f_in - f) / f_in`` of a border pixel ``f`` below the pixel
   ``f_in`` 2 px further in (along the normal of the zeros' border) is <= 1 % plus 3 of its noise sigmas.  On a
   fill ``s`` is 0 up to noise and scene texture (either sign); on a blurred ramp every ``s`` > 0.
3. **Phase evidence**: that clean step is seen on a border tilted >= 3 deg from the pixel axes (>= 16 px and
   >= 10 % of the border).  A tilted border crosses the pixel grid at every sub-pixel phase, so a ramp shows
   at most of them; along a pixel axis, a sharp dark edge clipped deep below 0 can jump from 0 to its plateau
   in one pixel at one unlucky phase -- there the step alone cannot tell a fill, and the rule does not guess.

Verdicts: ``"fill"`` (1-3 hold: the zeros are excluded, flagged), ``"unsure"`` (1 and 2 hold, 3 is missing:
kept as data, flagged so the user can give ``nodata``), ``"data"`` (no flag).  Zeros under 1 % of the image,
zeros that do not reach the image border, and float images are data without a look (no evidence of a fill).
``benchmarks/bench_zero_fill.py`` prints the detection and false-alarm rates over Baotou-like fills and real
dark targets clipped at 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from satchain.measure._robust import estimate_noise

__all__ = ["FillEvidence", "zero_fill_evidence", "zero_fill_mask"]

FILL_MIN_FRACTION = 0.01  # zeros below this share of an image are never taken for a fill
FILL_GAP_SIGMA = 10.0  # ... nor when the pixels bordering them come within this many noise sigma of 0
FILL_GAP_RANGE = 0.05  # ... or within this share of the data's range
FILL_STEP_MAX = 0.01  # the clean step: median shortfall of a border pixel below the pixel 2 px in
FILL_STEP_IN_PX = 2.0
FILL_TILT_MIN_DEG = 3.0  # border parts this far from the pixel axes carry the phase evidence
FILL_TILTED_MIN = 16  # ... at least this many border pixels and this share of the border
FILL_TILTED_SHARE = 0.10
_ORIENT_SIGMA = 3.0  # px, window of the structure tensor that gives the border's orientation
_COHERENCE_MIN = 0.8  # ... where it is one straight line (a corner mixes two normals)


@dataclass(frozen=True)
class FillEvidence:
    """What :func:`zero_fill_evidence` saw: ``n_zero`` zeros (``fraction`` of the image), the ``gap`` of the
    border pixels' 1st percentile above 0 over the data's range and the ``gap_min`` it must reach, the median
    shortfall ``step`` (tilted border) / ``step_all`` (whole border) and the ``step_max`` they must stay under,
    ``n_border`` / ``n_tilted`` border pixels, the pixel ``sigma``, the ``verdict`` and its one-line ``note``."""

    n_zero: int
    fraction: float
    gap: float
    gap_min: float
    step: float
    step_all: float
    step_max: float
    n_border: int
    n_tilted: int
    sigma: float
    verdict: str
    note: str | None


def _border_steps(a: np.ndarray, z: np.ndarray, band_rows: int = 512):
    """Per border pixel: (shortfall below the pixel 2 px in, the border's tilt from the pixel axes in deg, the
    value 2 px in); and the border pixels' values.  Computed over bands of rows (memory O(band))."""
    pad = 20  # covers the filters' supports (4 + 1 + 12 px) and the 2 px step
    out: list[list[np.ndarray]] = [[], [], [], []]
    for y0 in range(0, a.shape[0], band_rows):
        b0, b1 = max(y0 - pad, 0), min(y0 + band_rows + pad, a.shape[0])
        band = _band_steps(a[b0:b1].astype(np.float32), z[b0:b1], y0 - b0, min(band_rows, a.shape[0] - y0))
        for o, v in zip(out, band, strict=True):
            o.append(v)
    return tuple(np.concatenate(o) for o in out)


def _band_steps(f: np.ndarray, z: np.ndarray, c0: int, n_rows: int):
    """:func:`_border_steps` for the border pixels in rows ``c0 : c0 + n_rows`` of one band."""
    from scipy import ndimage as ndi

    rest = ~z
    border = ndi.binary_dilation(z, np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], bool)) & rest
    by, bx = np.nonzero(border[c0 : c0 + n_rows])
    by = by + c0
    g = ndi.gaussian_filter(z.astype(np.float32), 1.0)
    gy, gx = ndi.sobel(g, axis=0), ndi.sobel(g, axis=1)
    jxx, jyy, jxy = (ndi.gaussian_filter(v, _ORIENT_SIGMA)[by, bx] for v in (gx * gx, gy * gy, gx * gy))
    gy, gx = gy[by, bx], gx[by, bx]
    norm = np.hypot(gx, gy)
    norm[norm == 0] = 1.0
    ny, nx = -gy / norm, -gx / norm  # into the data
    # the border's normal over the window (structure tensor): its angle from the pixel axes, where coherent
    # (a straight border; a corner mixes two normals and is no evidence of a tilt)
    ang = 0.5 * np.arctan2(2 * jxy, jxx - jyy)
    tilt = np.degrees(np.abs(np.arctan(np.tan(2 * ang)) / 2))
    coh = np.hypot(jxx - jyy, 2 * jxy) / np.maximum(jxx + jyy, 1e-12)
    tilt = np.where(coh >= _COHERENCE_MIN, tilt, 0.0)
    iy = np.clip(np.rint(by + FILL_STEP_IN_PX * ny).astype(int), 0, f.shape[0] - 1)
    ix = np.clip(np.rint(bx + FILL_STEP_IN_PX * nx).astype(int), 0, f.shape[1] - 1)
    inside = rest[iy, ix] & ~border[iy, ix]
    fb, fin = f[by, bx][inside], f[iy, ix][inside]
    return (fin - fb) / np.maximum(fin, 1.0), tilt[inside], fin, f[by, bx]


def zero_fill_evidence(image) -> FillEvidence | None:
    """The evidence that an integer image's zeros are a fill outside the data (module docstring), or None where
    they cannot be one (a float image, zeros under 1 % of it or none on its border, all zeros)."""
    a = np.asarray(image)
    if a.ndim != 2 or not np.issubdtype(a.dtype, np.integer) or min(a.shape) < 8:
        return None
    z = a == 0
    n = int(np.count_nonzero(z))
    if n < FILL_MIN_FRACTION * a.size or n == a.size:
        return None
    if not (z[0].any() or z[-1].any() or z[:, 0].any() or z[:, -1].any()):
        return None
    rest = ~z
    if a.size - n < 64:
        return None
    sigma = estimate_noise(a, valid=rest)
    s, tilt, fin, fb = _border_steps(a, z)
    k = max(1, int(np.sqrt(a.size / 4e6)))  # the data's range from <= 4 Mpx
    hi = float(np.percentile(a[::k, ::k][rest[::k, ::k]], 99.5))
    gap = float(np.percentile(fb, 1)) / hi
    gap_min = max(FILL_GAP_SIGMA * sigma / hi, FILL_GAP_RANGE)
    tilted = tilt >= FILL_TILT_MIN_DEG
    n_t = int(np.count_nonzero(tilted))
    s_t = float(np.median(s[tilted])) if n_t else float("nan")
    s_all = float(np.median(s)) if s.size else float("nan")
    # each median's own noise: two pixels' noise over the level further in, 1.2533 / sqrt(n) for a median
    rel = 3 * 1.2533 * np.sqrt(2) * sigma / max(float(np.median(fin)), 1.0) if s.size else 0.0
    step_max = FILL_STEP_MAX + rel / np.sqrt(max(n_t, 1))
    phase = n_t >= max(FILL_TILTED_MIN, FILL_TILTED_SHARE * s.size)
    clean = s.size > 0 and s_all <= FILL_STEP_MAX + rel / np.sqrt(max(s.size, 1)) and (not phase or s_t <= step_max)
    verdict = "data" if gap < gap_min or not clean else ("fill" if phase else "unsure")
    ev = FillEvidence(n, n / a.size, gap, gap_min, s_t, s_all, float(step_max), int(fb.size), n_t, sigma, verdict, None)
    return _with_note(ev)


def _with_note(ev: FillEvidence) -> FillEvidence:
    head = f"{ev.n_zero} pixel(s) ({100 * ev.fraction:.0f} %) equal to 0"
    if ev.verdict == "fill":
        note = (
            f"{head} taken as nodata: a fill outside the data (its neighbours stand far off 0, at the level of "
            "the pixels further in, with no blurred rise); give nodata / --nodata to set it"
        )
    elif ev.verdict == "unsure":
        note = (
            f"{head} kept as data, though they may be a fill: their neighbours jump from 0 with no blurred rise, "
            "but only along the pixel axes, where a sharp dark edge clipped at 0 does the same; give nodata / "
            "--nodata 0 (or a valid mask) if they are a fill"
        )
    else:
        note = None
    return FillEvidence(**{**ev.__dict__, "note": note})


def zero_fill_mask(image) -> tuple[np.ndarray | None, str | None]:
    """(mask of the non-zero pixels, note) where an integer image's zeros are a fill outside the data;
    (None, note) where they may be one but the evidence does not settle it (kept as data); else (None, None).

    See :mod:`satchain.measure._zero_fill` for the evidence (a clean step from 0 to the level of the pixels
    further in, on a border tilted to the pixel grid), which a dark area clipped at 0 does not give.
    """
    ev = zero_fill_evidence(image)
    if ev is None:
        return None, None
    return (np.asarray(image) != 0 if ev.verdict == "fill" else None), ev.note
