"""The colour filter array section of a run (issue 32 point 4; see :mod:`satchain.focal`).

A system with ``[detector] cfa`` ("RGGB", ...) is a Bayer colour camera. The run's main image measures the base
array (the monochrome-equivalent system); this section forms what the colour camera itself delivers:

1. the raw mosaic of the run's scene (:func:`satchain.engine.cfa_sim.simulate_cfa`: each photosite integrates its
   own colour; noise, seed and units of ``[simulation]``; radiance, which has no single band on a colour array,
   is formed in electrons) and its images demosaiced by bilinear interpolation, Malvar (2004) and Menon (2007);
2. for every slanted edge of the truth, each raw colour plane measured on its own grid
   (:func:`satchain.prediction.cfa.measure_cfa`: red and blue every other row and column, green the quincunx
   turned onto its sqrt(2) px grid) against the design's prediction (:func:`satchain.prediction.cfa.predict_cfa`:
   the colour's system OTF along the measured edge normal): check rows ``cfa_plane_mtf`` at each plane's grid
   Nyquist, and for green also at its quincunx's own Nyquist along the normal;
3. at the neutral edge nearest 5 deg (both sides grey: no material spectrum), each demosaicing method's luminance
   MTF50 and its false colour (the chroma across the edge, a fraction of the step), side by side with the three
   colour planes themselves (a perfect interpolation) and the predicted luminance MTF50: reported, not checked.

``data`` (results.json ``cfa``) holds everything the report draws: the budget's per-plane block, each edge's
figures and MTF curves measured and predicted, the methods table and a crop of the reference edge demosaiced by
each method. ``write_files`` writes ``images/cfa/raw.tif`` (the mosaic; its pattern, phase and units in the
metadata) and ``images/cfa/rgb_<method>.png``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from satchain.config.sections_cfa import CFA_COLOURS, colour_system
from satchain.errors import ConfigError, InputError
from satchain.focal._rows import check_row, na_row

if TYPE_CHECKING:
    from satchain.comparison import CheckRow
    from satchain.config.run import RunConfig
    from satchain.engine.cfa_sim import CFAImages
    from satchain.results import BudgetResult, FocalSection, SceneResult
    from satchain.scene.truth import EdgeTruth

__all__ = ["METHODS", "section"]

#: The demosaicing methods the run compares, with their names in the report.
METHODS = {"bilinear": "bilinear", "malvar2004": "Malvar 2004", "menon2007": "Menon 2007"}
_PLANE_PX = {"red": 2.0, "green": math.sqrt(2.0), "blue": 2.0}  # a plane pixel, in photosites of the array
_MIN_SIDE_PX = 48  # the edge's region: a red or blue plane of >= 24 px a side
_CROP_PX = 24  # the report's crop of the reference edge, px a side
_CURVE_F = np.round(np.linspace(0.0, 1.0, 101), 6)  # cy/px of the array: the report's MTF curves
_REFERENCE_ANGLE_DEG = 5.0  # the neutral 5-degree edge


def section(config: RunConfig, budget: BudgetResult, scene: SceneResult, progress) -> FocalSection | None:
    """The colour filter array's section (None for a monochrome array)."""
    system = budget.system
    if system.detector.cfa is None:
        return None
    from satchain.engine.cfa_sim import CFA_UNITS, simulate_cfa
    from satchain.engine.simulate import SimParams
    from satchain.results import FocalSection

    c = config.simulation
    built = config.load_as_built_system(system)
    camera = system if built is None else built
    units = c.units if c.units in CFA_UNITS else "electrons"
    edges = [e for e in scene.truth.edges if e.in_window]
    total = len(edges) + 2
    progress("focal", 0, total)
    params = SimParams(far_margin_px=c.far_margin_px, border=c.border)
    images = simulate_cfa(scene.scene, camera, pixel_m=scene.pixel_m, seed=c.seed, noise=c.noise, units=units,
                          methods=tuple(METHODS), params=params)  # fmt: skip
    progress("focal", 1, total)
    to_px = _to_pixels(camera, scene.truth_dict, images.raw.shape)
    neutral = _neutral(scene.scene, edges)
    measured, rows = [], []
    for k, e in enumerate(edges):
        m, edge_rows = _edge(images, e, to_px(e), system, neutral[e.id], config.tolerances.edge_mtf_at_nyquist)
        measured.append(m)
        rows.extend(edge_rows)
        progress("focal", k + 2, total)
    data = _data(system, images, measured, units, c)
    progress("focal", total, total)
    title = f"Colour filter array (Bayer {system.detector.cfa})"
    return FocalSection("cfa", title, tuple(rows), {"title": title, **data}, _writer(images, camera, data))


