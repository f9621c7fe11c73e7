"""Radiometric calibration of an image to reflectance from the uniform areas of its scene truth.

The image is taken as linear in reflectance, ``value = offset + gain * rho``, seen through the system's
point-spread function.  The uniform areas of the truth -- the dark and bright sides of every slanted edge and
the background away from every item -- give the levels, each from the pixels at least :data:`ERODE_PX` inside
its area.

A diffraction-limited PSF is not compact: a hard-edged pupil (circular, obscured or not) gives a PSF whose
envelope falls as ``r**-3`` far from its core (the asymptote of the Airy pattern; Born & Wolf, *Principles of
Optics*, 8.5.2), so a fraction of every pixel's signal comes from tens of pixels away and a plateau's median
is pulled toward its surroundings by ~1 % of the step well inside a 120 px square.  That pull is modelled,
its strength fitted: with ``S(p) = sum_{r0 <= |q - p| <= R} value(q) / |q - p|**3`` (plus the image mean for
what lies beyond ``R``), every calibration pixel obeys

    ``value(p) = (1 - M) (offset + gain * rho(p)) + K S(p)``,  ``M = K sum 1 / r**3``,

where ``M`` is the fraction of the PSF beyond ``r0`` (:data:`TAIL_RMIN_PX`).  A linear least-squares fit of
``value`` on ``(1, rho, S)`` gives ``(1 - M) offset``, ``(1 - M) gain`` and ``K``.  A system without such a
tail (a Gaussian blur) fits ``K = 0`` and the plain straight line; a negative fitted tail (not physical) falls
back to the plain line.  The fit uses the medians of the pixels binned by ``S`` (robust to stray pixels).
"""

from __future__ import annotations

import math

import numpy as np

from satchain.measure._common import fill_invalid
from satchain.measure.auto._common import Frame, Skip
from satchain.scene.targets import SlantedEdge

__all__ = ["ERODE_PX", "TAIL_RMAX_PX", "TAIL_RMIN_PX", "calibrate"]

#: Calibration pixels lie at least this far (px) inside their uniform area (the PSF's core stays inside).
ERODE_PX = 6
#: Inner radius (px) of the modelled PSF tail; the core inside it is not modelled.
TAIL_RMIN_PX = 4.0
#: Outer radius (px) of the tail sum; beyond it the image mean stands in for the surroundings.
TAIL_RMAX_PX = 128
_MIN_REGION_PX = 25
_MAX_SAMPLES = 1_000_000
_BINS = 8
_MAX_TAIL_FRACTION = 0.5
_PASSES = 3

#: Background ring (px) around each edge's sides that enters the tail model with them.
_RING_PX = 64

_Region = tuple[float, np.ndarray, np.ndarray]  # (reflectance, rows, cols) of a uniform area's pixels


def _edge_regions(data: np.ndarray, it: dict, frame: Frame) -> list[_Region]:
    """The dark and bright sides of a slanted edge, ``ERODE_PX`` inside the square and away from the edge."""
    roi = frame.inside(it["bbox_m"], margin_px=ERODE_PX)
    try:
        frame.check_roi(roi)
    except Skip:
        return []
    xs, ys = frame.centres_m(roi)
    (cx, cy), (nx, ny) = it["edge_point_m"], it["normal_to_bright"]
    d = (xs - cx) * nx + (ys - cy) * ny
    lim = ERODE_PX * frame.pixel_m
    rows, cols = np.mgrid[roi[1] : roi[3], roi[0] : roi[2]]
    out = []
    for refl, sel in ((it["dark"], d < -lim), (it["bright"], d > lim)):
        sel = sel & np.isfinite(data[rows, cols])
        if np.count_nonzero(sel) >= _MIN_REGION_PX:
            out.append((float(refl), rows[sel], cols[sel]))
    return out


