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

Image geometry.  With ``image_affine`` (a pushbroom image sheared by Earth rotation, scaled along-track by a
line-rate error, or turned by yaw steering) every region of interest is taken through that map: an edge's
region is the largest axis-aligned box of pixels inside the square's image (a parallelogram), the star's
centre is the truth's mapped, and the uniform areas are where the map puts them.  An edge's angle is then
also given as ``angle_deg_expected``: the truth's direction through the map's linear part, the angle the
image should show (the comparison checks the measured angle against it).  The targets whose measurement
assumes the pattern aligned with the pixel grid are measured only while the map leaves them so to a stated
tolerance, and skipped with the reason otherwise, never measured wrong: a bar group while the drift of its
bars' edges across its region lowers its CTF by <= 1 % (``sinc(drift / period) >= 0.99``), a horizontal or
vertical wedge while its stripes drift <= 0.25 px over its length and its position <= 0.25 px down its
stripes.  A Siemens star, an ellipse in such an image, is measured in its own frame through the map, each
direction at the image's own frequency along it (``image_affine`` of :func:`~satchain.measure.star.measure_star`;
with ``row_offsets_px`` its rows aligned too).  A diagonal wedge is resampled through the map onto its own axes.
Periods and line widths are read in pixels of the axis across the pattern (its ground step ``Frame.step_m``).

Radiometry.  The star's input modulation, the bars' large-area levels and the wedge's contrast need image
values proportional to reflectance.  The image is calibrated to reflectance by a fit of
``value = offset + gain * reflectance`` to uniform truth areas (the two sides of every slanted edge, and the
background away from every item), the diffraction tail of the PSF that pulls every plateau toward its
surroundings modelled (:mod:`satchain.measure.auto._calibrate`); ``calibration`` in the result says what was
used.

Kinds.  :data:`MEASURERS` maps each scene kind to its result key and measuring function; a new target kind is
one entry there (and one in :data:`satchain.report.kinds.REPORT_KINDS` to show it).

Items that cannot be measured at this pixel size, that lie outside the image, or whose measurement fails are
listed in ``skipped`` with the reason; real-world objects (roads, cars, ...) have no measurement defined and
are listed there too.  Nothing is dropped silently.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from satchain._validate import as_float_array, check_positive, check_range, masked_as_nan
from satchain.errors import InputError
from satchain.measure._clipping import resolve_full_scale
from satchain.measure._common import to_jsonable
from satchain.measure._keys import RESULT_KEY
from satchain.measure.auto._calibrate import calibrate
from satchain.measure.auto._common import AutoContext, AutoItem, Frame, Skip, skip_entry
from satchain.measure.auto._items import bars_item, edge_item, star_item
from satchain.measure.auto._wedge import wedge_item
from satchain.scene.layout import OBJECT_KINDS
from satchain.scene.targets import BarTarget, HyperbolicWedge, SiemensStar, SlantedEdge

__all__ = [
    "MEASURERS",
    "OBJECT_KINDS",
    "AutoItem",
    "AutoResult",
    "Measurer",
    "check_image_affine",
    "measure_auto",
    "truth_origin_m",
]

#: A per-kind measurer: ``(context, truth item) -> (AutoItem, skipped entries)``; raises ``Skip`` (the reason)
#: or ``InputError`` for an item it cannot measure.
MeasureFn = Callable[[AutoContext, dict], tuple[AutoItem, list[dict]]]


@dataclass(frozen=True)
class Measurer:
    """One target kind of :func:`measure_auto`: the scene ``kind``, the ``key`` its results are grouped under in
    ``AutoResult.to_dict()`` (and results.json), and the function that measures one item."""

    kind: str
    key: str
    measure: MeasureFn