# --------------------------------------------------------------------------------------------- where the edges are
def _to_pixels(camera, truth: Mapping[str, Any], shape: tuple[int, int]) -> Callable[[EdgeTruth], tuple]:
    """An edge's square -> its region ``(x0, y0, x1, y1)`` in the mosaic: centred on the square's image, 80 % of
    its side (as the run's edges, 10 % in from each side), through the pushbroom image geometry when the system
    moves the image (Earth rotation, a line-rate error)."""
    from affine import Affine

    from satchain.measure.auto import truth_origin_m
    from satchain.tf.pushbroom import PushbroomTerms

    ox, oy = truth_origin_m(dict(truth))
    terms = PushbroomTerms(camera)
    if terms.active:
        fwd = terms.image_affine((shape[0], shape[1])) @ Affine.translation(-ox, -oy)
    else:
        fwd = Affine(1 / camera.gsd_act_m, 0, -ox / camera.gsd_act_m - 0.5, 0, 1 / camera.gsd_alt_m,
                     -oy / camera.gsd_alt_m - 0.5)  # fmt: skip

    def roi(e: EdgeTruth) -> tuple[int, int, int, int]:
        xmin, ymin, xmax, ymax = e.bbox_m
        col, row = fwd * ((xmin + xmax) / 2, (ymin + ymax) / 2)
        half = int(0.4 * min(xmax - xmin, ymax - ymin) / max(camera.gsd_act_m, camera.gsd_alt_m))
        cx, cy = int(round(col)), int(round(row))
        return cx - half, cy - half, cx + half + 1, cy + half + 1

    return roi


def _neutral(layout, edges) -> dict[str, bool]:
    """An edge is neutral when no material spectrum fills either side (both sides grey: equal spectra up to
    their level)."""
    coloured = {s.item_id for s in getattr(layout, "materials", ())}
    return {e.id: e.id not in coloured for e in edges}


# -------------------------------------------------------------------------------------------------- one edge
def _edge(images: CFAImages, e: EdgeTruth, roi: tuple[int, int, int, int], system, neutral: bool,
          tol: float) -> tuple[dict[str, Any], list[CheckRow]]:  # fmt: skip
    """One edge measured (its record for ``data`` and its check rows; n/a rows with the reason when it cannot be
    measured)."""
    from satchain.prediction.cfa import measure_cfa, predict_cfa

    rec: dict[str, Any] = {"id": e.id, "angle_deg": e.angle_deg, "measures": e.measures, "neutral": neutral,
                           "roi_px": list(roi), "reason": None}  # fmt: skip
    h, w = images.raw.shape
    side = min(roi[2] - roi[0], roi[3] - roi[1])
    why = None
    if roi[0] < 0 or roi[1] < 0 or roi[2] > w or roi[3] > h:
        why = f"its region {list(roi)} leaves the {w} x {h} px mosaic"
    elif side < _MIN_SIDE_PX:
        why = (f"too small at the system's GSD: its region is {side} px a side; the colour planes need >= "
               f"{_MIN_SIDE_PX} px ({_MIN_SIDE_PX // 2} px of a red or blue plane)")  # fmt: skip
    if why is None:
        try:
            m = measure_cfa(images, roi)
        except (InputError, ConfigError, ValueError) as exc:
            why = f"not measurable on the colour planes: {exc}"
    if why is not None:
        rec["reason"] = why
        return rec, _na_rows(e.id, why, tol)
    pred = predict_cfa(system, normal_deg=m.normal_deg)
    rec["normal_deg"] = m.normal_deg
    rec["planes"], rows = _planes(e.id, m, pred, tol)
    rec["curves"] = _curves(system, m)
    if neutral:
        rec["methods"] = _methods(m, pred)
        rec["crop"] = _crop(images, m, roi)
    return rec, rows


def _na_rows(edge_id: str, why: str, tol: float) -> list[CheckRow]:
    return [na_row(f"cfa {edge_id} {c} plane MTF@its Nyquist", "cfa_plane_mtf", f"{edge_id}:{c}", tolerance=tol,
                   tolerance_text=f"±{tol}", reason=why) for c in CFA_COLOURS]  # fmt: skip


def _sigma_at(edge, f_cy_per_px: float, plane_px: float) -> float | None:
    if edge.mtf_sigma is None:
        return None
    s = float(np.interp(f_cy_per_px * plane_px, edge.f_cy_per_px, np.asarray(edge.mtf_sigma, dtype=float)))
    return s if math.isfinite(s) else None


