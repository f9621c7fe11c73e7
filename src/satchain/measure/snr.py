"""The GIQE contrast SNR measured on an image alone, with the scene's truth record saying where things are.

SNR = gain (0.15 - 0.07) / noise(0.15): GIQE's contrast between reflectances 0.15 and 0.07 over the noise at
reflectance 0.15 (as :func:`satchain.radiometry.contrast_snr` predicts it).

* gain (image units per unit reflectance): the step between each slanted edge's plateaus (medians >= 4 px
  from the edge) over its truth reflectance step; the median over the edges.
* noise of a flat region: the standard deviation of pixel differences over sqrt 2 (scene shading cancels),
  clipped at 3.5 sigma (iterated from the MAD's sigma) and corrected for the clip. The differences are
  horizontal, but down the columns on an ACT edge's plateaus (along the edge: across it, the blurred edge's
  residual slope 4+ px out adds ~5 % to a dark plateau's noise in the default run). Not the MAD's sigma
  itself: on integer (DN) data the MAD moves in whole DN, steps of 10-25 % of a 4-8 DN noise, and it uses
  the data at 37 % efficiency. The background's is the median over all target-free 16 x 16 px patches
  (their minimum, used before, is biased low by ~15 % with ~15 patches).
* noise at 0.15: a straight line fitted to variance against level through the background and the edge
  plateaus (shot noise grows linearly with the signal, read and quantisation noise are constant), evaluated
  at the background level + gain (0.15 - background reflectance). The background is at 0.2 in satchain's
  scenes, where shot-limited noise is sqrt(0.2 / 0.15) = 1.15 x that at 0.15: taking it as is would bias
  the SNR ~13 % low. Without plateaus of distinct levels the background's sigma is used.
* ``snr_sigma``, the 1-sigma of ``snr``: the standard deviation of the whole estimate (gain, noises, fit)
  over :data:`BOOTSTRAP_N` bootstrap resamples (seeded: the same image gives the same sigma) of the blocks
  whose noise is independent -- the rows of each plateau and the background patches -- so correlation
  between neighbouring differences is kept. None (``snr_sigma_null_means`` says why) when the SNR is not
  measured or fewer than :data:`MIN_SIGMA_PATCHES` background patches leave nothing to resample.
* ``noise_free`` (in ``flags``; the SNR is then NaN with the reason): the background's scatter is not noise. Either
  it is spatially correlated -- white noise gives second differences 3 x the variance of the first (6 / 2 sigma^2),
  smooth structure (the optics' tails around the targets in a noise-free render) far less: the median patch's
  ratio below :data:`WHITE_RATIO_MIN` (half its first differences' variance or more is structure) -- or it is
  below what the image's floats resolve (16 eps of the level).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from satchain._validate import as_float_array, check_positive, split_mask
from satchain.errors import InputError
from satchain.measure._common import ResultMixin, robust_sigma
from satchain.scene.targets import SlantedEdge

if TYPE_CHECKING:
    from satchain.scene.truth import Truth

__all__ = ["BOOTSTRAP_N", "GIQE_CONTRAST", "GIQE_REFLECTANCE", "MIN_SIGMA_PATCHES", "WHITE_RATIO_MIN", "SnrResult",
           "measure_snr"]  # fmt: skip

#: The reflectance difference GIQE's SNR is defined for (0.15 - 0.07), and the reflectance of its noise.
GIQE_CONTRAST = 0.15 - 0.07
GIQE_REFLECTANCE = 0.15
#: Bootstrap resamples behind ``snr_sigma`` (its own sampling error ~ 1 / sqrt(2 * 200) = 5 %), and the seed.
BOOTSTRAP_N = 200
_BOOTSTRAP_SEED = 0
#: Fewest background patches ``snr_sigma`` is measured from (below that the bootstrap has nothing to resample).
MIN_SIGMA_PATCHES = 8
_PATCH_PX = 16
#: var(second differences) / var(first differences) of the median background patch below which its scatter is taken
#: as structure, not noise: white noise gives 3, smooth structure ~0 (0.18 in a noise-free render of the reference
#: camera; 2.9-3.0 with white noise at SNR 50 to 5000); 1.5: half the first differences' variance is structure.
WHITE_RATIO_MIN = 1.5
_PLATEAU_PX = 4.0
_MIN_PLATEAU_SAMPLES = 20
_CLIP = 3.5
#: Variance of a unit normal truncated at +-_CLIP (what a 3.5-sigma clip leaves of the variance).
_CLIP_VAR = 1.0 - 2.0 * _CLIP * math.exp(-0.5 * _CLIP**2) / math.sqrt(2.0 * math.pi) / math.erf(_CLIP / math.sqrt(2.0))


@dataclass(frozen=True)
class SnrResult(ResultMixin):
    """``snr``: GIQE contrast SNR (NaN when not measurable, ``reason`` says why); ``noise_dn``: noise sigma of one
    pixel (image units); ``gain_dn_per_reflectance``: image units per unit reflectance; ``n_edges``: edges the
    gain came from; ``snr_sigma``: the 1-sigma of ``snr`` measured by a bootstrap over the plateaus' rows and
    the background patches (None when not measured, ``snr_sigma_null_means`` says why); ``flags``:
    ``noise_free`` when the background's scatter is not noise (see the module docstring; ``snr`` is then NaN)."""

    snr: float
    noise_dn: float | None
    gain_dn_per_reflectance: float | None
    n_edges: int
    reason: str | None = None
    snr_sigma: float | None = None
    snr_sigma_null_means: str | None = None
    flags: tuple[str, ...] = ()