#: The registry of measurable scene kinds, in the order of ``AutoResult.to_dict()``.  A new target kind is one
#: entry; real-world objects (:data:`OBJECT_KINDS`) have no measurement defined.
MEASURERS: dict[str, Measurer] = {
    m.kind: m
    for m in (
        Measurer(SlantedEdge.kind, RESULT_KEY[SlantedEdge.kind], edge_item),
        Measurer(SiemensStar.kind, RESULT_KEY[SiemensStar.kind], star_item),
        Measurer(BarTarget.kind, RESULT_KEY[BarTarget.kind], bars_item),
        Measurer(HyperbolicWedge.kind, RESULT_KEY[HyperbolicWedge.kind], wedge_item),
    )
}


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
        for m in MEASURERS.values():
            out[m.key] = [it.summary for it in self.by_kind(m.kind)]
        out["skipped"] = list(self.skipped)
        out["warnings"] = list(self.warnings)
        return to_jsonable(out)


def measure_auto(
    image,
    truth: dict,
    *,
    pixel_m: float | None = None,
    origin_m: tuple[float, float] | None = None,
    ids=None,
    wedge_threshold: float = 0.15,
    full_scale: float | None = None,
    image_affine=None,
    row_offsets_px=None,
) -> AutoResult:
    """Run every applicable measurement on a simulated image, guided by its scene's truth record.

    Parameters
    ----------
    image : array_like, 2-D
        The simulated (or real) image covering the scene's ground.  NaN and a numpy masked array's masked
        pixels are nodata: left out of the calibration's areas and of the edges' lines; a star, bar group or
        wedge whose region holds one is skipped with the reason.
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
    image_affine : affine.Affine or 6 numbers, optional
        The image's geometry when it is not a plain grid of square pixels: scene metres (the truth's x, y) ->
        continuous pixel coordinates with pixel centres at integers, ``col = a x + b y + c``, ``row = d x + e y
        + f`` for ``(a, b, c, d, e, f)`` (a pushbroom image sheared and scaled by Earth rotation or a line-rate
        error: ``satchain run`` passes :meth:`satchain.tf.pushbroom.PushbroomTerms.image_affine`).  It places
        the image by itself (``origin_m`` is then not given; ``AutoResult.origin_m`` is the scene point of the
        image's top-left corner) and ``pixel_m`` defaults to its ACT ground step.  See "Image geometry" in the
        module docstring for what each target kind does with it.
    row_offsets_px : (du, dv), optional
        Per image row, the offsets a line of sight moving in time gives whole rows (``satchain run`` passes
        :class:`satchain.prediction.image_geometry.ImageGeometry`): a Siemens star is measured with its rows
        aligned (``row_offsets_px`` of :func:`~satchain.measure.star.measure_star`).

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
    raw = image if isinstance(image, np.ma.MaskedArray) else np.asarray(image)  # edges: masked pixels excluded
    data = as_float_array("image", masked_as_nan("image", raw), ndim=2, finite=False)  # other targets: nodata
    items = _truth_items(truth)
    frame = _frame(truth, data.shape, pixel_m, origin_m, image_affine)
    p, origin = frame.pixel_m, frame.origin_m
    thr = check_range("wedge_threshold", wedge_threshold, 0.0, 1.0, lo_open=True, hi_open=True)
    cal = calibrate(data, truth, items, frame)
    fs = resolve_full_scale(raw, full_scale)
    fs_refl = None if fs is None else (fs - cal["offset"]) / cal["gain"]
    ctx = AutoContext(raw, (data - cal["offset"]) / cal["gain"], frame, cal["fitted"], thr, fs, fs_refl, row_offsets_px)
    wanted = None if ids is None else {str(i) for i in ids}
    measured, skipped = [], []
    for it in items:
        kind, ident = str(it.get("kind")), str(it.get("id"))
        if wanted is None or ident in wanted:
            item, sk = _measure_one(ctx, it, kind, ident)
            measured += [item] if item is not None else []
            skipped += sk
    if wanted is not None:
        missing = sorted(wanted - {str(it.get("id")) for it in items})
        if missing:
            raise InputError(f"ids = {missing}: no such item in the truth record")
    warnings = () if cal["fitted"] else (f"radiometric calibration: {cal['note']}",)
    return AutoResult(p, origin, cal, tuple(measured), tuple(skipped), warnings)


def _measure_one(ctx: AutoContext, it: dict, kind: str, ident: str) -> tuple[AutoItem | None, list[dict]]:
    """One truth item through its kind's measurer: (the item or None, skipped entries)."""
    m = MEASURERS.get(kind)
    if m is None:
        why = (
            "no measurement defined for this kind (real-world object)"
            if kind in OBJECT_KINDS
            else f"unknown kind {kind!r}: no measurement defined"
        )
        return None, [skip_entry(ident, kind, why)]
    try:
        return m.measure(ctx, it)
    except Skip as exc:
        why = str(exc)
    except InputError as exc:
        why = f"measurement failed: {exc}"
    except (KeyError, TypeError, IndexError) as exc:
        why = f"truth record incomplete or malformed: {exc!r}"
    return None, [skip_entry(ident, kind, why)]