def _background_region(data: np.ndarray, truth: dict, items: list[dict], frame: Frame, window) -> _Region | None:
    """The background ``ERODE_PX`` away from every item's box (within ``window``, sampled), or None."""
    if "background" not in truth:
        return None
    x0, y0, x1, y1 = window
    keep = np.zeros(data.shape, dtype=bool)
    keep[y0:y1, x0:x1] = True
    for it in items:
        try:
            bx0, by0, bx1, by1 = frame.covering(it["bbox_m"])
        except (KeyError, TypeError, ValueError):
            continue
        g = ERODE_PX  # every pixel the item touches, widened by the margin
        keep[max(0, by0 - g) : max(0, by1 + g), max(0, bx0 - g) : max(0, bx1 + g)] = False
    step = max(1, int(math.ceil(math.sqrt(np.count_nonzero(keep) / _MAX_SAMPLES))))
    sub = np.zeros_like(keep)
    sub[::step, ::step] = True
    rows, cols = np.nonzero(keep & sub & np.isfinite(data))
    if rows.size < _MIN_REGION_PX:
        return None
    return float(truth["background"]), rows, cols


def _tail_kernel() -> np.ndarray:
    r_max = TAIL_RMAX_PX
    yy, xx = np.mgrid[-r_max : r_max + 1, -r_max : r_max + 1]
    r = np.hypot(xx, yy)
    return np.where((r >= TAIL_RMIN_PX) & (r <= r_max), 1.0 / np.maximum(r, 1.0) ** 3, 0.0)


