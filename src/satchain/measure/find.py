"""Automatic detection of slanted edges usable for MTF measurement (no truth file), as MTF Mapper does.

Algorithm
---------
1. **Noise.** Pixel noise ``sigma_n`` from the robust (MAD) response of Immerkaer's (1996) 3x3 Laplacian-
   difference mask, which cancels plateaus and linear ramps.
2. **Edge pixels**, in bands of ``band_rows`` rows (with an overlap, so memory stays O(band) in float32):
   gradient of a Gaussian (sigma 1 px); a pixel is an *edge pixel* when the gradient magnitude exceeds
   ``max(5 x its noise, 0.002 x the image's robust range)`` and the structure tensor (Gaussian window 1.5 px)
   is coherent (> 0.85): that removes corners, junctions and texture, so the four sides of a square fall
   apart into four separate components.  Only two full-size arrays are kept (a boolean mask and its labels).
3. **Segments**: 8-connected components long enough to matter; a weighted (gradient magnitude squared)
   principal-axis line fit gives the position, angle and length; collinear pieces of one edge are merged.
   Straightness: the mean offset from the fitted line of each quarter of the segment stays below 1 px, and
   the gradient directions agree (resultant length of the doubled angles > 0.98).
4. **ROI**: an axis-aligned rectangle straddling the segment: the rows (ACT edge) or columns (ALT edge) of its
   central part, trimmed at both ends so that a neighbouring side leaving a corner stays outside, and
   ``half_width_px`` on each side of the edge along the other axis (narrowed down to 0.625 x where a
   neighbour intrudes).  It must hold **only** this edge: no pixel
   farther than ``guard_px`` from the edge line may have a gradient above 10 % of the edge's own peak (or
   above the noise threshold), and each plateau must be flat to within noise.
5. **Checks**: tilt from the nearest axis in [``min_tilt_deg``, ``max_tilt_deg``] (0 deg: no phase
   diversity; 45 deg: ACT/ALT ambiguous), length >= ``min_length_px``, contrast-to-noise >= ``min_cnr``.

Every rejected segment is kept with its reason, so a refusal can say why.  Angles follow
:mod:`satchain.measure.edge`: ``angle_deg`` is the edge line's angle from the image y axis, in (-90, 90].
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from scipy import ndimage as ndi

from satchain._validate import as_float_array, check_positive, check_range
from satchain.errors import InputError
from satchain.measure._common import ResultMixin, fill_invalid, unmask, valid_mask
from satchain.measure._robust import estimate_noise

__all__ = ["EdgeCandidate", "EdgeSearch", "Rejection", "estimate_noise", "find_edges"]

_GRAD_SIGMA = 1.0  # px, Gaussian of the gradient
_TENSOR_SIGMA = 1.5  # px, structure-tensor window
_COHERENCE_MIN = 0.85
_K_NOISE = 5.0  # edge-pixel threshold in units of the gradient noise
_REL_RANGE = 0.002  # ... and in units of the image's robust range
_GRAD_NOISE_GAIN = 1.0 / np.sqrt(8 * np.pi * _GRAD_SIGMA**4)  # std of d/dx(G_sigma * noise) per unit noise
_PAD = 12  # band overlap (px): covers the Gaussian supports (4 sigma)


@dataclass(frozen=True)
class EdgeCandidate(ResultMixin):
    """A straight edge segment with an ROI that holds it alone.

    ``center_xy`` is the segment's centre (x = column, y = row, px); ``roi`` = (x0, y0, x1, y1), half-open;
    ``angle_deg`` the edge line's angle from the y axis (as :func:`~satchain.measure.edge.measure_edge`);
    ``tilt_deg`` its angle from the nearest pixel axis; ``direction`` "ACT" (near-vertical edge, normal
    along x) or "ALT"; ``contrast`` the step between the two plateaus (image units) and ``cnr`` that step
    over the pixel noise.
    """

    center_xy: tuple[float, float]
    roi: tuple[int, int, int, int]
    angle_deg: float
    tilt_deg: float
    direction: str
    length_px: float
    contrast: float
    cnr: float


@dataclass(frozen=True)
class Rejection(ResultMixin):
    """A segment that was found but not kept, with the reason (one of :data:`EdgeSearch.REASONS`)."""

    center_xy: tuple[float, float]
    angle_deg: float
    length_px: float
    reason: str
    detail: str = ""


@dataclass(frozen=True)
class EdgeSearch(ResultMixin):
    """Result of :func:`find_edges`: usable candidates (longest first), rejected segments, pixel noise."""

    candidates: tuple[EdgeCandidate, ...]
    rejected: tuple[Rejection, ...]
    noise_sigma: float
    n_segments: int
    warnings: tuple[str, ...] = field(default_factory=tuple)

    def __len__(self) -> int:
        return len(self.candidates)

    def __iter__(self):
        return iter(self.candidates)

    def rejection_counts(self) -> dict[str, int]:
        """Number of rejected segments per reason."""
        out: dict[str, int] = {}
        for r in self.rejected:
            out[r.reason] = out.get(r.reason, 0) + 1
        return out


def _robust_range(a: np.ndarray, valid=None) -> float:
    step = max(1, int(np.sqrt(a.size / 250_000)))
    sub = np.asarray(a[::step, ::step], dtype=np.float32)
    if valid is not None:
        sub = sub[valid[::step, ::step]]
    lo, hi = np.percentile(sub, [0.5, 99.5])
    return float(hi - lo)


@lru_cache(maxsize=8)
def _gauss_weights(sigma: float, order: int) -> np.ndarray:
    """The correlation weights ``ndi.gaussian_filter1d(x, sigma, order=order)`` applies (truncated at 4
    sigma): its response to a unit impulse, read back (exact: one product by 1 per output)."""
    lw = int(4.0 * sigma + 0.5)
    delta = np.zeros(2 * lw + 1)
    delta[lw] = 1.0
    w = ndi.gaussian_filter1d(delta, sigma, order=order, mode="constant")[::-1].copy()
    w.flags.writeable = False
    return w


def _gaussian(a: np.ndarray, sigma: float, orders=(0, 0)) -> np.ndarray:
    """``ndi.gaussian_filter(a, sigma, order=orders, mode="nearest")`` (the same passes, axis 0 then 1, into
    one output of ``a``'s dtype) with the kernels made once, not per call."""
    out = np.empty_like(a)
    ndi.correlate1d(a, _gauss_weights(sigma, orders[0]), 0, out, mode="nearest")
    ndi.correlate1d(out, _gauss_weights(sigma, orders[1]), 1, out, mode="nearest")
    return out


def _gradient(band: np.ndarray):
    """Gaussian-derivative gradient (gx, gy) of a float32 band."""
    gx = _gaussian(band, _GRAD_SIGMA, (0, 1))
    gy = _gaussian(band, _GRAD_SIGMA, (1, 0))
    return gx, gy


def _edge_mask(a: np.ndarray, threshold: float, band_rows: int, inner=None):
    """Boolean mask of coherent strong-gradient pixels, computed band by band in float32 (only ``inner``
    pixels, when given: those whose filters see no excluded pixel), and the gradient at its pixels: (flat
    indices, gx, gy), sorted (each band's gradient is the whole image's there: the bands overlap by the
    filters' reach)."""
    ny, nx = a.shape
    mask = np.zeros(a.shape, dtype=bool)
    flat, gxs, gys = [], [], []
    for y0 in range(0, ny, band_rows):
        lo, hi = max(0, y0 - _PAD), min(ny, y0 + band_rows + _PAD)
        band = np.asarray(a[lo:hi], dtype=np.float32)
        gx, gy = _gradient(band)
        jxx = _gaussian(gx * gx, _TENSOR_SIGMA)
        jyy = _gaussian(gy * gy, _TENSOR_SIGMA)
        jxy = _gaussian(gx * gy, _TENSOR_SIGMA)
        tr = jxx + jyy
        coh = np.sqrt((jxx - jyy) ** 2 + 4 * jxy**2) / np.maximum(tr, np.float32(1e-30))
        strong = (gx * gx + gy * gy > np.float32(threshold**2)) & (coh > _COHERENCE_MIN)
        rows = slice(y0 - lo, y0 - lo + min(band_rows, ny - y0))
        mask[y0 : min(ny, y0 + band_rows)] = strong[rows]
        k = np.flatnonzero(strong[rows])
        flat.append(k + y0 * nx)
        gxs.append(gx[rows].ravel()[k])
        gys.append(gy[rows].ravel()[k])
    if inner is not None:
        mask &= inner
    return mask, (np.concatenate(flat), np.concatenate(gxs), np.concatenate(gys))


@dataclass
class _Segment:
    xs: np.ndarray
    ys: np.ndarray
    w: np.ndarray
    gang: np.ndarray  # gradient direction (rad)

    def fit(self):
        """Weighted principal-axis line: (centre x, y, unit direction (ux, uy) with uy >= 0, length)."""
        sw = self.w.sum()
        cx, cy = (self.w * self.xs).sum() / sw, (self.w * self.ys).sum() / sw
        dx, dy = self.xs - cx, self.ys - cy
        cov = (
            np.array(
                [
                    [(self.w * dx * dx).sum(), (self.w * dx * dy).sum()],
                    [(self.w * dx * dy).sum(), (self.w * dy * dy).sum()],
                ]
            )
            / sw
        )
        evals, evecs = np.linalg.eigh(cov)
        ux, uy = evecs[:, 1]
        if uy < 0 or (uy == 0 and ux < 0):
            ux, uy = -ux, -uy
        t = dx * ux + dy * uy
        return float(cx), float(cy), float(ux), float(uy), float(t.max() - t.min() + 1.0)


def _segments(a: np.ndarray, mask: np.ndarray, min_length_px: float, grads) -> list[_Segment]:
    """Connected components of the edge mask that are long enough, with their gradient weights (``grads``:
    the gradient at the mask's pixels, from :func:`_edge_mask`)."""
    labels, n = ndi.label(mask, structure=np.ones((3, 3), dtype=int))
    flat, gx_all, gy_all = grads
    out = []
    for i, sl in enumerate(ndi.find_objects(labels), start=1):
        if sl is None:
            continue
        h, w = sl[0].stop - sl[0].start, sl[1].stop - sl[1].start
        if np.hypot(h, w) < 0.7 * min_length_px:
            continue
        yy, xx = np.nonzero(labels[sl] == i)
        yy += sl[0].start
        xx += sl[1].start
        k = np.searchsorted(flat, yy * a.shape[1] + xx)
        gxs, gys = gx_all[k].astype(float), gy_all[k].astype(float)
        out.append(_Segment(xx.astype(float), yy.astype(float), gxs**2 + gys**2, np.arctan2(gys, gxs)))
    del labels
    return out


def _merge_collinear(segs: list[_Segment], max_gap_px: float = 15.0) -> list[_Segment]:
    """Merge pieces of one edge: same polarity, angle within 1.5 deg, centre within 2 px of the other's line,
    and ends less than ``max_gap_px`` apart along it."""
    segs = sorted(segs, key=lambda s: -s.w.sum())
    merged: list[_Segment] = []
    params: list[tuple] = []  # (cx, cy, ux, uy, polarity angle, t_min, t_max) of each merged segment
    cos_tol = np.cos(np.deg2rad(1.5))

    def describe(s):
        cx, cy, ux, uy, _ = s.fit()
        t = (s.xs - cx) * ux + (s.ys - cy) * uy
        return (cx, cy, ux, uy, np.angle(np.sum(s.w * np.exp(1j * s.gang))), t.min(), t.max())

    for s in segs:
        p = describe(s)
        target = None
        if params:
            q = np.array(params)
            same_dir = np.abs(p[2] * q[:, 2] + p[3] * q[:, 3]) > cos_tol
            near = np.abs((p[0] - q[:, 0]) * q[:, 3] - (p[1] - q[:, 1]) * q[:, 2]) < 2.0
            pol = np.cos(p[4] - q[:, 4]) > 0.9
            tc = (p[0] - q[:, 0]) * q[:, 2] + (p[1] - q[:, 1]) * q[:, 3]  # p's centre along q's line
            half = 0.5 * (p[6] - p[5])
            gap = np.maximum(tc - half - q[:, 6], q[:, 5] - (tc + half))
            ok = np.nonzero(same_dir & near & pol & (gap < max_gap_px))[0]
            target = int(ok[0]) if ok.size else None
        if target is None:
            merged.append(s)
            params.append(p)
            continue
        m = merged[target]
        m.xs, m.ys = np.concatenate([m.xs, s.xs]), np.concatenate([m.ys, s.ys])
        m.w, m.gang = np.concatenate([m.w, s.w]), np.concatenate([m.gang, s.gang])
        params[target] = describe(m)
    return merged


def _straight(s: _Segment, cx, cy, ux, uy) -> str:
    """'' when the segment is straight, else the reason detail."""
    t = (s.xs - cx) * ux + (s.ys - cy) * uy
    d = (s.xs - cx) * uy - (s.ys - cy) * ux
    edges = np.quantile(t, [0.0, 0.25, 0.5, 0.75, 1.0])
    offs = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        sel = (t >= a) & (t <= b)
        if np.any(sel):
            offs.append(float((s.w[sel] * d[sel]).sum() / s.w[sel].sum()))
    dev = max(abs(o) for o in offs)
    res = float(np.abs(np.sum(s.w * np.exp(2j * s.gang))) / s.w.sum())
    if dev > 1.0:
        return f"curved: quarter-segment offsets up to {dev:.2f} px from the fitted line"
    if res < 0.98:
        return f"gradient directions disagree (resultant {res:.3f} < 0.98)"
    return ""


def _angle_from_y(ux: float, uy: float) -> float:
    ang = float(np.degrees(np.arctan2(ux, uy)))
    return ang - 180.0 if ang > 90.0 else (ang + 180.0 if ang <= -90.0 else ang)


def _roi_for(cx, cy, ux, uy, length, direction, half_w, shape, trim=None):
    """Axis-aligned ROI straddling the segment: its central part along it (``trim`` px off each end, by
    default enough to keep a side leaving a corner outside), ``half_w`` across it."""
    ny, nx = shape
    # along-axis (a) and across-axis (c) unit components; ACT: along = y, across = x
    ua, uc, ca, cc, n_a, n_c = (uy, ux, cy, cx, ny, nx) if direction == "ACT" else (ux, uy, cx, cy, nx, ny)
    slope = uc / ua
    if trim is None:
        trim = half_w * abs(slope) + 4.0
    half_len_a = 0.5 * (length - 1.0) * abs(ua) - trim
    if half_len_a < 4:
        return None
    a0, a1 = int(np.ceil(ca - half_len_a)), int(np.floor(ca + half_len_a)) + 1
    a0, a1 = max(a0, 0), min(a1, n_a)
    c_ends = (cc + (a0 - ca) * slope, cc + (a1 - 1 - ca) * slope)
    c0 = max(int(np.floor(min(c_ends) - half_w)), 0)
    c1 = min(int(np.ceil(max(c_ends) + half_w)) + 1, n_c)
    return (c0, a0, c1, a1) if direction == "ACT" else (a0, c0, a1, c1)


def _isolation(a, roi, cx, cy, ux, uy, noise, threshold, guard_px, inner_ok=None, stray_at=None):
    """(contrast, detail): detail '' when the ROI holds only this edge on flat plateaus.

    ``inner_ok``: pixels whose gradient sees no excluded pixel (others are neither structure nor plateau);
    ``stray_at``: a list that receives the (x, y) of the stray structure found."""
    x0, y0, x1, y1 = roi
    crop = np.asarray(a[y0:y1, x0:x1], dtype=np.float32)
    ok = np.ones(crop.shape, dtype=bool) if inner_ok is None else inner_ok[y0:y1, x0:x1]
    yy, xx = np.mgrid[y0:y1, x0:x1]
    d = (xx - cx) * uy - (yy - cy) * ux  # signed distance from the edge line (px)
    gx, gy = _gradient(crop)
    mag = np.hypot(gx, gy)
    peak = float(np.percentile(mag[np.abs(d) < 1.5], 90)) if np.any(np.abs(d) < 1.5) else 0.0
    far = np.abs(d) > guard_px
    # ignore the outermost pixel ring, where the 'nearest' border mode bends the gradient
    inner = np.zeros(crop.shape, dtype=bool)
    inner[2:-2, 2:-2] = True
    stray = far & inner & ok & (mag > max(threshold, 0.1 * peak))
    if stray_at is not None:
        stray_at.extend(zip(xx[stray].tolist(), yy[stray].tolist(), strict=True))
    if np.count_nonzero(stray) > max(2, 0.002 * crop.size):
        return 0.0, f"{int(np.count_nonzero(stray))} pixels of other structure farther than {guard_px:g} px"
    sides = [crop[(d < -guard_px) & ok], crop[(d > guard_px) & ok]]
    if min(s.size for s in sides) < 16:
        return 0.0, "plateaus too narrow"
    contrast = float(np.median(sides[1]) - np.median(sides[0]))
    for s, name in zip(sides, ("negative", "positive"), strict=True):
        spread = float(np.std(s))
        if spread > 3 * noise + 0.05 * abs(contrast):
            return contrast, f"{name}-side plateau not flat (std {spread:.3g} vs noise {noise:.3g})"
    return contrast, ""


def _trimmed_roi(a, line, direction, hw, p, levels):
    """(roi, contrast, detail) of the segment's ROI: first its whole length (1 px off each end); where other
    structure intrudes (a corner, a neighbouring side) the ROI ends just before it, on the side it lies, and
    is checked again.  ``roi`` None when the segment itself is too short; where the trimming would leave too
    few lines (a structure alongside the edge, not at its ends) the untrimmed ROI and its detail are returned,
    so that a narrower ROI is tried."""
    cx, cy, ux, uy, length = line
    noise, threshold, inner = levels
    roi = _roi_for(cx, cy, ux, uy, length, direction, hw, a.shape, trim=1.0)
    ax, ca = (1, cy) if direction == "ACT" else (0, cx)  # the ROI's along-edge bounds: roi[ax], roi[ax + 2]

    def too_short(r):
        return r[ax + 2] - r[ax] < max(p["min_length_px"] * 0.75, 12)

    if roi is None or too_short(roi):
        n = 0 if roi is None else roi[ax + 2] - roi[ax]
        return None, 0.0, f"ROI holds {n} lines once trimmed"
    for _ in range(6):
        stray: list = []
        contrast, why = _isolation(a, roi, cx, cy, ux, uy, noise, threshold, p["guard_px"], inner, stray)
        if not stray or not why.endswith(f"{p['guard_px']:g} px"):
            return roi, contrast, why
        pos = np.array([xy[ax] for xy in stray], dtype=float)  # along the edge
        lo, hi = pos[pos < ca], pos[pos >= ca]
        r = list(roi)
        if lo.size:
            r[ax] = max(r[ax], int(lo.max()) + 2)
        if hi.size:
            r[ax + 2] = min(r[ax + 2], int(hi.min()) - 1)
        if too_short(r):
            return roi, contrast, why
        roi = tuple(r)
    return roi, contrast, why


def _evaluate(a, s: _Segment, p: dict, noise: float, threshold: float, inner=None):
    """An EdgeCandidate, or a Rejection with its reason."""
    cx, cy, ux, uy, length = s.fit()
    ang = _angle_from_y(ux, uy)
    direction = "ACT" if abs(ang) < 45.0 else "ALT"
    tilt = abs(ang) if direction == "ACT" else 90.0 - abs(ang)

    def rej(reason, detail=""):
        return Rejection((cx, cy), ang, length, reason, detail)

    if length < p["min_length_px"]:
        return rej("short", f"{length:.0f} px < min_length_px = {p['min_length_px']:g}")
    if tilt < p["min_tilt_deg"]:
        return rej("axis-aligned", f"tilt {tilt:.2f} deg < {p['min_tilt_deg']:g} deg: no sub-pixel phase diversity")
    if tilt > p["max_tilt_deg"]:
        return rej("near 45 deg", f"tilt {tilt:.2f} deg > {p['max_tilt_deg']:g} deg: ACT/ALT ambiguous")
    polarity = float(np.abs(np.sum(s.w * np.exp(1j * s.gang))) / s.w.sum())
    if polarity < 0.9:
        return rej("not isolated", f"edges of both polarities in one segment (a thin line or bar; {polarity:.2f})")
    why = _straight(s, cx, cy, ux, uy)
    if why:
        return rej("not straight", why)
    hw0 = p["half_width_px"]
    widths = sorted({hw0, *(w for w in (0.75 * hw0, 0.625 * hw0) if w >= max(10.0, p["guard_px"] + 4))})[::-1]
    for hw in widths:  # narrower ROIs when a neighbour intrudes
        roi, contrast, why = _trimmed_roi(a, (cx, cy, ux, uy, length), direction, hw, p, (noise, threshold, inner))
        if roi is None:
            return rej("short", why)
        if not why:
            break
    if why:
        return rej("not isolated", why)
    cnr = abs(contrast) / noise if noise > 0 else float("inf")
    if cnr < p["min_cnr"]:
        return rej("low contrast", f"contrast-to-noise {cnr:.1f} < min_cnr = {p['min_cnr']:g}")
    return EdgeCandidate((cx, cy), roi, ang, tilt, direction, length, abs(contrast), cnr)


def find_edges(
    image,
    *,
    min_length_px: float = 25.0,
    min_cnr: float = 10.0,
    min_tilt_deg: float = 1.0,
    max_tilt_deg: float = 44.0,
    half_width_px: float = 16.0,
    guard_px: float = 5.0,
    max_edges: int | None = None,
    band_rows: int = 512,
    valid=None,
    nodata: float | None = None,
) -> EdgeSearch:
    """Find straight, isolated, slanted edges with enough contrast, each with an ROI for slanted-edge MTF.

    Parameters
    ----------
    image : array_like, 2-D
        The image (any real dtype; read band by band in float32, never copied whole as float64); a numpy
        masked array's masked pixels are excluded as ``valid = False`` ones are.
    min_length_px : float
        Shortest usable segment (px, along the edge).
    min_cnr : float
        Smallest step between the two plateaus, in units of the pixel noise.
    min_tilt_deg, max_tilt_deg : float
        Allowed angle between the edge and its nearest pixel axis (deg), within [0.5, 44.5].
    half_width_px : float
        ROI half-width across the edge (px); the ESF needs plateaus on both sides.  Where another structure
        intrudes, 0.75 and 0.625 of it are tried (not below 10 px nor ``guard_px + 4``).
    guard_px : float
        Distance from the edge line (px) beyond which the ROI must be free of any other structure.
    max_edges : int, optional
        Keep at most this many candidates: the longest, taken from ACT and ALT in turn (so that both
        directions stay represented).
    band_rows : int
        Rows per processing band (memory: a few float32 arrays of ``band_rows`` x width).
    valid : array_like of bool, optional
        Pixels to search (True); excluded pixels (an area-of-interest mask) are never edges, structure,
        plateau or noise: edge pixels are kept 3 px inside the valid area, so its border is no edge.
    nodata : float, optional
        Pixels equal to this value are excluded as well.

    Returns
    -------
    EdgeSearch
        ``candidates`` (longest first) and ``rejected`` (with reasons).

    Raises
    ------
    InputError
        Not a 2-D image, NaN/inf values, or an image smaller than 32 px.

    Examples
    --------
    >>> y, x = np.mgrid[0:160, 0:160]
    >>> t = np.deg2rad(6.0)
    >>> img = 0.2 + 0.6 / (1 + np.exp(-((x - 80.3) * np.cos(t) - (y - 80) * np.sin(t)) / 0.5))
    >>> s = find_edges(img)
    >>> len(s), s.candidates[0].direction, round(s.candidates[0].angle_deg, 1)
    (1, 'ACT', 6.0)
    """
    image, valid = unmask(image, valid)
    a = as_float_array("image", image, ndim=2, finite=False) if not isinstance(image, np.ndarray) else image
    ok = valid_mask(a, valid, nodata)
    inner = None
    if ok is not None:
        a = fill_invalid(a, ok)
        inner = ndi.binary_erosion(ok, np.ones((7, 7), dtype=bool))  # filters reaching no excluded pixel
    if a.ndim != 2:
        raise InputError(f"image: must be 2-D, got shape {a.shape}")
    if min(a.shape) < 32:
        raise InputError(f"image: shape {a.shape} is too small to search for edges; both sides must be >= 32 px")
    p = {
        "min_length_px": check_range("min_length_px", min_length_px, 12, None),
        "min_cnr": check_positive("min_cnr", min_cnr),
        "min_tilt_deg": check_range("min_tilt_deg", min_tilt_deg, 0.5, 44.5),
        "max_tilt_deg": check_range("max_tilt_deg", max_tilt_deg, 0.5, 44.5),
        "half_width_px": check_range("half_width_px", half_width_px, 8, 64),
        "guard_px": check_range("guard_px", guard_px, 2, 32),
    }
    if p["min_tilt_deg"] >= p["max_tilt_deg"]:
        raise InputError(f"min_tilt_deg = {min_tilt_deg:g}: must be < max_tilt_deg = {max_tilt_deg:g}")
    if p["guard_px"] >= p["half_width_px"] - 2:
        raise InputError(f"guard_px = {guard_px:g}: must be < half_width_px - 2 = {p['half_width_px'] - 2:g}")
    band_rows = int(check_range("band_rows", band_rows, 64, None))
    _check_finite(a, band_rows)
    noise = estimate_noise(a, band_rows=band_rows, valid=ok)
    threshold = max(_K_NOISE * _GRAD_NOISE_GAIN * noise, _REL_RANGE * _robust_range(a, ok), 1e-12)
    mask, grads = _edge_mask(a, threshold, band_rows, inner)
    segs = _merge_collinear(_segments(a, mask, p["min_length_px"], grads))
    del mask
    found: list[EdgeCandidate] = []
    rejected: list[Rejection] = []
    for s in segs:
        r = _evaluate(a, s, p, noise, threshold, inner)
        (found if isinstance(r, EdgeCandidate) else rejected).append(r)
    found.sort(key=lambda c: -c.length_px)
    warnings = []
    if max_edges is not None:
        max_edges = int(check_range("max_edges", max_edges, 1, None))
        if len(found) > max_edges:
            warnings.append(
                f"{len(found)} usable edges found; {max_edges} kept (max_edges: the longest, ACT and ALT in turn)"
            )
            found = _balanced(found, max_edges)
    return EdgeSearch(tuple(found), tuple(rejected), float(noise), len(segs), tuple(warnings))


def _check_finite(a: np.ndarray, band_rows: int) -> None:
    for y0 in range(0, a.shape[0], band_rows):
        band = a[y0 : y0 + band_rows]
        if np.issubdtype(band.dtype, np.floating) and not np.all(np.isfinite(band)):
            raise InputError("image: contains NaN/inf values; all values must be finite")


def _balanced(found: list[EdgeCandidate], n: int) -> list[EdgeCandidate]:
    """The ``n`` longest candidates taken from the ACT and ALT lists in turn, longest first."""
    lists = [[c for c in found if c.direction == d] for d in ("ACT", "ALT")]
    out: list[EdgeCandidate] = []
    k = 0
    while len(out) < n and any(lists):
        if lists[k % 2]:
            out.append(lists[k % 2].pop(0))
        k += 1
    return sorted(out, key=lambda c: -c.length_px)
