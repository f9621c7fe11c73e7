"""The bands of a ``[[bands]]`` system (PAN + MS) in ``satchain run`` (issue 32, points 3 and 6): every band formed
from the run's scene, and per band its edge MTF at its own Nyquist, its SNR and its offset from the PAN band, each
against its budget, with sigma and z.

- **Formed** by :func:`satchain.engine.bands.simulate_bands` (the camera as built when ``[as_built]`` gives one
  with bands; the predictions are the design's, as the main run's), with the run's units, noise, seed, far margin
  and border; written as ``images/bands/`` (``pan.tif``, ``ms.tif`` with band names and centre wavelengths,
  ``rgb.png``, ``false_colour.png``: :func:`satchain.engine.bands.write_band_rasters`).
- **Edge MTF at Nyquist** (kind ``band_edge_mtf_at_nyquist``): every slanted edge of the band's truth (the scene
  each band sees, :func:`satchain.scene.spectral.layout_for_band`) measured on the band's own image and grid
  (:func:`satchain.measure.auto.measure_auto` at the band's GSD) and compared at 0.5 cy/px of the band along the
  edge normal with the band's predicted MTF (:func:`satchain.prediction.core.predict` of the band's system, at its
  own time: the pushbroom terms of its rows), by the main run's edge check
  (:func:`satchain.comparison.compare`: noise floor and rows' displacements included). An edge the band's image
  cannot support (too small at its GSD, clipped) is an n/a row with the measurement's reason.
- **SNR** (kind ``band_snr``, relative): the signal SNR of the scene's clear background measured on the band image
  (:mod:`satchain.focal.bands_snr`: mean signal over the noise about a fitted plane, with its 1-sigma)
  against the band's budget at the background's reflectance in the band (its ``snr`` for a grey 0.2 background);
  n/a on a noise-free run. (The GIQE contrast SNR of :func:`satchain.measure.snr.measure_snr` reads 1-5 % below
  the budget's contrast SNR on the MS bands and ~3 % on PAN, with a 1-2 % sigma on a small scene: too close to the
  5 % tolerance to decide it.)
- **Registration** (kind ``band_registration``, per axis, band pixels): each band's offset from the PAN band
  (:mod:`satchain.focal.bands_registration`), and in row strips when the line of sight moves in time.

A system without bands (or whose bands have no spectral response) has no bands section: the run is unchanged.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

import numpy as np

from satchain.focal._rows import check_row, na_row
from satchain.focal.bands_registration import (
    AXES,
    MAX_AFFINE_DEPARTURE,
    affine_departure,
    measure_band_offset,
    predicted_offset_px,
    time_varying,
    unpredicted_motion,
)

if TYPE_CHECKING:
    from satchain.config.run import RunConfig
    from satchain.config.system import ImagingSystem
    from satchain.engine.bands import BandImage, BandImages
    from satchain.results import BudgetResult, FocalSection, SceneResult

__all__ = ["CURVE_POINTS", "KIND_EDGE", "KIND_REGISTRATION", "KIND_SNR", "TITLE", "section"]

TITLE = "Bands: PAN and multispectral"
KIND_EDGE, KIND_SNR, KIND_REGISTRATION = "band_edge_mtf_at_nyquist", "band_snr", "band_registration"
#: Points of each band's predicted MTF curve (0 to 1 cy/px of the band: twice its Nyquist).
CURVE_POINTS = 51
_NOISE_FREE = "the band image is noise-free ([simulation] noise = false): it has no noise to measure an SNR from"


def section(config: RunConfig, budget: BudgetResult, scene: SceneResult, progress) -> FocalSection | None:
    """The bands section of a run (see the module docstring); None for a system without spectral bands."""
    from satchain.engine.bands import simulate_bands
    from satchain.engine.simulate import SimParams
    from satchain.prediction.budget import band_budgets
    from satchain.results import FocalSection

    design = budget.system
    if not design.bands or not any(b.spectral_response is not None for b in design.bands):
        return None
    built = config.load_as_built_system(design)
    formed_by = built if built is not None and len(built.bands) == len(design.bands) else design
    c = config.simulation
    total = len(design.bands) + 1
    progress("focal", 0, total)
    images = simulate_bands(scene.scene, formed_by, pixel_m=scene.pixel_m, units=c.units, noise=c.noise,
                            seed=c.seed, params=SimParams(far_margin_px=c.far_margin_px, border=c.border))  # fmt: skip
    progress("focal", 1, total)
    entries = list(budget.budget.get("bands") or band_budgets(design))
    ref = design.band_index(entries[0]["registration"]["reference_band"])
    rows: list = []
    bands: list[dict[str, Any]] = []
    for k, b in enumerate(images):
        r, d = _band(config, design, images, b, entries, ref, scene)
        rows += r
        bands.append(d)
        progress("focal", k + 2, total)
    data = {
        "title": TITLE,
        "reference_band": design.band_names[ref],
        "noise": bool(c.noise),
        "units": c.units,
        "system_formed": "as built" if formed_by is not design else "design",
        "predictions": "the design's budget per band (satchain.prediction.budget.band_budgets); edges through "
        "satchain.prediction.core.predict of each band's system at its own time",
        "snr_definition": "signal SNR of the clear background: its mean signal (electrons, dark level and offset "
        "removed) over its noise (the pixels' scatter about a fitted plane), against the band's radiometric budget at "
        "the background's reflectance in the band",
        "registration_convention": "the band's content relative to the reference band's, (ALT, ACT) band px: "
        "image(y, x) = reference(y - dy, x - dx)",
        "bands": bands,
    }
    return FocalSection("bands", TITLE, tuple(rows), data, write_files=lambda out: _write(images, out))


def _write(images: BandImages, out_dir: Path) -> list[str]:
    from satchain.engine.bands import write_band_rasters

    folder = Path(out_dir) / "images" / "bands"
    folder.mkdir(parents=True, exist_ok=True)
    return [p.relative_to(out_dir).as_posix() for p in write_band_rasters(images, folder).values()]


def _band(config: RunConfig, design: ImagingSystem, images: BandImages, b: BandImage, entries: list, ref: int,
          scene: SceneResult) -> tuple[list, dict[str, Any]]:  # fmt: skip
    """Band ``b``'s check rows and its results.json entry."""
    from satchain.engine.bands import at_own_time, band_delay_s, band_response
    from satchain.scene.spectral import layout_for_band

    i, entry = b.index, entries[b.index]
    layout = layout_for_band(scene.scene, *band_response(design, i))
    truth = scene.truth_dict if layout is scene.scene else layout.truth(pixel_m=scene.pixel_m)
    s_pred = at_own_time(design.for_band(i), band_delay_s(design, i))
    content = _content_offset_px(design, i, entry)
    geo, affine, origin = _geometry(b, truth, content, images.seed)
    edge_rows, edges = _edges(config, s_pred, b, truth, geo, affine, origin)
    snr_row, snr = _snr(config, s_pred, b, truth, entry, affine, origin)
    out: dict[str, Any] = {
        "index": i,
        "name": b.name,
        "center_wavelength_m": b.center_wavelength_m,
        "gsd_m": b.gsd_act_m,
        "pitch_m": b.system.detector.pitch_x_m,
        "tdi_stages": b.system.detector.tdi_stages,
        "shape": list(b.image.shape),
        "nyquist_cy_per_px": 0.5,
        "nyquist_cy_per_mm": dict(entry["nyquist_cy_per_mm"]),
        "mtf_at_nyquist_predicted": dict(entry["mtf_at_nyquist"]),
        "edges": edges,
        "snr": snr,
        "mtf_curve": _curve(s_pred),
        "registration": None,
    }
    rows = [*edge_rows, snr_row]
    if i != ref:
        reg_rows, out["registration"] = _registration(config, design, images, b, entries, ref, scene)
        rows += reg_rows
    return rows, out