def _truth_items(truth) -> list[dict]:
    if not isinstance(truth, dict) or not isinstance(truth.get("items"), list):
        raise InputError("truth: must be a scene truth record (a dict with an 'items' list)")
    bad = [i for i, it in enumerate(truth["items"]) if not isinstance(it, dict)]
    if bad:
        raise InputError(f"truth.items[{bad[0]}]: must be an object with 'kind' and 'id'")
    return truth["items"]


def truth_origin_m(truth: dict) -> tuple[float, float]:
    """The scene point (m) of the top-left corner of the truth's render window (``(0, 0)`` for a whole-scene
    render): where :func:`measure_auto` puts an image's corner by default."""
    t_pix = truth.get("pixel_m")
    win = truth.get("window_px") or [0, 0, 0, 0]
    tp = float(t_pix) if t_pix is not None else 0.0
    return int(win[1]) * tp, int(win[0]) * tp


def check_image_affine(image_affine) -> tuple[float, float, float, float, float, float] | None:
    """``image_affine`` as ``(a, b, c, d, e, f)`` (see :func:`measure_auto`), or None; a clear error otherwise."""
    if image_affine is None:
        return None
    allowed = (
        "must be an affine.Affine or 6 finite numbers (a, b, c, d, e, f) mapping scene metres to image pixels "
        "(col = a x + b y + c, row = d x + e y + f), invertible"
    )
    try:
        vals = tuple(image_affine)
    except TypeError:
        vals = ()
    if len(vals) == 9 and tuple(vals[6:]) == (0, 0, 1):
        vals = vals[:6]
    ok = len(vals) == 6 and all(isinstance(v, (int, float, np.integer, np.floating)) for v in vals)
    ok = ok and not any(isinstance(v, (bool, np.bool_)) for v in vals)
    coeffs = tuple(float(v) for v in vals) if ok else ()
    if not ok or not all(math.isfinite(v) for v in coeffs):
        raise InputError(f"image_affine = {image_affine!r}: {allowed}")
    a, b, c, d, e, f = coeffs
    det = a * e - b * d
    if det == 0 or abs(det) <= 1e-12 * (abs(a) + abs(b)) * (abs(d) + abs(e)):
        raise InputError(f"image_affine = {image_affine!r}: not invertible (a e - b d = {det:g}); {allowed}")
    return a, b, c, d, e, f


def _frame(truth: dict, shape, pixel_m, origin_m, image_affine) -> Frame:
    """The image's :class:`Frame` (see :func:`measure_auto`)."""
    coeffs = check_image_affine(image_affine)
    if coeffs is None:
        p, origin = _geometry(truth, shape, pixel_m, origin_m)
        return Frame(p, origin, tuple(shape))
    if origin_m is not None:
        raise InputError(
            f"origin_m = {origin_m!r}: give origin_m or image_affine, not both (image_affine places the image)"
        )
    geo = Frame(1.0, (0.0, 0.0), tuple(shape), coeffs)
    p = geo.step_m(0) if pixel_m is None else check_positive("pixel_m", pixel_m, error=InputError)
    origin = geo.metres(-0.5, -0.5)
    return Frame(p, (float(origin[0]), float(origin[1])), tuple(shape), coeffs)


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
        origin_m = truth_origin_m(truth)
    try:
        ox, oy = (float(v) for v in origin_m)
    except (TypeError, ValueError):
        raise InputError(f"origin_m = {origin_m!r}: must be a pair (x, y) in metres") from None
    if not (math.isfinite(ox) and math.isfinite(oy)):
        raise InputError(f"origin_m = {origin_m!r}: must be finite")
    return p, (ox, oy)
