"""Every applicable measurement of a simulated image, driven by the scene's truth record (``measure auto``).

Geometry.  The truth record (written by :mod:`satchain.scene`) gives each item in scene metres.  The image
measured has its own ground pixel ``pixel_m`` and its top-left corner at scene point ``origin_m``: pixel
``[i, j]`` covers ``x in [ox + j p, ox + (j+1) p)``, ``y in [oy + i p, oy + (i+1) p)`` (the engine's geometry
contract, phase 0).  Regions of interest are the pixels whose footprints lie inside the target, kept away from
its borders, so the surround never enters a measurement:

* **slanted edge** -- the square shrunk by ``max(3 px, 10 %)`` on every side (away from its corners and from
  the square's own borders, which are edges too).  Angles are reported in the truth's convention (``act``:
  tilt of the edge from +y towards +x; ``alt``: from +x towards +y), measured and true side by side.
* **Siemens star** -- centre and radius from the truth (the centre then refined from the data, reported as
  ``center_xy_px_measured`` with its 1-sigma); the outer 2 px of the disc and the uniform centre are left
  out.  ``cycles`` from the truth (and checked against the data).
* **bar groups** -- across the bars, from the centre of the first bar to the centre of the last (so the
  profile holds the bars and the gaps between them, never the plate around them); along the bars, the middle
  with one bar width left out at each end.  Periods in px = ``period_m / pixel_m``; groups finer than 2 px
  (beyond Nyquist) are skipped.
* **hyperbolic wedge** -- the paper's contrast scan.  At each position ``s`` along the wedge only the rows
  between the centres of the first and the last dark stripe (``t in [w/2, (2N - 3/2) w]``, ``w = w(s)``) enter
  the contrast; the others are filled with the median of those rows (which changes neither max nor min).  The
  line width at each column is ``w(s) / pixel_m`` from the truth's hyperbola.

Radiometry.  The star's input modulation, the bars' large-area levels and the wedge's contrast need image
values proportional to reflectance.  The image is calibrated to reflectance by a straight-line fit
``value = offset + gain * reflectance`` to the medians of uniform truth areas (the two sides of every slanted
edge, and the background away from every item); ``calibration`` in the result says what was used.

Items that cannot be measured at this pixel size, that lie outside the image, or whose measurement fails are
listed in ``skipped`` with the reason; real-world objects (roads, cars, ...) have no measurement defined and
are listed there too.  Nothing is dropped silently.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from satchain._validate import as_float_array, check_positive, check_range
from satchain.errors import InputError
from satchain.measure._clipping import resolve_full_scale
from satchain.measure._common import to_jsonable
from satchain.measure.bars import measure_bars
from satchain.measure.edge import measure_edge
from satchain.measure.star import measure_star
from satchain.measure.wedge import measure_wedge

__all__ = ["AutoItem", "AutoResult", "measure_auto", "OBJECT_KINDS"]

#: Scene kinds with no image-quality measurement defined (real-world objects).
OBJECT_KINDS = ("road", "car", "railway", "wagon", "house")
_EDGE_MIN_PX = 16
_EDGE_MARGIN_PX = 3
_STAR_EDGE_PX = 2.0
_STAR_MIN_PX = 8.0
_PLATEAU_PX = 4.0
_MIN_REGION_PX = 25
_MAX_SAMPLES = 1_000_000
_KEYS = {
    "slanted_edge": "slanted_edges",
    "siemens_star": "siemens_star",
    "bar_target": "bar_targets",
    "hyperbolic_wedge": "hyperbolic_wedge",
}


class _Skip(Exception):
    """An item that cannot be measured; the message is the reason."""


@dataclass(frozen=True)
class AutoItem:
    """One measured item: its truth id and kind, the core result object and its JSON summary."""

    id: str
    kind: str
    result: Any
    summary: dict


@dataclass(frozen=True)
class AutoResult:
    """Result of :func:`measure_auto`; ``to_dict()`` groups the items by kind (see the module docstring)."""

    pixel_m: float
    origin_m: tuple[float, float]
    calibration: dict
    items: tuple[AutoItem, ...]
    skipped: tuple[dict, ...]
    warnings: tuple[str, ...] = field(default=())

    def by_kind(self, kind: str) -> list[AutoItem]:
        """Measured items of one scene kind (``slanted_edge``, ``siemens_star``, ...)."""
        return [it for it in self.items if it.kind == kind]

    def to_dict(self) -> dict:
        out: dict[str, Any] = {"pixel_m": self.pixel_m, "origin_m": list(self.origin_m)}
        out["calibration"] = self.calibration
        for kind, key in _KEYS.items():
            out[key] = [it.summary for it in self.by_kind(kind)]
        out["skipped"] = list(self.skipped)
        out["warnings"] = list(self.warnings)
        return to_jsonable(out)


@dataclass(frozen=True)
class _Frame:
    """Pixel geometry of the measured image in scene metres."""

    pixel_m: float
    origin_m: tuple[float, float]
    shape: tuple[int, int]
    full_scale: float | None = None  # the sensor's full scale in the image's units (None: unknown) ...
    full_scale_refl: float | None = None  # ... and in the calibrated reflectance the star/bars/wedge read

    def px(self, x_m: float, y_m: float) -> tuple[float, float]:
        """Scene point -> continuous pixel coordinates with pixel centres at integers (x = col, y = row)."""
        p, (ox, oy) = self.pixel_m, self.origin_m
        return (x_m - ox) / p - 0.5, (y_m - oy) / p - 0.5

    def inside(self, bbox_m, margin_px: int = 0):
        """ROI ``(x0, y0, x1, y1)``: pixels whose footprints lie inside ``bbox_m``, less a margin."""
        p, (ox, oy) = self.pixel_m, self.origin_m
        xmin, ymin, xmax, ymax = (float(v) for v in bbox_m)
        x0 = math.ceil((xmin - ox) / p - 1e-9) + margin_px
        y0 = math.ceil((ymin - oy) / p - 1e-9) + margin_px
        x1 = math.floor((xmax - ox) / p + 1e-9) - margin_px
        y1 = math.floor((ymax - oy) / p + 1e-9) - margin_px
        return x0, y0, x1, y1

    def centres(self, lo_m: float, hi_m: float, axis: int) -> tuple[int, int]:
        """Half-open index range of the pixels whose centres lie in ``[lo_m, hi_m]`` along x (0) or y (1)."""
        o = self.origin_m[axis]
        i0 = math.ceil((lo_m - o) / self.pixel_m - 0.5 - 1e-9)
        i1 = math.floor((hi_m - o) / self.pixel_m - 0.5 + 1e-9) + 1
        return i0, i1

    def check_roi(self, roi) -> None:
        x0, y0, x1, y1 = roi
        ny, nx = self.shape
        if not (0 <= x0 < x1 <= nx and 0 <= y0 < y1 <= ny):
            raise _Skip(
                f"region {tuple(int(v) for v in roi)} (x0, y0, x1, y1) is not inside the image "
                f"({nx} x {ny} px): the item lies outside or across the image border"
            )


def measure_auto(
    image,
    truth: dict,
    *,
    pixel_m: float | None = None,
    origin_m: tuple[float, float] | None = None,
    ids=None,
    wedge_threshold: float = 0.15,
    full_scale: float | None = None,
) -> AutoResult:
    """Run every applicable measurement on a simulated image, guided by its scene's truth record.

    Parameters
    ----------
    image : array_like, 2-D
        The simulated (or real) image covering the scene's ground.
    truth : dict
        The scene truth record (``satchain-scene-truth/1``, the ``*.truth.json`` written with a render).
    pixel_m : float, optional
        Ground size of the image's pixels (m).  By default ``truth["image_pixel_m"]`` if present, else the
        truth's render ``pixel_m`` when the image has the render's shape; otherwise an error.
    origin_m : (x, y), optional
        Scene point (m) of the image's top-left corner; by default the corner of the truth's render window
        (``(0, 0)`` for a whole-scene render).
    ids : iterable of str, optional
        Measure only these item ids.
    wedge_threshold : float
        Contrast at which wedge stripes count as no longer resolved (the paper's 15 %).
    full_scale : float, optional
        The sensor's full scale in the image's units (``2**bit_depth - 1`` for DN; the run passes its
        detector's); integer images default to their dtype maximum.  Pixels at it are clipped; without it
        clipping is named only on other evidence (:func:`satchain.measure.find_clipping`).

    Returns
    -------
    AutoResult

    Examples
    --------
    >>> from satchain.scene import Scene, SlantedEdge
    >>> scene = Scene(30.0, 30.0, (SlantedEdge("e", center_m=(15.0, 15.0), size_m=24.0),), pixel_m=0.25)
    >>> img = scene.render().reshape(60, 2, 60, 2).mean(axis=(1, 3))  # 0.5 m pixels
    >>> r = measure_auto(img, scene.truth(), pixel_m=0.5)
    >>> e = r.to_dict()["slanted_edges"][0]
    >>> e["direction"], round(e["angle_deg"], 1), e["angle_deg_truth"]
    ('ACT', 5.0, 5.0)
    """
    raw = np.asarray(image)
    data = as_float_array("image", raw, ndim=2, finite=False)
    items = _truth_items(truth)
    p, origin = _geometry(truth, data.shape, pixel_m, origin_m)
    thr = check_range("wedge_threshold", wedge_threshold, 0.0, 1.0, lo_open=True, hi_open=True)
    frame = _Frame(p, origin, data.shape)
    cal = _calibrate(data, truth, items, frame)
    refl = (data - cal["offset"]) / cal["gain"]
    fs = resolve_full_scale(raw, full_scale)
    frame = replace(frame, full_scale=fs, full_scale_refl=None if fs is None else (fs - cal["offset"]) / cal["gain"])
    wanted = None if ids is None else {str(i) for i in ids}
    measured, skipped = [], []
    for it in items:
        kind, ident = str(it.get("kind")), str(it.get("id"))
        if wanted is not None and ident not in wanted:
            continue
        if kind in OBJECT_KINDS:
            skipped.append(_skip(ident, kind, "no measurement defined for this kind (real-world object)"))
            continue
        if kind not in _KEYS:
            skipped.append(_skip(ident, kind, f"unknown kind {kind!r}: no measurement defined"))
            continue
        try:
            if kind == "slanted_edge":
                measured.append(_edge_item(raw, it, frame))
            elif kind == "siemens_star":
                measured.append(_star_item(refl, it, frame, cal["fitted"]))
            elif kind == "bar_target":
                item, sk = _bars_item(refl, it, frame, cal["fitted"])
                measured.append(item)
                skipped += sk
            else:
                measured.append(_wedge_item(refl, it, frame, thr))
        except _Skip as exc:
            skipped.append(_skip(ident, kind, str(exc)))
        except InputError as exc:
            skipped.append(_skip(ident, kind, f"measurement failed: {exc}"))
        except (KeyError, TypeError, IndexError) as exc:
            skipped.append(_skip(ident, kind, f"truth record incomplete or malformed: {exc!r}"))
    if wanted is not None:
        missing = sorted(wanted - {str(it.get("id")) for it in items})
        if missing:
            raise InputError(f"ids = {missing}: no such item in the truth record")
    warnings = () if cal["fitted"] else (f"radiometric calibration: {cal['note']}",)
    return AutoResult(p, origin, cal, tuple(measured), tuple(skipped), warnings)


def _skip(ident: str, kind: str, reason: str) -> dict:
    return {"id": ident, "kind": kind, "reason": reason}


def _truth_items(truth) -> list[dict]:
    if not isinstance(truth, dict) or not isinstance(truth.get("items"), list):
        raise InputError("truth: must be a scene truth record (a dict with an 'items' list)")
    bad = [i for i, it in enumerate(truth["items"]) if not isinstance(it, dict)]
    if bad:
        raise InputError(f"truth.items[{bad[0]}]: must be an object with 'kind' and 'id'")
    return truth["items"]


def _geometry(truth: dict, shape, pixel_m, origin_m):
    """Resolve the image's pixel size and origin (see :func:`measure_auto`)."""
    t_pix = truth.get("pixel_m")
    win = truth.get("window_px") or [0, 0, 0, 0]
    if pixel_m is None:
        pixel_m = truth.get("image_pixel_m")
    if pixel_m is None and t_pix is not None and tuple(shape) == (int(win[2]), int(win[3])):
        pixel_m = t_pix
    if pixel_m is None:
        raise InputError(
            f"pixel_m: not given, and the image of shape {tuple(shape)} is not the truth's render "
            f"(window {win}); give the image's ground pixel size in metres"
        )
    p = check_positive("pixel_m", pixel_m, error=InputError)
    if origin_m is None:
        tp = float(t_pix) if t_pix is not None else 0.0
        origin_m = (int(win[1]) * tp, int(win[0]) * tp)
    try:
        ox, oy = (float(v) for v in origin_m)
    except (TypeError, ValueError):
        raise InputError(f"origin_m = {origin_m!r}: must be a pair (x, y) in metres") from None
    if not (math.isfinite(ox) and math.isfinite(oy)):
        raise InputError(f"origin_m = {origin_m!r}: must be finite")
    return p, (ox, oy)


# ---------------------------------------------------------------------------------------------- radiometry


def _pixel_centres_m(frame: _Frame, roi):
    x0, y0, x1, y1 = roi
    p, (ox, oy) = frame.pixel_m, frame.origin_m
    ys, xs = np.mgrid[y0:y1, x0:x1]
    return ox + (xs + 0.5) * p, oy + (ys + 0.5) * p


def _edge_levels(data: np.ndarray, it: dict, frame: _Frame) -> list[tuple[float, float, int]]:
    """(reflectance, median value, count) of the dark and bright sides of a slanted edge."""
    roi = frame.inside(it["bbox_m"], margin_px=int(_PLATEAU_PX))
    try:
        frame.check_roi(roi)
    except _Skip:
        return []
    xs, ys = _pixel_centres_m(frame, roi)
    (cx, cy), (nx, ny) = it["edge_point_m"], it["normal_to_bright"]
    d = (xs - cx) * nx + (ys - cy) * ny
    sub = data[roi[1] : roi[3], roi[0] : roi[2]]
    out = []
    lim = _PLATEAU_PX * frame.pixel_m
    for refl, sel in ((it["dark"], d < -lim), (it["bright"], d > lim)):
        v = sub[sel]
        v = v[np.isfinite(v)]
        if v.size >= _MIN_REGION_PX:
            out.append((float(refl), float(np.median(v)), int(v.size)))
    return out


def _background_level(data: np.ndarray, truth: dict, items: list[dict], frame: _Frame):
    """(reflectance, median, count) of the background away from every item, or None."""
    if "background" not in truth:
        return None
    ny, nx = data.shape
    step = max(1, int(math.ceil(math.sqrt(data.size / _MAX_SAMPLES))))
    keep = np.ones((ny, nx), dtype=bool)
    pad = _PLATEAU_PX
    for it in items:
        try:
            x0, y0, x1, y1 = frame.inside(it["bbox_m"])
        except (KeyError, TypeError, ValueError):
            continue
        # pixels touching the bbox, grown by the margin (inside() gives the inner pixels; widen by 1 + pad)
        keep[
            max(0, y0 - 1 - int(pad)) : max(0, y1 + 1 + int(pad)),
            max(0, x0 - 1 - int(pad)) : max(0, x1 + 1 + int(pad)),
        ] = False
    v = data[::step, ::step][keep[::step, ::step]]
    v = v[np.isfinite(v)]
    if v.size < _MIN_REGION_PX:
        return None
    return float(truth["background"]), float(np.median(v)), int(v.size)


def _calibrate(data: np.ndarray, truth: dict, items: list[dict], frame: _Frame) -> dict:
    """Straight-line fit ``value = offset + gain * reflectance`` to uniform truth areas."""
    levels = []
    for it in items:
        if it.get("kind") == "slanted_edge":
            try:
                levels += _edge_levels(data, it, frame)
            except (KeyError, TypeError, ValueError):
                continue
    bg = _background_level(data, truth, items, frame)
    if bg is not None:
        levels.append(bg)
    refl = np.array([lv[0] for lv in levels])
    vals = np.array([lv[1] for lv in levels])
    info = {"levels": [{"reflectance": r, "median": v, "n_px": n} for r, v, n in levels]}
    if refl.size and np.ptp(refl) > 0.05:
        gain, offset = np.polyfit(refl, vals, 1)
        if gain > 0:
            res = float(np.max(np.abs(vals - (offset + gain * refl))) / gain)
            note = f"fitted to {refl.size} uniform areas; max residual {res:.3g} in reflectance"
            return {"offset": float(offset), "gain": float(gain), "fitted": True, "note": note, **info}
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


# -------------------------------------------------------------------------------------------------- items


def _wrap_deg(a: float) -> float:
    """Angle of an undirected line, wrapped into (-90, 90]."""
    a = (a + 90.0) % 180.0 - 90.0
    return 90.0 if a == -90.0 else a


def _to_truth_convention(angle_image_deg: float, measures: str) -> float:
    """measure_edge's angle (from +y towards +x) -> the truth's (``act``: the same; ``alt``: +x to +y)."""
    return _wrap_deg(angle_image_deg if measures == "act" else 90.0 - angle_image_deg)


def _edge_item(raw: np.ndarray, it: dict, frame: _Frame) -> AutoItem:
    """Slanted edge: the square shrunk by max(3 px, 10 %) on each side."""
    x0, y0, x1, y1 = frame.inside(it["bbox_m"])
    side = min(x1 - x0, y1 - y0)
    margin = max(_EDGE_MARGIN_PX, int(math.ceil(0.1 * side)))
    roi = (x0 + margin, y0 + margin, x1 - margin, y1 - margin)
    if min(roi[2] - roi[0], roi[3] - roi[1]) < _EDGE_MIN_PX:
        raise _Skip(
            f"too small at {frame.pixel_m:g} m pixels: the square is {side} px wide, its inner region "
            f"{max(0, side - 2 * margin)} px; need >= {_EDGE_MIN_PX} px"
        )
    frame.check_roi(roi)
    r = measure_edge(raw, roi=roi, pixel_m=frame.pixel_m, full_scale=frame.full_scale)
    measures = str(it["measures"]).lower()
    dx, dy = it["edge_direction"]
    truth_image = _wrap_deg(math.degrees(math.atan2(dx, dy)))
    warnings = list(r.warnings)
    if r.direction != measures.upper():
        warnings.append(f"the edge was measured as {r.direction} although the truth says {measures.upper()}")
    summary = {
        "id": it["id"],
        "roi_px": list(roi),
        "angle_deg": _to_truth_convention(r.angle_deg, measures),
        "angle_deg_truth": float(it["angle_deg"]),
        "angle_convention": "truth's: act = from +y towards +x, alt = from +x towards +y",
        "edge_angle_deg_image": r.angle_deg,
        "edge_angle_deg_image_truth": truth_image,
        "direction": r.direction,
        "direction_truth": measures.upper(),
        "mtf_at_nyquist": r.mtf_at_nyquist,
        "mtf_at_nyquist_std": r.mtf_at_nyquist_std,
        "mtf_at_nyquist_sigma": r.mtf_at_nyquist_sigma,
        "mtf_sigma": r.mtf_sigma,
        "flags": list(r.flags),
        "mtf50_cy_per_px": r.mtf50_cy_per_px,
        "rer": r.rer,
        "overshoot": r.overshoot,
        "n_lines": r.n_lines,
        "warnings": warnings,
        "f_cy_per_px": r.f_cy_per_px,
        "f_cy_per_m_ground": r.f_cy_per_m_ground,
        "mtf": r.mtf,
    }
    return AutoItem(str(it["id"]), "slanted_edge", r, to_jsonable(summary))


def _star_item(refl: np.ndarray, it: dict, frame: _Frame, calibrated: bool) -> AutoItem:
    """Siemens star: centre, radius and cycles from the truth; input modulation = amplitude / mean."""
    p = frame.pixel_m
    cycles = int(it["cycles"])
    xc, yc = frame.px(*it["center_m"])
    radius = float(it["radius_m"]) / p - _STAR_EDGE_PX
    inner = float(it.get("inner_radius_m", 0.0)) / p + 1.0
    if radius < _STAR_MIN_PX:
        raise _Skip(f"too small at {p:g} m pixels: usable radius {radius:.1f} px < {_STAR_MIN_PX:g} px")
    roi = (
        math.floor(xc - radius) - 1,
        math.floor(yc - radius) - 1,
        math.ceil(xc + radius) + 2,
        math.ceil(yc + radius) + 2,
    )
    frame.check_roi(roi)
    f_max = min(0.75, cycles / (2 * math.pi * max(inner, 2.0)))
    m0 = float(it["amplitude"]) / float(it["mean"]) if calibrated else None
    r = measure_star(
        refl,
        cycles=cycles,
        center=(xc - roi[0], yc - roi[1]),
        radius_px=radius,
        roi=roi,
        input_modulation=m0,
        f_max_cy_per_px=f_max,
        pixel_m=p,
        full_scale=frame.full_scale_refl,
    )
    summary = {
        "id": it["id"],
        "roi_px": list(roi),
        "cycles": cycles,
        "center_xy_px": [xc, yc],
        "radius_px": [float(r.radius_px.min()), float(r.radius_px.max())],
        "input_modulation": r.input_modulation,
        "input_modulation_from": "truth" if m0 is not None else r.input_modulation_from,
        "center_xy_px_measured": [r.center_xy_px[0] + roi[0], r.center_xy_px[1] + roi[1]],
        "center_std_px": r.center_std_px,
        "input_modulation_std": r.input_modulation_std,
        "mtf_at_nyquist": r.mtf_at_nyquist,
        "mtf_at_nyquist_std": r.mtf_at_nyquist_std,
        "f_cy_per_px": r.f_cy_per_px,
        "f_cy_per_m_ground": r.f_cy_per_m_ground,
        "mtf": r.mtf,
        "mtf_std": r.mtf_std,
        "mtf_all": r.mtf_all,
        "flags": list(r.flags),
    }
    return AutoItem(str(it["id"]), "siemens_star", r, to_jsonable(summary))


def _group_roi(group: dict, frame: _Frame, orientation: str):
    """Bar-group ROI: first to last bar centre across the bars, one bar width in from each end along them."""
    bars = np.asarray(group["bars_m"], dtype=float)
    b = float(group["bar_width_m"])
    across, along = (0, 1) if orientation == "act" else (1, 0)
    centres = 0.5 * (bars[:, across] + bars[:, across + 2])
    a0, a1 = frame.centres(float(centres.min()), float(centres.max()), across)
    lo, hi = float(bars[:, along].max()) + b, float(bars[:, along + 2].min()) - b
    l0, l1 = frame.centres(lo, hi, along)
    return (a0, l0, a1, l1) if orientation == "act" else (l0, a0, l1, a1)


def _bars_item(refl: np.ndarray, it: dict, frame: _Frame, calibrated: bool):
    """Bar target: one ROI per group; groups beyond Nyquist or too small are skipped (listed)."""
    p = frame.pixel_m
    orientation = str(it["orientation"]).lower()
    if int(it["n_bars"]) < 2:
        raise _Skip("a single bar per group has no period to measure a CTF on")
    keep, rois, skipped = [], [], []
    for k, g in enumerate(it["groups"]):
        gid = f"{it['id']}/group_{k}"
        period_px = float(g["period_m"]) / p
        if period_px < 2.0:
            reason = f"period {g['period_m']:g} m = {period_px:.2f} px < 2 px: beyond the Nyquist frequency"
            skipped.append(_skip(gid, "bar_group", reason))
            continue
        roi = _group_roi(g, frame, orientation)
        if roi[2] - roi[0] < 2 or roi[3] - roi[1] < 2:
            skipped.append(_skip(gid, "bar_group", f"region {roi} is under 2 px on a side at {p:g} m pixels"))
            continue
        try:
            frame.check_roi(roi)
        except _Skip as exc:
            skipped.append(_skip(gid, "bar_group", str(exc)))
            continue
        keep.append(k)
        rois.append(roi)
    if not keep:
        raise _Skip(f"no bar group is measurable at {p:g} m pixels (see the bar_group entries)")
    levels = (float(it["dark"]), float(it["bright"])) if calibrated else None
    direction = "ACT" if orientation == "act" else "ALT"
    while True:  # a group refused (no bars at its period, ...) is listed and the others measured
        groups = [it["groups"][k] for k in keep]
        periods_px = [float(g["period_m"]) / p for g in groups]
        try:
            r = measure_bars(
                refl,
                periods_px=periods_px,
                group_rois=rois,
                direction=direction,
                levels=levels,
                pixel_m=p,
                bars_per_group=int(it["n_bars"]),
                full_scale=frame.full_scale_refl,
            )
        except InputError as exc:
            bad = re.search(r"(?:group_rois|periods_px)\[(\d+)\]", str(exc))
            if bad is None or len(keep) < 2:
                raise
            j = int(bad.group(1))
            skipped.append(_skip(f"{it['id']}/group_{keep[j]}", "bar_group", f"refused: {exc}"))
            del keep[j], rois[j]
            continue
        if not r.refused:
            break
        for j, why in sorted(r.refused, reverse=True):  # refused alone by measure_bars: listed, the rest remeasured
            skipped.append(_skip(f"{it['id']}/group_{keep[j]}", "bar_group", f"refused: {why}"))
            del keep[j], rois[j]
    rows = [
        {
            "group": k,
            "period_m": float(g["period_m"]),
            "period_px": pp,
            "roi_px": list(roi),
            "ctf": c,
            "ctf_std": cs,
            "mtf": m,
            "phase_px": ph,
            "ctf_correction": None if r.ctf_correction is None else float(r.ctf_correction[j]),
            "flags": [f for f in r.flags if f.startswith(f"group {j}:")],
        }
        for j, (k, g, pp, roi, c, cs, m, ph) in enumerate(
            zip(keep, groups, periods_px, rois, r.ctf, r.ctf_std, r.mtf, r.phase_px, strict=True)
        )
    ]
    summary = {
        "id": it["id"],
        "direction": direction,
        "periods_m": [float(g["period_m"]) for g in groups],
        "periods_px": periods_px,
        "f_cy_per_px": r.f_cy_per_px,
        "f_cy_per_m_ground": r.f_cy_per_m_ground,
        "ctf": r.ctf,
        "ctf_std": r.ctf_std,
        "ctf_correction": r.ctf_correction,
        "mtf": r.mtf,
        "mtf_std": r.mtf_std,
        "large_area_contrast": r.large_area_contrast,
        "levels_from": "truth" if levels is not None else r.levels_from,
        "flags": list(r.flags),
        "groups": rows,
    }
    return AutoItem(str(it["id"]), "bar_target", r, to_jsonable(summary)), skipped


def _wedge_geometry(it: dict):
    """(w0, x0, length, n_stripes, horizontal, local origin) from a hyperbolic-wedge truth record."""
    w0, x0 = float(it["line_width_start_m"]), float(it["x0_m"])
    horizontal = str(it["orientation"]).lower() == "horizontal"
    return w0, x0, float(it["length_m"]), int(it["n_stripes"]), horizontal, tuple(it["local_origin_m"])


def _diagonal_wedge_grid(refl: np.ndarray, it: dict, frame: _Frame) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A diagonal wedge resampled onto its own (t, s) axes -- s at the pixel spacing, t at a quarter of it --
    by cubic-spline interpolation (``scipy.ndimage.map_coordinates``): rows are t (across the stripes),
    columns s. The contrast scan then reads line widths in metres from the wedge's own geometry."""
    from scipy import ndimage

    p = frame.pixel_m
    w0, _, length, n, _, (lox, loy) = _wedge_geometry(it)
    s_m = (np.arange(int(length / p)) + 0.5) * p
    t_m = np.arange(0.5 * w0, (2 * n - 1.5) * w0 + 1e-9, p / 4)  # fine across the stripes: max/min found
    r = np.sqrt(0.5)
    x = lox + r * (s_m[None, :] - t_m[:, None])
    y = loy + r * (s_m[None, :] + t_m[:, None])
    cols, rows = (x - frame.origin_m[0]) / p - 0.5, (y - frame.origin_m[1]) / p - 0.5
    if cols.min() < 0 or rows.min() < 0 or cols.max() > refl.shape[1] - 1 or rows.max() > refl.shape[0] - 1:
        raise _Skip("outside the image")
    ts = ndimage.map_coordinates(np.asarray(refl, float), [rows, cols], order=3, mode="nearest")
    return ts, s_m, t_m


def _wedge_item(refl: np.ndarray, it: dict, frame: _Frame, threshold: float) -> AutoItem:
    """Hyperbolic wedge: the contrast scan over the stripes only (see the module docstring). A diagonal wedge
    is first resampled onto its own axes; its resolution is along the D135 diagonal."""
    p = frame.pixel_m
    w0, x0, length, n, horizontal, (lox, loy) = _wedge_geometry(it)
    if str(it["orientation"]).lower() == "diagonal":
        ts, s_m, t_m = _diagonal_wedge_grid(refl, it, frame)
        return _scan_wedge(ts, s_m, t_m, it, w0, x0, n, t_m[1] - t_m[0], threshold, "D135", None, frame.full_scale_refl)
    if w0 / p < 1.0:
        raise _Skip(f"too small: the widest lines ({w0:g} m = {w0 / p:.2f} px) are finer than 1 px (Nyquist)")
    s_ax, t_ax = (0, 1) if horizontal else (1, 0)
    s_org, t_org = (lox, loy) if horizontal else (loy, lox)
    s0, s1 = frame.centres(s_org + 0.5 * p, s_org + length - 0.5 * p, s_ax)
    t0, t1 = frame.centres(t_org + 0.5 * w0, t_org + (2 * n - 1.5) * w0, t_ax)
    roi = (s0, t0, s1, t1) if horizontal else (t0, s0, t1, s1)
    frame.check_roi(roi)
    sub = refl[roi[1] : roi[3], roi[0] : roi[2]]
    ts = np.array(sub if horizontal else sub.T, dtype=float)  # rows = t (across the stripes), cols = s
    s_m = frame.origin_m[s_ax] + (np.arange(s0, s1) + 0.5) * p - s_org
    t_m = frame.origin_m[t_ax] + (np.arange(t0, t1) + 0.5) * p - t_org
    direction = "ALT" if horizontal else "ACT"
    return _scan_wedge(ts, s_m, t_m, it, w0, x0, n, p, threshold, direction, roi, frame.full_scale_refl)


def _scan_wedge(ts, s_m, t_m, it, w0, x0, n, p, threshold, direction, roi, full_scale=None) -> AutoItem:
    """The contrast scan on a wedge laid out as rows = t (across the stripes, spacing ``p`` m), columns = s
    (along it)."""
    w = w0 * x0 / (x0 + s_m)
    inside = (t_m[:, None] >= 0.5 * w[None, :]) & (t_m[:, None] <= (2 * n - 1.5) * w[None, :])
    count = inside.sum(axis=0)
    stop = int(np.argmax(count < 3)) if np.any(count < 3) else count.size
    if stop < 4:
        raise _Skip(f"too small at {p:g} m pixels: fewer than 4 positions with 3 or more rows across the stripes")
    ts, inside, w, s_m = ts[:, :stop], inside[:, :stop], w[:stop], s_m[:stop]
    if not np.all(np.isfinite(ts[inside])):
        raise InputError("image: the wedge region contains NaN/inf values")
    fill = np.array([np.median(ts[inside[:, j], j]) for j in range(stop)])
    ts = np.where(inside, ts, fill[None, :])
    r = measure_wedge(
        ts if direction != "ACT" else ts.T,
        line_width_px=w / p,
        direction="ACT" if direction == "ACT" else "ALT",
        threshold=threshold,
        pixel_m=p,
        full_scale=full_scale,
    )
    summary = {
        "id": it["id"],
        "orientation": it["orientation"],
        "direction": direction,
        "roi_px": None if roi is None else list(roi),
        "threshold": r.threshold,
        "resolution_m": r.resolved_line_width_m,
        "resolution_m_std": r.resolved_line_width_m_std,
        "resolved_line_width_px": r.resolved_line_width_px,
        "resolved_line_width_px_std": r.resolved_line_width_px_std,
        "flags": list(r.flags),
        "resolved_position_px": r.resolved_position_px,
        "resolved_f_cy_per_px": r.resolved_f_cy_per_px,
        "resolved_f_cy_per_m_ground": r.resolved_f_cy_per_m_ground,
        "position_px": r.position_px,
        "position_m_along_wedge": s_m[r.position_px.astype(int)],
        "line_width_m": r.line_width_px * p,
        "line_width_px": r.line_width_px,
        "contrast": r.contrast,
    }
    return AutoItem(str(it["id"]), "hyperbolic_wedge", r, to_jsonable(summary))
