"""The simulated image with every target's region drawn and labelled, and per-target thumbnails at ground
truth, focal plane and detector (PNG bytes at native resolution, for the report's click-to-zoom).

All three stages of a thumbnail share one grey scale, reflectance 0..1: the detector image is converted
with the run's radiometric calibration (``measured["calibration"]``: offset and gain fitted to the truth's
uniform areas), or stretched between its 0.5 and 99.5 percentiles when there is none.
"""

from __future__ import annotations

import io
import math
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Patch, Polygon, Rectangle

from satchain.io.images import PNG_COMPRESS_LEVEL
from satchain.report._save import save_figure
from satchain.report._style import axis_band_in, place_grid, title_band_in
from satchain.report.compare_plots import rc_for
from satchain.report.kinds import REPORT_KINDS, measured_entries
from satchain.scene.objects import Car, House, Railway, Wagon

__all__ = [
    "GALLERY_KINDS",
    "assemble_thumbnail",
    "draw_image_with_rois",
    "grey8_truth_panel",
    "image_extent",
    "image_rois_args",
    "item_thumbnail",
    "mapped_box",
    "panel_maps",
    "panel_window",
    "plot_image_with_rois",
    "target_thumbnails",
    "thumbnail_boxes",
    "thumbnail_calls",
    "thumbnail_crops",
    "to_grey8",
    "truth_panel",
]

#: Measurement targets (every one is shown) and real-world objects (the first of each kind is shown).
GALLERY_KINDS = tuple(REPORT_KINDS)
OBJECT_KINDS = (Car.kind, Wagon.kind, House.kind, Railway.kind)
_OBJECT_COLOUR = "#d0d000"
#: Largest side of a native-resolution crop (px); larger crops are block-averaged by an integer factor.
MAX_SIDE_PX = 2000
#: Smallest extent shown around an object (m), so that a car is seen with its surroundings.
MIN_EXTENT_M = 12.0


def _to_reflectance(ctx):
    """Detector DN -> reflectance, with the run's calibration (or a percentile stretch)."""
    cal = (ctx.measured or {}).get("calibration") or {}
    img = np.asarray(ctx.image, float)
    gain, offset = cal.get("gain"), cal.get("offset")
    if gain:
        return (img - float(offset or 0.0)) / float(gain)
    lo, hi = np.percentile(img, [0.5, 99.5])
    return (img - lo) / max(hi - lo, 1e-12)


def plot_image_with_rois(ctx, path: Path) -> None:
    """The simulated image (detector samples) with every measured target's region of interest drawn and
    labelled, and every other object outlined by kind."""
    draw_image_with_rois(*image_rois_args(ctx), path)


def image_rois_args(ctx) -> tuple[np.ndarray, float, dict, list[dict]]:
    """The plain data :func:`draw_image_with_rois` needs (a job for a helper process). Under a pushbroom image
    map (``ctx.image_affine``: shear, along-track scale, yaw) each item carries ``outline_m``, its box's corners
    where the image has them (image metres: pixel ``(col, row)`` spans ``[col, col + 1] x gsd``)."""
    rois = {m["id"]: m["roi_px"] for _, m in measured_entries(ctx.measured) if m.get("roi_px") is not None}
    gsd, geo = float(ctx.image_gsd_m), getattr(ctx, "image_affine", None)
    items = ctx.truth["items"]
    if geo is not None:
        a, b, c, d, e, f = tuple(geo)[:6]

        def image_m(x, y):
            return ((a * x + b * y + c + 0.5) * gsd, (d * x + e * y + f + 0.5) * gsd)

        items = [dict(it, outline_m=[image_m(x, y) for x, y in _corners_m(it["bbox_m"])]) for it in items]
    return _to_reflectance(ctx), gsd, rois, items


def _corners_m(box) -> list[tuple[float, float]]:
    x0, y0, x1, y1 = box
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


def _item_shape(it: dict, **kw) -> tuple[float, float, Patch]:
    """An item's box where the image has it (``outline_m``, else ``bbox_m``): its top-left (m) and its patch."""
    outline = it.get("outline_m")
    if outline:
        x0, y0 = min(p[0] for p in outline), min(p[1] for p in outline)
        return x0, y0, Polygon(outline, closed=True, fill=False, **kw)
    x0, y0, x1, y1 = it["bbox_m"]
    return x0, y0, Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, **kw)