def _convolve_valid(a: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """``scipy.signal.fftconvolve(a, kernel, mode="valid")`` by real FFTs of a fast size (scipy.signal itself
    is not imported: it pulls in scipy.stats, about a second of start-up for one convolution)."""
    import scipy.fft as sfft

    (ny, nx), (ky, kx) = a.shape, kernel.shape
    shape = [sfft.next_fast_len(n, real=True) for n in (ny + ky - 1, nx + kx - 1)]
    full = sfft.irfft2(sfft.rfft2(a, shape) * sfft.rfft2(kernel, shape), shape)
    return full[ky - 1 : ny, kx - 1 : nx]


class _Tail:
    """The r^-3 tail sum over the part of the image within ``TAIL_RMAX_PX`` of ``window`` (the image mirrored
    at its borders), plus ``2 pi / R`` times the mean for what lies beyond ``R``."""

    def __init__(self, data: np.ndarray, window) -> None:
        r_max = TAIL_RMAX_PX
        x0, y0, x1, y1 = window
        ny, nx = data.shape
        self.x0, self.y0 = max(0, x0 - r_max), max(0, y0 - r_max)
        crop = np.asarray(data[self.y0 : min(ny, y1 + r_max), self.x0 : min(nx, x1 + r_max)], dtype=float)
        finite = np.isfinite(crop)
        self.crop = np.where(finite, crop, np.median(crop[finite]))
        self.kernel = _tail_kernel()
        #: sum of the weights, the far part included: the tail fraction is K times this
        self.weight = float(self.kernel.sum() + 2 * math.pi / r_max)

    def sum(self, u: np.ndarray) -> np.ndarray:
        r_max = TAIL_RMAX_PX
        padded = np.pad(u, r_max, mode="symmetric")
        return _convolve_valid(padded, self.kernel) + (2 * math.pi / r_max) * float(np.mean(u))

    def at(self, s: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        return s[rows - self.y0, cols - self.x0]


def _points(regions: list[_Region], data: np.ndarray, s_at=None) -> np.ndarray:
    """Per region, up to ``_BINS`` points (rho, median value, median S, count) of its pixels binned by S;
    ``s_at(k, rows, cols)`` gives S at the pixels of region ``k`` (0 without)."""
    out = []
    for k, (refl, rows, cols) in enumerate(regions):
        v = data[rows, cols].astype(float)
        sv = np.zeros_like(v) if s_at is None else s_at(k, rows, cols)
        order = np.argsort(sv, kind="stable")
        nb = max(1, min(_BINS, v.size // _MIN_REGION_PX))
        for chunk in np.array_split(order, nb):
            out.append((refl, float(np.median(v[chunk])), float(np.median(sv[chunk])), chunk.size))
    return np.array(out, dtype=float).reshape(-1, 4)


def _lsq(pts: np.ndarray, with_tail: bool):
    w = np.sqrt(pts[:, 3])
    cols = [np.ones(len(pts)), pts[:, 0]] + ([pts[:, 2]] if with_tail else [])
    a = np.column_stack(cols)
    if np.linalg.matrix_rank(a) < a.shape[1]:
        return None
    coef, *_ = np.linalg.lstsq(a * w[:, None], pts[:, 1] * w, rcond=None)
    return coef, a @ coef


def _residual(pts: np.ndarray, model: np.ndarray, gain: float) -> float:
    return float(np.max(np.abs(pts[:, 1] - model)) / gain) if gain > 0 else math.inf


def _fit_tail(regions: list[_Region], owner: list[int], windows: list, data: np.ndarray, offset0: float):
    """(offset, gain, tail fraction M, max residual) of the tail model, or None when it does not apply.

    Region ``k`` lies in ``windows[owner[k]]``.  ``u`` estimates the scene above the offset, ``gain * rho``;
    each pass fits ``value = offset + (1 - M) gain rho + K S(u)`` and deconvolves the tail from the image for
    the next ``u`` (``u = (value - offset - K S(u)) / (1 - M)``): the error shrinks by ~M per pass."""
    tails = [_Tail(data, w) for w in windows]
    us = [t.crop - offset0 for t in tails]
    fit = None
    for _ in range(_PASSES):
        ss = [t.sum(u) for t, u in zip(tails, us, strict=True)]
        pts = _points(regions, data, lambda k, r, c, ss=ss: tails[owner[k]].at(ss[owner[k]], r, c))
        got = _lsq(pts, True) if len(pts) >= 4 else None
        if got is None:
            return None
        (offset, g1, k), model = got
        m = k * tails[0].weight
        if not (0.0 <= m < _MAX_TAIL_FRACTION and g1 > 0):
            return None
        fit = (float(offset), float(g1 / (1 - m)), float(m), _residual(pts, model, g1))
        us = [(t.crop - offset - k * s_) / (1 - m) for t, s_ in zip(tails, ss, strict=True)]
    return fit


def _fit(regions: list[_Region], owner: list[int], windows: list, data: np.ndarray):
    """(offset, gain, tail fraction M or None, max residual in reflectance), or None when no line fits."""
    pts = _points(regions, data)
    got = _lsq(pts, False)
    if got is None:
        return None
    (offset, gain), model = got
    plain = (float(offset), float(gain), None, _residual(pts, model, gain))
    if gain <= 0 or not windows:
        return plain
    return _fit_tail(regions, owner, windows, data, offset) or plain


def _windows(groups: list[list[_Region]], shape) -> list[tuple[int, int, int, int]]:
    """Boxes ``(x0, y0, x1, y1)`` around each edge's sides grown by ``_RING_PX``, overlapping ones merged."""
    ny, nx = shape
    boxes = []
    for g in groups:
        rr = np.concatenate([r[1] for r in g])
        cc = np.concatenate([r[2] for r in g])
        boxes.append(
            (
                max(0, int(cc.min()) - _RING_PX),
                max(0, int(rr.min()) - _RING_PX),
                min(nx, int(cc.max()) + _RING_PX + 1),
                min(ny, int(rr.max()) + _RING_PX + 1),
            )
        )
    merged = True
    while merged:
        merged = False
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                a, b = boxes[i], boxes[j]
                if a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]:
                    boxes[i] = (min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3]))
                    del boxes[j]
                    merged = True
                    break
            if merged:
                break
    return boxes


def _inside(box, rows: np.ndarray, cols: np.ndarray) -> bool:
    x0, y0, x1, y1 = box
    return bool(x0 <= cols[0] < x1 and y0 <= rows[0] < y1)


def _without_nodata(regions: list[_Region], owner: list[int], data: np.ndarray):
    """The regions free of nodata (NaN: nodata, a masked array's masked pixels), their owners, and ``data``
    with each NaN replaced by its nearest valid value (the tail sums see no NaN; the areas used hold none)."""
    bad = ~np.isfinite(data)
    if not bad.any():
        return regions, owner, data
    keep = [k for k, (_, rows, cols) in enumerate(regions) if not bad[rows, cols].any()]
    return [regions[k] for k in keep], [owner[k] for k in keep], fill_invalid(data, ~bad)


def calibrate(data: np.ndarray, truth: dict, items: list[dict], frame: Frame) -> dict:
    """``value = offset + gain * reflectance`` from the truth's uniform areas, the PSF's diffraction tail
    modelled (see the module docstring).  Returns ``offset``, ``gain``, ``fitted``, ``note``, ``levels``
    (reflectance, median value, pixel count of every area used) and ``tail_fraction`` (the fitted fraction
    of the PSF beyond :data:`TAIL_RMIN_PX`, None when not modelled)."""
    groups: list[list[_Region]] = []
    for it in items:
        if it.get("kind") == SlantedEdge.kind:
            try:
                g = _edge_regions(data, it, frame)
            except (KeyError, TypeError, ValueError):
                continue
            groups += [g] if g else []
    # the tail sum is needed around the edges only (bounded work on any image size): the background is taken
    # there too; without edges, the background of the whole image gives one level
    windows = _windows(groups, data.shape)
    regions = [r for g in groups for r in g]
    owner = [next(i for i, w in enumerate(windows) if _inside(w, r[1], r[2])) for r in regions]
    for i, w in enumerate(windows or [(0, 0, data.shape[1], data.shape[0])]):
        bg = _background_region(data, truth, items, frame, w)
        if bg is not None:
            regions.append(bg)
            owner.append(i)
    regions, owner, data = _without_nodata(regions, owner, data)
    levels = [(r, float(np.median(data[rows, cols])), int(rows.size)) for r, rows, cols in regions]
    info = {
        "levels": [{"reflectance": r, "median": v, "n_px": n} for r, v, n in levels],
        "tail_fraction": None,
    }
    refl = np.array([lv[0] for lv in levels])
    vals = np.array([lv[1] for lv in levels])
    if refl.size and np.ptp(refl) > 0.05:
        fit = _fit(regions, owner, windows, data)
        if fit is not None and fit[1] > 0:
            offset, gain, m, res = fit
            how = (
                f"the PSF's r^-3 tail modelled ({100 * m:.2f} % of it beyond {TAIL_RMIN_PX:g} px)"
                if m is not None
                else "no PSF tail modelled"
            )
            note = f"fitted to {len(levels)} uniform areas, {how}; max residual {res:.3g} in reflectance"
            info["tail_fraction"] = m
            return {"offset": float(offset), "gain": float(gain), "fitted": True, "note": note, **info}
        gain = float("nan") if fit is None else fit[1]
        note = f"fit to {refl.size} uniform areas gave a gain {gain:.3g} <= 0; image taken as reflectance"
    elif refl.size and refl.max() > 0:
        gain = float(np.mean(vals / np.where(refl > 0, refl, np.nan)))
        if gain > 0:
            note = "one reflectance level only: offset assumed 0"
            return {"offset": 0.0, "gain": gain, "fitted": True, "note": note, **info}
        note = "the one uniform area gave a non-positive gain; image taken as reflectance"
    else:
        note = "no uniform truth areas (edge sides, background) in the image; image taken as reflectance"
    return {"offset": 0.0, "gain": 1.0, "fitted": False, "note": note, **info}