def _content_offset_px(design: ImagingSystem, i: int, entry: dict) -> tuple[float, float]:
    """Where band ``i``'s content lies from its nominal grid (ALT, ACT band px): its own injected offset and what
    the Earth's rotation and the line-rate error add over its delay (the budget's); where the measurements look for
    the targets."""
    own = design.bands[i].registration_offset_px
    zero = {"alt_px": 0.0, "act_px": 0.0}
    earth = entry["registration"].get("earth_rotation") or zero
    rate = entry["registration"].get("line_rate") or zero
    return (float(own[0]) + float(earth["alt_px"]) + float(rate["alt_px"]),
            float(own[1]) + float(earth["act_px"]) + float(rate["act_px"]))  # fmt: skip


def _geometry(b: BandImage, truth: dict, content: tuple[float, float], seed: int):
    """``(ImageGeometry or None, image_affine or None, origin_m or None)`` of band ``b``'s image: its pushbroom
    geometry (its own time path) when its line of sight moves, the truth -> pixel map the measurements use."""
    from affine import Affine

    from satchain.engine.timepath import time_path
    from satchain.measure.auto import truth_origin_m
    from satchain.prediction.image_geometry import run_geometry
    from satchain.tf.pushbroom import PushbroomTerms

    ox, oy = truth_origin_m(truth)
    terms = PushbroomTerms(b.system)
    if not terms.active:
        g = b.gsd_act_m
        return None, None, (ox - content[1] * g, oy - content[0] * b.gsd_alt_m)
    tp = time_path(b.system, b.image.shape[0], seed=seed)
    geo = run_geometry(b.system, truth, SimpleNamespace(time_path=tp), b.image.shape)
    shape = (int(b.image.shape[0]), int(b.image.shape[1]))
    affine = Affine.translation(content[1], content[0]) @ terms.image_affine(shape) @ Affine.translation(-ox, -oy)
    return geo, affine, None