def _noise_sigma(diffs: np.ndarray) -> float:
    """Noise sigma of one pixel from the horizontal differences of a flat region: their standard deviation
    within 3.5 sigma (two passes from the MAD's sigma), corrected for the clip, over sqrt 2."""
    d = diffs - np.median(diffs)
    s = robust_sigma(d) or float(np.std(d))
    for _ in range(2):
        if s <= 0:
            return 0.0
        s = float(np.std(d[np.abs(d) <= _CLIP * s])) / math.sqrt(_CLIP_VAR)
    return s / math.sqrt(2)


class _Flat:
    """A flat region by rows (the blocks a bootstrap resamples): each row's values and horizontal differences."""

    def __init__(self, block: np.ndarray, mask: np.ndarray):
        pairs = mask[:, 1:] & mask[:, :-1]
        diffs = np.diff(block, axis=1)
        keep = [i for i in range(block.shape[0]) if mask[i].any()]
        self.values = [block[i][mask[i]] for i in keep]
        self.diffs = [diffs[i][pairs[i]] for i in keep]
        self.level = float(np.median(block[mask]))

    def take(self, rows: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """(values, differences) of the rows ``rows`` (all rows when None)."""
        pick = range(len(self.values)) if rows is None else rows
        return np.concatenate([self.values[i] for i in pick]), np.concatenate([self.diffs[i] for i in pick])

    def level_noise(self, rows: np.ndarray | None) -> tuple[float, tuple[float, float] | None]:
        """The median level, and (level, noise sigma) when there are enough pairs for a noise."""
        v, d = self.take(rows)
        level = float(np.median(v))
        return level, ((level, _noise_sigma(d)) if d.size >= 2 * _MIN_PLATEAU_SAMPLES else None)


def _edge_plateaus(image: np.ndarray, it: Mapping[str, Any], frame) -> tuple[_Flat, _Flat] | None:
    """An edge's bright and dark plateaus (>= 4 px from the edge, >= 2 px inside its square), None when either
    is too small. ``frame``: the image's geometry (:class:`satchain.measure.auto._common.Frame`)."""
    x0, y0, x1, y1 = (float(v) for v in it["bbox_m"])
    c0, r0, c1, r1 = frame.covering(it["bbox_m"])
    r0, r1, c0, c1 = max(r0, 0), min(r1, image.shape[0]), max(c0, 0), min(c1, image.shape[1])
    if r1 - r0 < 12 or c1 - c0 < 12:
        return None
    rr, cc = np.mgrid[r0:r1, c0:c1]
    xm, ym = frame.metres(cc.astype(float), rr.astype(float))  # pixel centres in scene metres
    step = 2.5 * max(frame.step_m(0), frame.step_m(1))  # the pixels 2 px and more inside the square
    inside = (xm >= x0 + step) & (xm <= x1 - step) & (ym >= y0 + step) & (ym <= y1 - step)
    (px, py), (nx, ny) = it["edge_point_m"], it["normal_to_bright"]
    d = (xm - px) * nx + (ym - py) * ny
    block = image[r0:r1, c0:c1]
    far = _PLATEAU_PX * max(frame.step_m(0), frame.step_m(1))
    bright, dark = inside & (d > far), inside & (d < -far)
    if bright.sum() <= _MIN_PLATEAU_SAMPLES or dark.sum() <= _MIN_PLATEAU_SAMPLES:
        return None
    if abs(nx) > abs(ny):  # an ACT edge: take differences down its columns, along the edge, not across it
        block, bright, dark = block.T, bright.T, dark.T
    return _Flat(block, bright), _Flat(block, dark)


def _background_patches(image: np.ndarray, items, frame) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(levels, noise sigmas, white ratios) of all target-free 16 x 16 px patches of the background; a patch's
    white ratio is var(second differences) / var(first differences) along its rows (3 for white noise)."""
    occupied = np.zeros(image.shape, bool)
    for it in items:
        c0, r0, c1, r1 = frame.covering(it["bbox_m"])
        occupied[max(r0 - 2, 0) : max(r1 + 2, 0), max(c0 - 2, 0) : max(c1 + 2, 0)] = True
    n, sigmas, levels, ratios = _PATCH_PX, [], [], []
    for r in range(0, image.shape[0] - n + 1, n):
        for c in range(0, image.shape[1] - n + 1, n):
            if not occupied[r : r + n, c : c + n].any():
                patch = image[r : r + n, c : c + n]
                d1 = np.diff(patch, axis=1).ravel()
                sigmas.append(_noise_sigma(d1))
                levels.append(float(np.median(patch)))
                v1 = float(np.mean((d1 - np.median(d1)) ** 2))
                ratios.append(float(np.mean(np.diff(patch, 2, axis=1) ** 2)) / v1 if v1 > 0 else float("nan"))
    return np.array(levels), np.array(sigmas), np.array(ratios)


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


def _estimate(edges, patches, r_bg: float, rng: np.random.Generator | None = None, gain_given: float | None = None):
    """(snr, noise, gain) from the edges' plateaus and the background patches; with ``rng``, from one
    bootstrap resample of the plateaus' rows and of the patches."""

    def rows(flat: _Flat):
        return None if rng is None else rng.integers(0, len(flat.values), len(flat.values))

    gains, plateaus = [], []
    for bright, dark, step in edges:
        (hi, p_hi), (lo, p_lo) = bright.level_noise(rows(bright)), dark.level_noise(rows(dark))
        gains.append((hi - lo) / step)
        plateaus += [p for p in (p_hi, p_lo) if p is not None]
    levels, sigmas = patches[:2]
    if rng is not None:
        pick = rng.integers(0, len(levels), len(levels))
        levels, sigmas = levels[pick], sigmas[pick]
    gain = float(np.median(gains)) if gain_given is None else gain_given
    bg = (float(np.median(levels)), float(np.median(sigmas)))
    noise = _noise_at(bg[0] + gain * (GIQE_REFLECTANCE - r_bg), bg, plateaus)
    return gain * GIQE_CONTRAST / noise, noise, gain, bg[1]


def _snr_sigma(edges, patches, r_bg: float, gain_given: float | None = None) -> tuple[float | None, str | None]:
    """The bootstrap standard deviation of the SNR (see the module docstring), or None and why."""
    if len(patches[0]) < MIN_SIGMA_PATCHES:
        return None, (
            f"only {len(patches[0])} target-free background patch(es); the SNR's sigma needs at least "
            f"{MIN_SIGMA_PATCHES} to resample"
        )
    rng = np.random.default_rng(_BOOTSTRAP_SEED)
    with np.errstate(divide="ignore", invalid="ignore"):
        snr = np.array([_estimate(edges, patches, r_bg, rng, gain_given)[0] for _ in range(BOOTSTRAP_N)])
    ok = np.isfinite(snr)
    if ok.sum() < 0.9 * BOOTSTRAP_N:
        return None, f"{BOOTSTRAP_N - ok.sum()} of {BOOTSTRAP_N} bootstrap resamples gave no SNR (noise of 0?)"
    return float(np.std(snr[ok], ddof=1)), None


def measure_snr(
    image, truth: Mapping[str, Any] | Truth, *, pixel_m: float, gain: float | None = None, image_affine=None
) -> SnrResult:
    """GIQE contrast SNR of ``image`` (see the module docstring).

    Parameters
    ----------
    image : array_like, 2-D
        The image (any linear unit: DN, electrons, ...), its top-left pixel at the scene origin; every pixel
        valid (NaN and a numpy masked array's masked pixels are refused).
    truth : mapping or Truth
        The scene's truth record (``items`` with ``bbox_m``; slanted edges with ``edge_point_m``,
        ``normal_to_bright``, ``bright``, ``dark``).
    pixel_m : float
        Ground size of the image's pixels, m.
    gain : float, optional
        The image's units per unit reflectance when known better than from the edges' plateau medians, e.g.
        ``measure_auto(...).calibration["gain"]``, which models the optics' diffraction tail (the plateaus'
        medians are pulled toward their surroundings by it: the straight line through them reads the gain
        ~1.5 % low for an obscured aperture).  Default: the median over the edges of (bright - dark) / step.
    image_affine : affine.Affine or 6 numbers, optional
        Scene metres -> image pixel coordinates (centres at integers) of a pushbroom image sheared or scaled by
        its motion (as :func:`satchain.measure.auto.measure_auto` takes it); the plateaus and the target-free
        background are placed through it.

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
    from satchain.measure.auto import check_image_affine
    from satchain.measure.auto._common import Frame

    image, masked = split_mask("image", image)
    if masked is not None:
        raise InputError(
            f"image: {int(masked.sum())} pixel(s) are masked; the SNR's plateaus and background patches are placed "
            "over the whole scene and take no mask (as NaN is refused): give an image whose every pixel is valid"
        )
    a = as_float_array("image", image, ndim=2)
    pixel_m = check_positive("pixel_m", pixel_m)
    frame = Frame(pixel_m, (0.0, 0.0), a.shape, check_image_affine(image_affine))
    gain_given = None if gain is None else check_positive("gain", gain)
    truth = truth.to_dict() if hasattr(truth, "to_dict") else truth  # a satchain.scene.truth.Truth
    items = list(truth.get("items", []))
    edges = []  # (bright plateau, dark plateau, reflectance step) of each edge with a nonzero step
    for it in items:
        if it.get("kind") == SlantedEdge.kind and (flats := _edge_plateaus(a, it, frame)) is not None:
            step = float(it["bright"]) - float(it["dark"])
            if step and flats[0].level != flats[1].level:
                edges.append((*flats, step))
    patches = _background_patches(a, items, frame)
    bg_sigma = float(np.median(patches[1])) if len(patches[1]) else None
    gain, free = None, None if bg_sigma is None else _not_noise(image, bg_sigma, patches)
    if not edges:
        reason = "no slanted edge with plateaus on both sides inside the image (the gain needs one)"
    elif bg_sigma is None:
        reason = f"no {_PATCH_PX}x{_PATCH_PX} px background patch free of targets (the noise needs one)"
    elif free is not None:
        reason = free
    else:
        r_bg = float(truth.get("background", GIQE_REFLECTANCE))
        snr, noise, gain, _ = _estimate(edges, patches, r_bg, gain_given=gain_given)
        return SnrResult(snr, noise, gain, len(edges), None, *_snr_sigma(edges, patches, r_bg, gain_given))
    if edges:
        gain = float(np.median([(bright.level - dark.level) / step for bright, dark, step in edges]))
    flags = ("noise_free",) if free is not None and edges else ()
    return SnrResult(float("nan"), bg_sigma, gain, len(edges), reason, None, "the SNR is not measured: " + reason,
                     flags)  # fmt: skip


def _not_noise(image, bg_sigma: float, patches) -> str | None:
    """Why the background's scatter ``bg_sigma`` is not noise (a noise-free image), or None when it is: none at
    all, below the image's float resolution, or spatially correlated (the median patch's white ratio below
    :data:`WHITE_RATIO_MIN`)."""
    levels, _, ratios = patches
    if bg_sigma <= 0:
        return "the background has no measurable noise (noise-free image?)"
    dtype = np.asarray(image).dtype
    floor = 16 * np.finfo(dtype).eps * float(np.median(np.abs(levels))) if dtype.kind == "f" else 0.0
    if bg_sigma < floor:
        return (f"noise-free image: the background's scatter ({bg_sigma:.3g}) is below its {dtype} values' "
                f"resolution ({floor:.3g}, 16 eps of the level): no noise to measure an SNR from")  # fmt: skip
    ratio = float(np.nanmedian(ratios)) if np.isfinite(ratios).any() else float("nan")
    if ratio < WHITE_RATIO_MIN:
        return (
            f"noise-free image: the background's scatter ({bg_sigma:.3g}) is not noise: neighbouring pixels' "
            f"differences are correlated (second differences carry {ratio:.2f} x the first's variance, white "
            "noise 3), as the scene's own structure makes them, such as the optics' tails around the targets"
        )
    return None