def _planes(edge_id: str, m, pred: Mapping[str, Any], tol: float) -> tuple[dict[str, Any], list[CheckRow]]:
    """Each plane's figures and its check rows: at its grid's Nyquist, and green also at its quincunx's Nyquist
    along the edge normal."""
    from satchain.prediction.cfa_budget import alias_along_cy_per_px

    out, rows = {}, []
    for colour in CFA_COLOURS:
        p, px = m.planes[colour], _PLANE_PX[colour]
        s_grid, s_zone = _sigma_at(p.edge, p.f_grid_cy_per_px, px), _sigma_at(p.edge, p.f_zone_cy_per_px, px)
        out[colour] = {
            "sampling": p.sampling, "f_grid_cy_per_px": p.f_grid_cy_per_px,
            "measured_at_grid_nyquist": p.measured_at_grid_nyquist, "predicted_at_grid_nyquist": pred[colour]["grid"],
            "sigma_at_grid_nyquist": s_grid, "f_zone_cy_per_px": p.f_zone_cy_per_px,
            "measured_at_zone_nyquist": p.measured_at_zone_nyquist, "predicted_at_zone_nyquist": pred[colour]["zone"],
            "sigma_at_zone_nyquist": s_zone, "measured_mtf50_cy_per_px": p.measured_mtf50_cy_per_px,
            "predicted_mtf50_cy_per_px": pred[colour]["mtf50"],
            "alias_cy_per_px": alias_along_cy_per_px(m.pattern, colour, m.normal_deg),
        }  # fmt: skip
        checks = [("grid", p.f_grid_cy_per_px, "its grid's Nyquist", colour)]
        if colour == "green":
            checks.append(("zone", p.f_zone_cy_per_px, "the quincunx's Nyquist", "green_quincunx"))
        for key, f, where, ident in checks:
            rows.append(check_row(
                f"cfa {edge_id} {colour} plane MTF@{where} ({f:.3f} cy/px)", "cfa_plane_mtf", f"{edge_id}:{ident}",
                out[colour][f"measured_at_{key}_nyquist"], out[colour][f"predicted_at_{key}_nyquist"],
                tolerance=tol, tolerance_text=f"±{tol}", sigma=out[colour][f"sigma_at_{key}_nyquist"],
                sigma_null_means="the plane's edge gave no MTF sigma",
                note=f"the raw {colour} photosites on their own grid ({p.sampling}) against the {colour} "
                     "response's system MTF along the edge normal"))  # fmt: skip
    return out, rows


def _curves(system, m) -> dict[str, Any]:
    """Each plane's MTF along the edge normal, measured (on its own grid, to where its ESF bins reach) and
    predicted, at :data:`_CURVE_F`."""
    from satchain.tf.budget import SystemOTF
    from satchain.tf.cfa import plane_mtf

    det = system.detector
    out: dict[str, Any] = {"f_cy_per_px": _CURVE_F.tolist()}
    for colour in CFA_COLOURS:
        e, px = m.planes[colour].edge, _PLANE_PX[colour]
        f_top = float(np.max(e.f_cy_per_px)) / px
        meas = np.interp(_CURVE_F * px, e.f_cy_per_px, e.mtf)
        otf = SystemOTF(colour_system(system, colour))
        pred = plane_mtf(otf, _CURVE_F, pitch_x_m=det.pitch_x_m, pitch_y_m=det.pitch_y_m, direction_deg=m.normal_deg)
        measured = [round(float(v), 5) if f <= f_top else None for f, v in zip(_CURVE_F, meas, strict=True)]
        out[colour] = {"measured": measured, "predicted": [round(float(v), 5) for v in pred]}
    return out


def _methods(m, pred: Mapping[str, Any]) -> list[dict[str, Any]]:
    """The demosaicing methods side by side at this edge (and ``true``: the colour planes themselves)."""
    label = {"true": "the colour planes themselves, noise-free (a perfect interpolation)", **METHODS}
    return [
        {"method": k, "label": label[k], "luminance_mtf50_cy_per_px": v.mtf50_cy_per_px,
         "luminance_mtf50_predicted": pred["luminance_mtf50"], "false_colour_peak": v.false_colour_peak,
         "false_colour_rms": v.false_colour_rms, "flat_false_colour_peak": v.flat_peak}
        for k, v in m.methods.items()
    ]  # fmt: skip