def _edges(config: RunConfig, s_pred: ImagingSystem, b: BandImage, truth: dict, geo, affine,
           origin) -> tuple[list, list[dict[str, Any]]]:  # fmt: skip
    """Every slanted edge of the band: its check rows (the main run's edge check, relabelled) and entries."""
    from satchain.comparison import compare
    from satchain.engine.sensor import sensor_from_system
    from satchain.measure._keys import RESULT_KEY
    from satchain.measure.auto import measure_auto
    from satchain.prediction.core import predict
    from satchain.scene.targets import SlantedEdge
    from satchain.tf.budget import SystemOTF

    edges_only = dict(truth, items=[it for it in truth["items"] if it.get("kind") == SlantedEdge.kind])
    if not edges_only["items"]:
        return [], []
    sensor = sensor_from_system(b.system)
    full_scale = sensor.full_scale(config.simulation.units, noise=config.simulation.noise)
    where = {"image_affine": affine} if affine is not None else {"origin_m": origin}
    auto = measure_auto(b.image, edges_only, pixel_m=b.gsd_act_m, full_scale=full_scale, **where)
    grid = None if geo is None else (geo.steps_m, (~geo.to_image) @ (-0.5, -0.5))
    pred = predict(s_pred, edges_only, otf=SystemOTF(s_pred), sensor=sensor, image_grid_m=grid)
    if geo is not None:
        pred = dataclasses.replace(pred, geometry=geo)
    comp = compare(auto, pred, config.tolerances)
    measured = {e["id"]: e for e in auto.to_dict().get(RESULT_KEY[SlantedEdge.kind], [])}
    rows, out = [], []
    for row in comp.rows:
        if row.kind != "edge_mtf_at_nyquist":
            continue
        e = measured.get(str(row.id), {})
        direction = str(e.get("direction") or _truth_direction(edges_only, row.id))
        rows.append(dataclasses.replace(row, kind=KIND_EDGE, id=f"{b.name}/{row.id}",
                                        figure=f"{b.name} edge {row.id} MTF@Nyquist ({direction})"))  # fmt: skip
        f = np.asarray(e.get("f_cy_per_px") or [], dtype=float)
        mtf = np.asarray(e.get("mtf") or [], dtype=float)
        keep = np.flatnonzero(f <= 1.0)[:: max(1, int(np.ceil(np.count_nonzero(f <= 1.0) / 50)))]
        out.append({
            "id": row.id, "direction": direction, "measured": row.measured, "predicted": row.predicted,
            "error": row.error, "sigma": row.sigma, "pass": row.passed, "reason": row.reason,
            "f_cy_per_px": f[keep].tolist(), "mtf_measured": mtf[keep].tolist(),
        })  # fmt: skip
    return rows, out


