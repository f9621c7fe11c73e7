"""Clipping named only on evidence (issue 18): :func:`find_clipping`.

A region's own maximum is not evidence of clipping: every region has one, and a noise-free render repeats
its plateau value exactly.  Clipping is named when one of these holds:

(a) **full scale** -- pixels sit at (or above) the sensor's full scale, when it is known: the caller's
    ``full_scale`` (the run passes the detector's: ``2**bit_depth - 1`` DN, or the full well in electrons, in
    the image's units), or the dtype maximum of an integer image (255 for uint8, 65535 for uint16).  Any such
    pixel is clipped; the caller decides from their number whether to refuse or to flag.

(b) **a plateau that shows saturation** -- at least ``max(10 px, 0.5 %)`` of the pixels are *exactly* equal
    (within ``1e-9`` of the range, far below any noise) to the region's maximum (or minimum), and either

    (b1) *zero variance where noise is expected*: the data has a pixel noise ``sigma`` above twice the
         quantum of its values and 1e-4 of its range (the caller's ``noise_std``; else estimated from the
         second and fourth differences of the pixels off both extremes, and trusted only when the other
         extreme is no exact plateau), and the plateau's neighbours stand off it by more than ``0.1 sigma``:
         noisy data never repeats one value on many pixels; or

    (b2) *a step onto a flat top, on one side only* (noise-free data): along the rows or the columns
         (whichever cross the plateau's border more often), the pixel that follows a flat run (three plateau
         pixels in a row) stands off the plateau by ``g1``.  A profile cut flat runs into the plateau with a
         finite slope: median ``g1`` above ``max(2 quanta, 0.1 % of the range)``.  A smooth approach leaves
         far less: a blurred edge's Gaussian tail meets the plateau at the float's last bits (``g1 < 1e-6``
         of the range for a blur of 0.4 px or more), a quantised ramp arrives one quantum at a time.  It
         counts only when the other extreme has no flat run, or is met smoothly -- a step below 0.1 % of the
         range and 100 times below the cut side's, seen at six or more sub-pixel phases, or at two or more
         within ``1e-6`` of the range.  A pixel-sharp (unblurred) target steps onto both its plateaus, a
         clip cuts one side; but a border along an axis or at a critical tilt (``atan(1/n)``) samples n
         phases only, and a few phases can make one side of a sharp target look smooth by luck (down to
         ``1e-9`` of the range at one phase, no lower than ``6.7e-6`` at two to five, over 9000 sharp edges).

Not named, because the data alone cannot tell them from an unclipped target: a noise-free image clipped at
both extremes, one blurred by less than ~0.3 px (as a pixel-sharp target) -- at an exact critical tilt
(2-5 phases) by up to ~0.5 px, whose smooth side then steps onto its plateau by up to 2e-5 of the range --,
one whose other extreme is a
flat run sampled at one phase (a border along a pixel axis or at 45 deg); a plateau narrower than three
pixels; a few clipped pixels when the full scale is not known.  Where the noise is only estimated, a noisy
image clipped at both extremes is not named either (an exact plateau at the other extreme says the data is
noise-free there); the measurements that know their noise pass it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from satchain._validate import check_range
from satchain.errors import InputError
from satchain.measure._robust import robust_sigma

__all__ = ["Clipping", "find_clipping", "integer_full_scale", "resolve_full_scale"]

MIN_PLATEAU_PX = 10  # fewer equal pixels at the extreme are never a plateau ...
MIN_PLATEAU_FRACTION = 0.005  # ... nor a smaller share of the region
STEP_RATIO = 100.0  # ... and its step at most this many times smaller than the cut side's
MIN_PHASES = 6  # a smooth approach counts when seen at this many sub-pixel phases (critical tilts: n <= 5) ...
TAIL_MAX = 1e-6  # ... or at two or more, meeting the plateau within this share of the range (a blur's tail)
STEP_MIN = 1e-3  # a step onto a plateau above this share of the range is a cut; below, a smooth approach
NOISE_MIN = 1e-4  # data whose pixel noise is below this share of the range count as noise-free
NOISY_STEP = 0.1  # noisy data: the plateau's neighbours stand off it by more than this many sigma
_TIE_REL = 1e-9  # "exactly equal": within this share of the range


@dataclass(frozen=True)
class Clipping:
    """Evidence of clipping found by :func:`find_clipping`.

    ``side``: ``"maximum"`` or ``"minimum"``; ``level``: the clipped value; ``n_pixels`` and ``fraction``:
    the pixels at it; ``evidence``: ``"full_scale"`` (a), ``"noisy_plateau"`` (b1) or ``"kink"`` (b2);
    ``message``: one line for flags and refusals (starts with ``clipping:``).
    """

    side: str
    level: float
    n_pixels: int
    fraction: float
    evidence: str
    message: str

    def __str__(self) -> str:
        return self.message


def integer_full_scale(image) -> float | None:
    """The dtype maximum of an integer image (its ADC full scale when nothing else is known), else None.

    Examples
    --------
    >>> integer_full_scale(np.zeros(3, np.uint16)), integer_full_scale(np.zeros(3))
    (65535.0, None)
    """
    dt = np.asarray(image).dtype
    return float(np.iinfo(dt).max) if np.issubdtype(dt, np.integer) else None


def resolve_full_scale(image, full_scale=None, saturation_level=None) -> float | None:
    """The full scale a measurement uses: ``full_scale`` (or its former name ``saturation_level``), else the
    dtype maximum of an integer ``image``, else None (unknown).  Refuses a non-number and two different
    values."""
    if full_scale is not None and saturation_level is not None and full_scale != saturation_level:
        raise InputError(
            f"full_scale = {full_scale!r}, saturation_level = {saturation_level!r}: the same quantity twice; "
            "give full_scale only"
        )
    fs = full_scale if full_scale is not None else saturation_level
    if fs is None:
        return integer_full_scale(image)
    return check_range("full_scale", fs, None, None, error=InputError)


def find_clipping(
    data, *, full_scale: float | None = None, noise_std: float | None = None, valid=None, unique=None
) -> Clipping | None:
    """Evidence that ``data`` is clipped (see the module docstring for the criterion), or None.

    Parameters
    ----------
    data : array_like, 1-D or 2-D
        The region measured (finite values).
    full_scale : float, optional
        The sensor's full scale in the data's units (e.g. ``2**bits - 1`` DN); pixels at or above it are
        clipped.  Integer data default to their dtype maximum.
    noise_std : float, optional
        Pixel noise of the data (1 sigma) when the caller knows it; estimated from the data otherwise.
    valid : array_like of bool, optional
        Pixels to consider (the shape of ``data``); excluded pixels (nodata, outside an area of interest)
        are never clipping, never a plateau's neighbour and never enter the noise estimate.
    unique : ndarray, optional
        ``np.unique`` of the considered pixels' values when the caller has it already (saves a sort).

    Examples
    --------
    >>> x = np.arange(200.0)
    >>> edge = 0.05 + 0.75 / (1 + np.exp(-(x - 100) / 8))  # smooth: its top is no evidence
    >>> find_clipping(np.tile(edge, (20, 1))) is None
    True
    >>> find_clipping(np.tile(np.minimum(edge, 0.7), (20, 1))).evidence  # cut flat at 0.7
    'kink'
    >>> find_clipping(np.array([[10, 200, 255]], dtype=np.uint8)).message
    'clipping: 1 pixel(s) (33.3 %) at the full scale 255'
    """
    d, full_scale, noise_std, ok = _check_args(data, full_scale, noise_std, valid)
    if not np.any(ok):
        return None
    d_ok = d if valid is None else d[ok]  # (every pixel considered: no masked copy)
    lo, hi = float(d_ok.min()), float(d_ok.max())
    span = hi - lo
    n_ok = int(np.count_nonzero(ok))
    if full_scale is not None:
        n = int(np.count_nonzero(ok & (d >= full_scale - _TIE_REL * max(abs(full_scale), span))))
        if n:
            frac = n / n_ok
            msg = f"clipping: {n} pixel(s) ({100 * frac:.1f} %) at the full scale {full_scale:g}"
            return Clipping("maximum", full_scale, n, frac, "full_scale", msg)
    if span <= 0:
        return None
    return _fill_hint(_plateau_evidence(d, lo, hi, noise_std, ok, unique))


def _fill_hint(clip: Clipping | None) -> Clipping | None:
    """A plateau at exactly 0 at the minimum is as likely a fill outside the data (a cal/val crop's area of
    interest, an integer file without a nodata tag) as a dark area clipped at 0: the message says how to
    leave the zeros out."""
    if clip is None or clip.side != "minimum" or clip.level != 0:
        return clip
    hint = (
        "; if these zeros are a fill outside the data (no nodata tag in the file), not a dark area clipped at 0, "
        "give --nodata 0 (nodata=0 in Python) to leave them out"
    )
    return Clipping(clip.side, clip.level, clip.n_pixels, clip.fraction, clip.evidence, clip.message + hint)


def _check_valid(valid, shape) -> np.ndarray:
    """The boolean mask of the pixels to consider (all of them without ``valid``)."""
    if valid is None:
        return np.ones(shape, dtype=bool)
    v = np.atleast_2d(np.asarray(valid))
    if v.shape != shape or v.dtype != bool:
        raise InputError(f"valid: must be a boolean array of the data's shape {shape}, got {v.dtype} {v.shape}")
    return v


def _check_args(data, full_scale, noise_std, valid=None):
    """The checked inputs of :func:`find_clipping`: (2-D float data, full scale or None, noise or None, mask)."""
    d = np.atleast_2d(np.asarray(data, dtype=float))
    if d.ndim != 2 or d.size == 0:
        raise InputError(f"data: need a 1-D or 2-D array of values, got shape {np.shape(data)}")
    ok = _check_valid(valid, d.shape)
    if not np.all(np.isfinite(d if valid is None else d[ok])):
        raise InputError("data: contains NaN/inf; all values must be finite")
    if full_scale is None:
        full_scale = integer_full_scale(data)
    else:
        full_scale = check_range("full_scale", full_scale, None, None, error=InputError)
    if noise_std is not None:
        noise_std = check_range("noise_std", noise_std, 0.0, None, error=InputError)
    return d, full_scale, noise_std, ok


def _plateau_evidence(d: np.ndarray, lo: float, hi: float, noise_std: float | None, ok: np.ndarray, unique=None):
    """A flat run at the region's maximum (minimum) that shows clipping: where noise is expected, or met with
    a kink while the other extreme is reached smoothly (see the module docstring)."""
    span = hi - lo
    tol = _TIE_REL * span
    plateaus = {side: _plateau(d, v, tol, ok) for side, v in (("maximum", hi), ("minimum", lo))}
    if plateaus["maximum"] is None and plateaus["minimum"] is None:
        return None  # no flat run at either extreme: no evidence (the noise and the quantum are not needed)
    quantum = _quantum(np.unique(d[ok]) if unique is None else unique)
    step_min = max(2 * quantum, STEP_MIN * span)  # smaller steps onto a plateau: reached smoothly
    if noise_std is None:  # estimated: trusted where the other extreme is no exact plateau (noise-free there)
        sigma = _pixel_noise(d, lo, hi, tol, ok)
        trusted = {"maximum": plateaus["minimum"] is None, "minimum": plateaus["maximum"] is None}
    else:
        sigma, trusted = noise_std, {"maximum": True, "minimum": True}
    noisy = sigma > max(2 * quantum, NOISE_MIN * span)
    for side, other in (("maximum", "minimum"), ("minimum", "maximum")):
        p = plateaus[side]
        if p is None:
            continue
        n, g_near, g1, _ = p
        v, frac = (hi if side == "maximum" else lo), n / np.count_nonzero(ok)
        head = f"clipping: {n} pixel(s) ({100 * frac:.1f} %) exactly at the region {side} {v:g}"
        if noisy and trusted[side] and g_near > max(NOISY_STEP * sigma, 2 * quantum):
            msg = f"{head} while the noise elsewhere is {sigma:.3g} (a flat run where noise is expected)"
            return Clipping(side, v, n, frac, "noisy_plateau", msg)
        po = plateaus[other]
        # the other extreme: no flat run (NaN), or flat runs met smoothly at several sub-pixel phases
        smooth_other = (
            po is None
            or not np.isfinite(po[2])
            or (
                po[2] <= min(step_min, g1 / STEP_RATIO)
                and (po[3] >= MIN_PHASES or (po[3] >= 2 and po[2] <= TAIL_MAX * span))
            )
        )
        if g1 > step_min and smooth_other:
            how = "has no flat run" if po is None or not np.isfinite(po[2]) else "is reached smoothly"
            msg = (
                f"{head}, reached with a kink (median step onto it {g1:.3g} = {100 * g1 / span:.1f} % of the "
                f"range) while the {other} {how}: a profile cut flat"
            )
            return Clipping(side, v, n, frac, "kink", msg)
    return None


def _quantum(u: np.ndarray) -> float:
    """The smallest gap between the distinct values ``u`` (a DN step in quantised data; ~0 in continuous
    data)."""
    return float(np.min(np.diff(u))) if u.size > 1 else 0.0


def _plateau(d: np.ndarray, v: float, tol: float, ok: np.ndarray):
    """``(n, g_near, g1, phases)`` of the pixels equal to ``v``, None when too few for a plateau.

    ``g_near``: median gap to ``v`` of the plateau's off-plateau 4-neighbours.  ``g1``: median gap of the
    pixel after each flat run (three plateau pixels, then one off it) along the axis (rows or columns) with
    the most such runs, the one most across the plateau's border; NaN without any (a ridge, or a smooth
    extremum sampled symmetrically, two equal pixels, is no flat run).  ``phases``: how many different gaps
    (to 1 % in log) follow those runs: a tilted target samples its profile at many sub-pixel phases, one
    near 45 deg or along an axis at a few, which can make one side look smooth by luck."""
    at = np.abs(d - v) <= tol
    n = int(np.count_nonzero(at))
    if n < max(MIN_PLATEAU_PX, MIN_PLATEAU_FRACTION * d.size):
        return None
    near, per_axis = [], []
    for a, m in ((d, at), (d.T, at.T)):  # steps along x, then along y
        after = []
        for sl in (slice(None), slice(None, None, -1)):  # both senses
            aa, mm = a[:, sl], m[:, sl]
            near.append(np.abs(aa[:, 1:][mm[:, :-1] & ~mm[:, 1:]] - v))
            if aa.shape[1] >= 4:
                run = mm[:, :-3] & mm[:, 1:-2] & mm[:, 2:-1] & ~mm[:, 3:]
                after.append(np.abs(aa[:, 3:][run] - v))
        per_axis.append(np.concatenate(after) if after else np.zeros(0))
    g_near = np.concatenate(near)
    if g_near.size == 0:
        return None
    g1 = max(per_axis, key=lambda g: g.size)
    if g1.size < 3:
        return n, float(np.median(g_near)), float("nan"), 0
    phases = np.unique(np.round(100 * np.log10(np.maximum(g1, 1e-300)))).size
    return n, float(np.median(g_near)), float(np.median(g1)), int(phases)


def _pixel_noise(d: np.ndarray, lo: float, hi: float, tol: float, ok: np.ndarray) -> float:
    """Pixel noise off both extremes (0: none, or cannot tell), the smallest of four estimates.

    Along each axis the robust sigma of the second and of the fourth differences (white noise: variances
    ``6 sigma**2`` and ``70 sigma**2``; a smooth signal leaves far less in the fourth than in the second, so
    the blur of an edge is not taken for noise), over the pixels off both extremes; the smaller axis wins
    (structure across one axis is not noise).  Needs 20 % of the pixels off the extremes: a noise-free render
    is mostly exact plateaus.  Stencils that touch an excluded (not ``ok``) pixel are left out."""
    out = []
    for a, o in ((d, ok), (d.T, ok.T)):
        if a.shape[1] < 5:
            continue
        c = a[:, 2:-2]
        every = o.all()  # no excluded pixel: every stencil inside
        inside = True if every else o[:, :-4] & o[:, 1:-3] & o[:, 2:-2] & o[:, 3:-1] & o[:, 4:]
        keep = (np.abs(c - lo) > tol) & (np.abs(c - hi) > tol) & inside
        n_keep, n_inside = np.count_nonzero(keep), (c.size if every else np.count_nonzero(inside))
        if n_keep < max(0.2 * n_inside, 20):
            return 0.0
        sel = slice(None) if n_keep == keep.size else keep  # all kept: the same values, without a copy
        d2 = (a[:, 3:-1] - 2 * c + a[:, 1:-3])[sel]
        d4 = (a[:, 4:] - 4 * a[:, 3:-1] + 6 * c - 4 * a[:, 1:-3] + a[:, :-4])[sel]
        out.append(min(robust_sigma(d2) / math.sqrt(6.0), robust_sigma(d4) / math.sqrt(70.0)))
    return float(min(out)) if out else 0.0