def draw_image_with_rois(img: np.ndarray, gsd: float, rois: dict, items: list[dict], path: Path) -> None:
    """:func:`plot_image_with_rois` from plain data: the image in reflectance, its GSD, the regions measured
    (pixel boxes by id) and the truth's items (drawn at their ``outline_m`` when they have one, the image's own
    geometry, else at their box)."""
    h, w = img.shape
    scale = min(820.0 / w, 1150.0 / h, 3.0)
    width_in = w * scale / 100 + 1.0
    with matplotlib.rc_context(rc_for(width_in)):
        fig = Figure(figsize=(width_in, h * scale / 100 + 1.0), dpi=100)  # fixed layout in inches (_style.place_grid)
        ax = fig.add_axes((0, 0, 1, 1))
        ax.imshow(img, cmap="gray", vmin=0, vmax=1, interpolation="nearest", extent=(0, w * gsd, h * gsd, 0))
        # the image fixed the limits: the boxes are added without updating the data limits (add_patch's cost)
        box = ax.add_artist
        seen = set()
        for it in items:
            x0, y0 = _item_shape(it)[:2]
            kind = it["kind"]
            if kind in REPORT_KINDS:
                c = REPORT_KINDS[kind].colour
                box(_item_shape(it, ec=c, lw=1, ls=":")[2])
                if it["id"] in rois:
                    rx0, ry0, rx1, ry1 = rois[it["id"]]
                    box(
                        Rectangle(
                            (rx0 * gsd, ry0 * gsd), (rx1 - rx0) * gsd, (ry1 - ry0) * gsd, fill=False, ec=c, lw=1.6
                        )
                    )
                ax.text(
                    x0,
                    y0 - 0.6,
                    it["id"],
                    color="white",
                    va="bottom",
                    bbox=dict(facecolor=c, edgecolor="none", pad=1.2, alpha=0.85),
                )
            else:
                lab = kind if kind not in seen else None
                seen.add(kind)
                box(_item_shape(it, ec=_OBJECT_COLOUR, lw=0.7, label=lab)[2])
        ax.set_xlabel("x, across-track (m)")
        ax.set_ylabel("y, along-track (m)")
        ax.set_title(f"Simulated image, GSD {gsd * 100:.0f} cm")
        if seen:
            ax.legend(loc="upper right", title="other objects", framealpha=0.85)
        place_grid(fig, [[ax]], top=title_band_in(), bottom=axis_band_in())
        save_figure(fig, path, dpi=100)


def to_grey8(arr: np.ndarray) -> np.ndarray:
    """Reflectance 0..1 -> 8-bit grey levels, pixel by pixel (NaN: 0), in float64 (in place on one copy)."""
    v = np.multiply(arr, 255.0, dtype=np.float64)
    np.nan_to_num(v, copy=False)
    np.round(v, out=v)
    np.clip(v, 0, 255, out=v)
    return v.astype(np.uint8)