def _truth_direction(truth: dict, id_: Any) -> str:
    it: dict[str, Any] = next((x for x in truth["items"] if x.get("id") == id_), {})
    return str(it.get("measures", "?")).upper()


def _snr(config: RunConfig, s_pred: ImagingSystem, b: BandImage, truth: dict, entry: dict, affine,
         origin) -> tuple[Any, dict[str, Any]]:  # fmt: skip
    """The band's signal SNR on the scene's clear background (:mod:`satchain.focal.bands_snr`) against its budget at
    the background's reflectance in the band (relative)."""
    from satchain.engine.sensor import sensor_from_system
    from satchain.focal.bands_snr import measure_background_snr, predicted_background_snr

    tol = config.tolerances.band_snr_rel
    rho = float(truth.get("background", s_pred.illumination.reflectance))
    label, pred = f"{b.name} SNR (background, reflectance {rho:.3g})", predicted_background_snr(s_pred, entry, rho)
    text = f"±{tol:.0%}"
    if not config.simulation.noise:
        row = na_row(label, KIND_SNR, b.name, tolerance=tol, tolerance_text=text, reason=_NOISE_FREE, predicted=pred)
        return row, {"measured": None, "predicted": pred, "sigma": None, "reason": _NOISE_FREE,
                     "background_reflectance": rho}  # fmt: skip
    if affine is not None:
        to_pixel = lambda x, y: tuple(v + 0.5 for v in affine @ (x, y))  # noqa: E731  (centres at integers)
    else:
        to_pixel = lambda x, y: ((x - origin[0]) / b.gsd_act_m, (y - origin[1]) / b.gsd_alt_m)  # noqa: E731
    r = measure_background_snr(b.image, truth, to_pixel=to_pixel, sensor=sensor_from_system(b.system),
                               units=config.simulation.units)  # fmt: skip
    sig = None if r["sigma"] is None else float(r["sigma"]) / pred
    row = check_row(label, KIND_SNR, b.name, r["snr"], pred, tolerance=tol, tolerance_text=text, sigma=sig,
                    relative=True, reason=r["reason"],
                    note="signal SNR of the clear background (mean signal / noise about a plane fitted to it) "
                    "against the band's radiometric budget at the background's reflectance")  # fmt: skip
    return row, {"measured": r["snr"], "predicted": pred, "sigma": r["sigma"], "reason": r["reason"],
                 "background_reflectance": rho, "n_pixels": r["n_pixels"]}  # fmt: skip


def _curve(s: ImagingSystem) -> dict[str, Any]:
    """The band's predicted MTF along ACT and ALT, 0 to 1 cy/px of the band (:data:`CURVE_POINTS` points), with
    the frequencies in cy/mm on the focal plane."""
    from satchain.prediction.budget import DirectionalMTF
    from satchain.tf.budget import SystemOTF

    otf = SystemOTF(s)
    f_px = np.linspace(0.0, 1.0, CURVE_POINTS)
    out: dict[str, Any] = {"f_cy_per_px": f_px.tolist()}
    for d, pitch in (("act", s.detector.pitch_x_m), ("alt", s.detector.pitch_y_m)):
        f_mm = f_px / (pitch * 1e3)
        out[f"f_cy_per_mm_{d}"] = f_mm.tolist()
        out[d] = DirectionalMTF(otf, d)(f_mm).tolist()
    return out