def _crop(images: CFAImages, m, roi) -> dict[str, Any]:
    """A :data:`_CROP_PX` px square of each method's RGB image (reflectance, 4 decimals) centred on the edge."""
    x_pl, y_pl = m.planes["red"].edge.edge_point_xy  # on the red plane of the region
    r0, c0 = (int(v) for v in np.argwhere(images.masks["red"][roi[1] : roi[1] + 2, roi[0] : roi[0] + 2])[0])
    cx, cy = roi[0] + c0 + 2 * x_pl, roi[1] + r0 + 2 * y_pl
    x0 = int(np.clip(round(cx) - _CROP_PX // 2, roi[0], roi[2] - _CROP_PX))
    y0 = int(np.clip(round(cy) - _CROP_PX // 2, roi[1], roi[3] - _CROP_PX))
    rgbs = {"true": images.true_rgb, **images.rgb}
    crop = {k: np.round(np.asarray(v)[y0 : y0 + _CROP_PX, x0 : x0 + _CROP_PX], 4).tolist() for k, v in rgbs.items()}
    return {"box_px": [x0, y0, x0 + _CROP_PX, y0 + _CROP_PX], "rgb": crop}


# ------------------------------------------------------------------------------------------------ the section's data
def _reference(measured: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The measured neutral edge nearest :data:`_REFERENCE_ANGLE_DEG`."""
    ok = [r for r in measured if r.get("methods")]
    return min(ok, key=lambda r: abs(abs(r["angle_deg"]) - _REFERENCE_ANGLE_DEG)) if ok else None


def _data(system, images: CFAImages, measured: list[dict[str, Any]], units: str, sim) -> dict[str, Any]:
    from satchain.prediction.cfa_budget import cfa_budget

    b = cfa_budget(system)
    ref = _reference(measured)
    why = None
    if ref is None:
        why = ("no neutral slanted edge (both sides grey) was measured" if measured else
               "the scene has no slanted edge")  # fmt: skip
    top = float(np.percentile(images.true_rgb, 99.5)) or 1.0
    return {
        "pattern": b["pattern"],
        "responses": b["responses"],
        "units": units,
        "units_note": None if units == sim.units else f"[simulation] units = {sim.units!r} has no single band on a "
                      f"colour array: the mosaic is in {units}",
        "noise": bool(sim.noise),
        "seed": int(sim.seed),
        "shape_px": list(images.raw.shape),
        "planes_predicted": b["planes"],
        "edges": measured,
        "methods_edge": None if ref is None else ref["id"],
        "methods_reason": why,
        "methods": [] if ref is None else ref["methods"],
        "crop": None if ref is None else {"edge": ref["id"], **ref["crop"], "display_max": top},
        "files": ["images/cfa/raw.tif", *(f"images/cfa/rgb_{k}.png" for k in METHODS)],
    }  # fmt: skip


def _writer(images: CFAImages, camera, data: Mapping[str, Any]) -> Callable[[Path], list[str]]:
    def write(out_dir: Path) -> list[str]:
        from PIL import Image, PngImagePlugin

        from satchain.io.images import PNG_COMPRESS_LEVEL, atomic_path, write_simulated

        d = Path(out_dir) / "images" / "cfa"
        d.mkdir(parents=True, exist_ok=True)
        meta = {"cfa_pattern": images.pattern, "cfa_origin_rc": list(images.origin), "noise": images.noise,
                "system": camera.name, "gain": dict(images.gain), "offset": dict(images.offset)}  # fmt: skip
        write_simulated(d / "raw.tif", images.raw, units=images.units, bit_depth=camera.detector.bit_depth,
                        pixel_m=camera.gsd_act_m, metadata=meta, preview=False)  # fmt: skip
        top = float(np.percentile(images.true_rgb, 99.5)) or 1.0
        for method, rgb in images.rgb.items():
            img = np.round(np.clip(np.asarray(rgb) / top, 0.0, 1.0) * 255).astype(np.uint8)
            info = PngImagePlugin.PngInfo()
            stretch = f"reflectance 0..{top:.6g}, all channels alike"
            info.add_text(
                "satchain", json.dumps({"demosaicing": method, "cfa_pattern": images.pattern, "stretch": stretch})
            )
            with atomic_path(d / f"rgb_{method}.png") as tmp:
                Image.fromarray(img, mode="RGB").save(tmp, format="PNG", pnginfo=info,
                                                      compress_level=PNG_COMPRESS_LEVEL)  # fmt: skip
        return list(data["files"])

    return write