def _png(arr: np.ndarray) -> tuple[bytes, int, int]:
    """Reflectance 0..1 -> 8-bit grey PNG bytes (block-averaged down to ``MAX_SIDE_PX``)."""
    k = max(1, math.ceil(max(arr.shape) / MAX_SIDE_PX))
    if k > 1:
        h, w = (arr.shape[0] // k) * k, (arr.shape[1] // k) * k
        arr = arr[:h, :w].reshape(h // k, k, w // k, k).mean(axis=(1, 3))
    return _png_grey8(to_grey8(arr))


def _png_grey8(u8: np.ndarray) -> tuple[bytes, int, int]:
    """8-bit grey levels -> PNG bytes, width, height."""
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(u8, mode="L").save(buf, format="PNG", compress_level=PNG_COMPRESS_LEVEL)
    return buf.getvalue(), u8.shape[1], u8.shape[0]


def _crop(image: np.ndarray, box_m, pixel_m: float, origin_m=(0.0, 0.0)) -> np.ndarray:
    x0, y0, x1, y1 = box_m
    ox, oy = origin_m
    r0, c0 = max(int(math.floor((y0 - oy) / pixel_m)), 0), max(int(math.floor((x0 - ox) / pixel_m)), 0)
    r1 = min(int(math.ceil((y1 - oy) / pixel_m)), image.shape[0])
    c1 = min(int(math.ceil((x1 - ox) / pixel_m)), image.shape[1])
    return image[r0:r1, c0:c1]


def _scene(ctx):
    sc = getattr(ctx, "scene", None)
    if sc is not None:
        return sc
    from satchain.scene import load_layout

    return load_layout(ctx.config.layout_source())


def _box(it: dict, extent: tuple[float, float]) -> tuple[float, float, float, float]:
    """The item's box, widened to at least MIN_EXTENT_M for small objects, clipped to the scene."""
    x0, y0, x1, y1 = it["bbox_m"]
    if it["kind"] not in GALLERY_KINDS:
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        hw, hh = max(x1 - x0, MIN_EXTENT_M) / 2, max(y1 - y0, MIN_EXTENT_M) / 2
        x0, x1, y0, y1 = cx - hw, cx + hw, cy - hh, cy + hh
    return max(x0, 0.0), max(y0, 0.0), min(x1, extent[0]), min(y1, extent[1])


def _chosen_items(truth: dict) -> list[dict]:
    items = [it for it in truth["items"] if it["kind"] in GALLERY_KINDS]
    for kind in OBJECT_KINDS:
        first = next((it for it in truth["items"] if it["kind"] == kind), None)
        if first is not None:
            items.append(first)
    return items


def thumbnail_boxes(truth: dict, extent: tuple[float, float]) -> list[tuple[dict, tuple]]:
    """``({"id", "kind"}, box in metres)`` of every shown item, its box clipped to the image's ``extent``
    (width, height in metres)."""
    return [({"id": it["id"], "kind": it["kind"]}, _box(it, extent)) for it in _chosen_items(truth)]


def image_extent(ctx) -> tuple[float, float]:
    """The simulated image's ground extent (width, height in metres)."""
    gsd = float(ctx.image_gsd_m)
    return (ctx.image.shape[1] * gsd, ctx.image.shape[0] * gsd)


def thumbnail_crops(ctx, boxes) -> list[tuple[np.ndarray, float, np.ndarray, float]]:
    """Per box (m): the focal-plane and detector crops with their pixel sizes (the detector in reflectance:
    :func:`_to_reflectance`), each of the box where that panel has it (:func:`panel_maps`)."""
    fp_pixel = float(ctx.config.scene.pixel_m) * float(ctx.simulator.D)
    gsd = float(ctx.image_gsd_m)
    fp, det = np.asarray(ctx.focal_plane, float), _to_reflectance(ctx)
    maps = panel_maps(ctx)
    return [(_crop(fp, mapped_box(maps["focal plane"], box), fp_pixel), fp_pixel,
             _crop(det, mapped_box(maps["detector"], box), gsd), gsd) for box in boxes]  # fmt: skip


def panel_maps(ctx) -> dict:
    """Each thumbnail panel's map from truth metres to its own coordinates (``affine.Affine``; None: the truth's
    metres): ``"detector"``, the image's pixels times the GSD through the run's image map (``ctx.image_affine``:
    a pushbroom image's shear, along-track scale or yaw); ``"focal plane"``, under a yaw the ground turned about
    the yaw's pivot as the engine forms it; ``"ground truth"``: None."""
    from affine import Affine

    geo = getattr(ctx, "image_affine", None)
    out = {"ground truth": None, "focal plane": None, "detector": None}
    if geo is None:
        return out
    gsd = float(ctx.image_gsd_m)
    out["detector"] = Affine.scale(gsd) @ Affine.translation(0.5, 0.5) @ geo
    sim = getattr(ctx, "simulator", None)
    yaw_deg: float = getattr(sim, "yaw_deg", 0.0)
    if sim is not None and yaw_deg:
        from satchain.engine.yaw import grid_origin_m
        from satchain.measure.auto import truth_origin_m
        from satchain.tf.pushbroom import yaw_pivot_m

        a = sim.input_pixel_m
        ox, oy = truth_origin_m(ctx.truth)
        px, py = yaw_pivot_m(sim.output_shape, (sim.xs.k * a, sim.ys.k * a), grid_origin_m(sim))
        shift = Affine.translation(ox, oy)  # the truth's origin: the engine's grid starts there
        out["focal plane"] = shift @ Affine.rotation(sim.yaw_deg, pivot=(px, py)) @ ~shift
    return out


def mapped_box(panel, box) -> tuple[float, float, float, float]:
    """The extent, in a panel's coordinates (:func:`panel_maps`), of a box in truth metres."""
    if panel is None:
        return tuple(box)
    pts = [panel @ p for p in _corners_m(box)]
    xs, ys = [p[0] for p in pts], [p[1] for p in pts]
    return min(xs), min(ys), max(xs), max(ys)


def thumbnail_calls(ctx) -> list[tuple]:
    """The arguments of :func:`item_thumbnail` for every shown item (plain data: the scene, crops, pixel sizes),
    so that the thumbnails can be made in helper processes (:class:`satchain.report._jobs.FigureJobs`)."""
    p = float(ctx.config.scene.pixel_m)
    scene = _scene(ctx)
    shown = thumbnail_boxes(ctx.truth, image_extent(ctx))
    crops = thumbnail_crops(ctx, [box for _, box in shown])
    return [(scene, it, box, p, *c) for (it, box), c in zip(shown, crops, strict=True)]


def panel_window(box, p: float) -> tuple[int, int, int, int]:
    """The pixels (row0, col0, height, width) at ``p`` of a thumbnail's ground-truth panel over ``box`` (m)."""
    x0, y0, x1, y1 = box
    return int(y0 / p), int(x0 / p), max(int(math.ceil((y1 - y0) / p)), 1), max(int(math.ceil((x1 - x0) / p)), 1)


def truth_panel(scene, box, p: float) -> dict | None:
    """A thumbnail's ground-truth panel: ``scene`` rendered over ``box`` (m) at ``p`` (its long part, so a
    run has a helper process make it while it measures)."""
    return _panel("ground truth", np.asarray(scene.render(panel_window(box, p), pixel_m=p), float), p)


def grey8_truth_panel(u8: np.ndarray, p: float) -> dict:
    """:func:`truth_panel` from its pixels already as grey levels (:func:`to_grey8` of the render; at most
    ``MAX_SIDE_PX`` on a side): a run keeps them as its simulation renders the scene
    (:class:`satchain.report.truth_crops.TruthCrops`), so that only the PNG is made here."""
    png, wpx, hpx = _png_grey8(u8)
    return {"title": "ground truth", "png": png, "width": wpx, "height": hpx, "pixel_m": p}


def _panel(title: str, arr: np.ndarray, pix: float) -> dict | None:
    if arr.size == 0:
        return None
    png, wpx, hpx = _png(arr)
    shown_pix = pix * max(1, math.ceil(max(arr.shape) / MAX_SIDE_PX))
    return {"title": title, "png": png, "width": wpx, "height": hpx, "pixel_m": shown_pix}


def assemble_thumbnail(it: dict, box, truth: dict | None, fp: np.ndarray, fp_pixel: float, det: np.ndarray,
                       gsd: float) -> dict:  # fmt: skip
    """One item's thumbnail from its ground-truth panel (:func:`truth_panel`) and its two crops."""
    panels = [truth, _panel("focal plane", fp, fp_pixel), _panel("detector", det, gsd)]
    return {"id": it["id"], "kind": it["kind"], "box_m": box, "panels": [q for q in panels if q is not None]}


def item_thumbnail(scene, it: dict, box, p: float, fp: np.ndarray, fp_pixel: float, det: np.ndarray,
                   gsd: float) -> dict:  # fmt: skip
    """One item's three panels (ground truth rendered here, focal plane and detector crops): see
    :func:`target_thumbnails`."""
    return assemble_thumbnail(it, box, truth_panel(scene, box, p), fp, fp_pixel, det, gsd)


def target_thumbnails(ctx) -> list[dict]:
    """Per shown item: id, kind, box (m) and three panels (ground truth, focal plane, detector), each a dict
    with ``title``, ``png`` (bytes), ``width``/``height`` (px) and ``pixel_m``."""
    return [item_thumbnail(*args) for args in thumbnail_calls(ctx)]