def _registration(config: RunConfig, design: ImagingSystem, images: BandImages, b: BandImage, entries: list,
                  ref: int, scene: SceneResult) -> tuple[list, dict[str, Any]]:  # fmt: skip
    """Band ``b``'s offset from the reference band: one row per axis, and its entry (with strips)."""
    tol = config.tolerances.registration_px
    text = f"±{tol:g} px"
    r = images[ref]
    ratio = b.system.detector.pitch_x_m / r.system.detector.pitch_x_m
    label = f"{b.name} offset from {r.name} ({{}}, band px)"
    if ratio < 1.0 - 1e-9 or abs(ratio - round(ratio)) > 1e-6:
        why = (f"the band's pitch is {ratio:.4g} x the reference's: registration needs an integer multiple of "
               "it (a band no finer than the reference)")  # fmt: skip
        rows = [na_row(label.format(d.upper()), KIND_REGISTRATION, f"{b.name}/{d}", tolerance=tol,
                       tolerance_text=text, reason=why) for d in AXES]  # fmt: skip
        return rows, {"measured_px": None, "reason": why, "strips": []}
    departure = affine_departure(scene.scene, design, ref, b.index)
    if departure > MAX_AFFINE_DEPARTURE:
        why = (f"the scene's materials are not one affine function of each other between {r.name} and {b.name} "
               f"(their band reflectances depart from the best line by {departure:.1%} of the range, above "
               f"{MAX_AFFINE_DEPARTURE:.0%}): registration fits {b.name} = gain x {r.name} + bias, so its offset "
               "would be biased; measure it on a scene of two materials, or a grey one")  # fmt: skip
        pred = predicted_offset_px(entries[b.index], np.arange(r.image.shape[0]),
                                   (r.system.line_time_s, r.system.detector.tdi_stages))
        rows = [na_row(label.format(d.upper()), KIND_REGISTRATION, f"{b.name}/{d}", tolerance=tol,
                       tolerance_text=text, reason=why, predicted=pred[d]) for d in AXES]  # fmt: skip
        return rows, {"measured_px": None, "sigma_px": None, "predicted_px": {d: pred[d] for d in AXES},
                      "parts": pred["parts"], "reason": why, "affine_departure": departure, "strips": [],
                      "reference_band": r.name}  # fmt: skip
    ref_time = (r.system.line_time_s, float(r.system.detector.tdi_stages))
    got = measure_band_offset(r.image, b.image, scale=int(round(ratio)), entry=entries[b.index], ref_time=ref_time,
                              strips=time_varying(b.system))  # fmt: skip
    got["affine_departure"] = departure
    unpredicted = unpredicted_motion(b.system)
    rows, z = [], {}
    for d in AXES:
        m = None if got["measured_px"] is None else got["measured_px"][d]
        p = got["predicted_px"][d]
        s = None if got["sigma_px"] is None else got["sigma_px"][d]
        if unpredicted is not None or m is None:
            row = na_row(label.format(d.upper()), KIND_REGISTRATION, f"{b.name}/{d}", tolerance=tol,
                         tolerance_text=text, reason=unpredicted or got["reason"], measured=m,
                         predicted=None if unpredicted else p)  # fmt: skip
        else:
            row = check_row(label.format(d.upper()), KIND_REGISTRATION, f"{b.name}/{d}", m, p, tolerance=tol,
                            tolerance_text=text, sigma=s, note=_parts_note(got["parts"], d))  # fmt: skip
        rows.append(row)
        z[d] = row.z
    got["z"] = z
    got["reference_band"] = r.name
    got["scale"] = int(round(ratio))
    return rows, got


def _parts_note(parts: dict, d: str) -> str:
    p = {k: v[d] for k, v in parts.items()}
    rate = f" + line rate {p['line_rate']:+.4f}" if p.get("line_rate") else ""
    return (f"predicted = static {p['static']:+.4f} + Earth rotation {p['earth_rotation']:+.4f}{rate} + oscillations "
            f"{p['oscillations']:+.4f} px (averaged over the rows measured)")  # fmt: skip
