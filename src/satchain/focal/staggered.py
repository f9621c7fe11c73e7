"""The staggered section of a run (issue 32 point 5; see :mod:`satchain.focal`): a ``[detector] layout =
"staggered"`` system's two arrays, half a pixel apart along and across track, imaged from the run's scene and
combined onto the grid of half the pitch (:func:`satchain.engine.staggered.simulate_staggered`, the quincunx
bilinear fill), measured on that grid and compared with the prediction.

- every slanted edge of the truth: its MTF along the edge normal at the combined grid's Nyquist (``1/p``,
  0.5 cy per combined pixel) and at one array's (``1/(2p)``), against the system MTF times the combination's
  transfer function (:func:`satchain.tf.staggered.combination_otf`) along that normal;
- every bar target: its CTF per group against Coltman's CTF of that MTF; the groups whose period is below two
  pixels of one array (above its Nyquist, which one array alone cannot sample) are what the combination is for.

The main run (its image, edges, bars, ...) is array A alone, unchanged. The checks live in
:mod:`satchain.focal._staggered_checks`.
"""

from __future__ import annotations

import math
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from satchain.config.sections_staggered import stagger_separation_px
from satchain.focal._rows import na_row
from satchain.focal._staggered_checks import bar_section, combined_mtf2d, edge_section, prediction_curves
from satchain.measure._keys import RESULT_KEY
from satchain.scene.targets import BarTarget, SlantedEdge

EDGES, BARS = RESULT_KEY[SlantedEdge.kind], RESULT_KEY[BarTarget.kind]

if TYPE_CHECKING:
    from satchain.config.run import RunConfig
    from satchain.engine.staggered import StaggeredImages
    from satchain.results import BudgetResult, FocalSection, SceneResult

__all__ = ["COMBINATION_TEXT", "TITLE", "section"]

TITLE = "Staggered arrays: the combined half-pitch grid"
#: The combination, in words (results.json and the report quote it).
COMBINATION_TEXT = (
    "quincunx bilinear: array A's samples at the even rows and columns of the p/2 grid, array B's (half a pixel "
    "along and across track from A) at the odd ones, every other point the mean of its 4 neighbours (up, down, "
    "left, right)"
)
#: Its transfer function on the combined grid, in words (:func:`satchain.tf.staggered.combination_otf`).
TRANSFER_TEXT = (
    "H(fx, fy) = 1/2 + cos(pi p fx)/4 + cos(pi p fy)/4 (p the array pitch, f on the focal plane): 1 at f = 0, "
    "3/4 at one array's Nyquist 1/(2p) and 1/2 at the combined Nyquist 1/p along an axis"
)
ALIASING_TEXT = "unaliased inside |f_x| + |f_y| < 1/p; the first alias copies at (+-1/p, +-1/p)"
FILES = ("images/staggered/combined.tif", "images/staggered/array_a.tif", "images/staggered/array_b.tif")
Progress = Any


def section(config: RunConfig, budget: BudgetResult, scene: SceneResult, progress: Progress) -> FocalSection | None:
    """The staggered section of the run, or None for any other layout (the run is then unchanged)."""
    from satchain.results import FocalSection

    system = budget.system
    if system.detector.layout != "staggered":
        return None
    progress("focal", 0, 3)
    refusal = _not_simulated(system, scene)
    if refusal is not None:
        tol = config.tolerances.edge_mtf_at_nyquist
        row = na_row("staggered combined grid", "staggered_edge_mtf_at_nyquist", None, tolerance=tol,
                     tolerance_text=f"±{tol}", reason=refusal)  # fmt: skip
        return FocalSection("staggered", TITLE, (row,), {"title": TITLE, "not_simulated": refusal})
    built = config.load_as_built_system(system)
    simulated = system if built is None or built.detector.layout != "staggered" else built
    images = _simulate(config, simulated, scene)
    progress("focal", 1, 3)
    measured = _measure(config, simulated, scene, images)
    progress("focal", 2, 3)
    mtf2d = combined_mtf2d(budget.otf, system.detector.pitch_x_m)
    edge_rows, edges = edge_section(measured[EDGES], scene.truth_dict, mtf2d, config.tolerances)
    bar_rows, bars = bar_section(measured[BARS], mtf2d, config, pitch_m=system.detector.pitch_x_m)
    skipped = list(measured["skipped"])
    na = _skipped_rows(skipped, config, {e["id"] for e in edges}, {b["id"] for b in bars})
    data = _data(system, simulated is not system, budget, config, images, edges, bars, skipped, mtf2d)
    progress("focal", 3, 3)
    return FocalSection("staggered", TITLE, tuple(edge_rows + bar_rows + na), data,
                        write_files=partial(_write_files, images, config.simulation.units, simulated))  # fmt: skip


def _not_simulated(system, scene: SceneResult) -> str | None:
    """Why the two arrays cannot be imaged from this run's scene, or None."""
    from satchain.scene.layout import Scene

    if system.bands:
        return (
            f"the system has {len(system.bands)} [[bands]]: a staggered layout is formed for one monochrome array "
            "(give the staggered camera without [[bands]])"
        )
    if not isinstance(scene.scene, Scene):
        return (
            "the scene is an image: array B sees the ground half a GSD from array A, which a raster cannot give "
            "without resampling it (give a layout: [scene] layout = a scene file or 'paper')"
        )
    return None


def _render_pixel_m(gsd_act_m: float, scene_pixel_m: float) -> float:
    """The layout's rendering pixel: the largest not above the run's scene pixel that divides half the ACT GSD."""
    return gsd_act_m / (2 * math.ceil(gsd_act_m / (2 * scene_pixel_m) - 1e-9))


def _simulate(config: RunConfig, system, scene: SceneResult) -> StaggeredImages:
    from satchain.engine.simulate import SimParams
    from satchain.engine.staggered import simulate_staggered

    c = config.simulation
    return simulate_staggered(
        scene.scene, system, pixel_m=_render_pixel_m(system.gsd_act_m, scene.pixel_m), seed=c.seed, noise=c.noise,
        units=c.units, params=SimParams(far_margin_px=c.far_margin_px, border=c.border),
    )  # fmt: skip


def _measure(config: RunConfig, system, scene: SceneResult, images: StaggeredImages) -> dict[str, Any]:
    """The edges and bar targets of the truth measured on the combined grid (as the run measures its image)."""
    from satchain.engine.sensor import sensor_from_system
    from satchain.measure.auto import measure_auto

    truth = scene.truth_dict
    ids = [str(it["id"]) for it in truth.get("items", []) if it.get("kind") in (SlantedEdge.kind, BarTarget.kind)]
    if not ids:
        return {EDGES: [], BARS: [], "skipped": []}
    c = config.simulation
    t = images.transform
    auto = measure_auto(images.combined, truth, pixel_m=images.combined_gsd_m[0], origin_m=(t.c, t.f), ids=ids,
                        wedge_threshold=config.measurement.wedge_threshold,
                        full_scale=sensor_from_system(system).full_scale(c.units, noise=c.noise))  # fmt: skip
    return auto.to_dict()


def _skipped_rows(skipped: list[dict], config: RunConfig, edge_ids: set, bar_ids: set) -> list:
    """An n/a row for each edge or bar target the combined grid could not measure at all (with the reason)."""
    rows = []
    for s in skipped:
        ident, kind = str(s.get("id")), str(s.get("kind", ""))
        if kind == SlantedEdge.kind and ident not in edge_ids:
            tol = config.tolerances.edge_mtf_at_nyquist
            rows.append(
                na_row(
                    f"staggered edge {ident} MTF@combined Nyquist",
                    "staggered_edge_mtf_at_nyquist",
                    ident,
                    tolerance=tol,
                    tolerance_text=f"±{tol}",
                    reason=f"not measured: {s.get('reason')}",
                )
            )
        elif kind == BarTarget.kind and ident not in bar_ids:
            tol = config.tolerances.bar_ctf
            rows.append(
                na_row(
                    f"staggered bars {ident} max |CTF error|",
                    "staggered_bar_ctf",
                    ident,
                    tolerance=tol,
                    tolerance_text=f"≤{tol}",
                    reason=f"not measured: {s.get('reason')}",
                )
            )
    return rows


def _data(system, as_built: bool, budget: BudgetResult, config: RunConfig, images: StaggeredImages, edges: list,
          bars: list, skipped: list, mtf2d) -> dict[str, Any]:  # fmt: skip
    """results.json's ``staggered`` entry: everything the report draws."""
    from satchain.tf.staggered import nyquist_cy_per_mm

    p = system.detector.pitch_x_m
    st = budget.budget.get("staggered") or {}
    t = images.transform
    beyond = [f"{b['id']} group {g['group']}" for b in bars for g in b["groups"]
              if g["beyond_single_nyquist"] and g["resolved_measured"]]  # fmt: skip
    return {
        "title": TITLE,
        "system": system.name,
        "simulated": "as built ([as_built])" if as_built else "as designed",
        "pitch_m": p,
        "combined_pitch_m": p / 2,
        "gsd_m": list(images.gsd_m),
        "combined_gsd_m": list(images.combined_gsd_m),
        "nyquist_cy_per_mm": {
            "single_array": nyquist_cy_per_mm(p) / 2,
            "combined_axis": nyquist_cy_per_mm(p),
            "combined_diagonal": nyquist_cy_per_mm(p, direction="diagonal"),
        },  # fmt: skip
        "combination": {
            "method": images.combination,
            "description": COMBINATION_TEXT,
            "transfer_function": TRANSFER_TEXT,
        },  # fmt: skip
        "aliasing": st.get("aliasing", ALIASING_TEXT),
        "budget": {k: st[k] for k in ("mtf_at_combined_nyquist", "mtf_at_single_nyquist") if k in st},
        "grid": {
            "array_shape": list(images.a.shape),
            "combined_shape": list(images.combined.shape),
            "array_window_px": list(images.window),
            "combined_origin_m": [t.c, t.f],
            "array_b_offset": "half a GSD along and across track from array A (+x, +y)",
            "separation_px": stagger_separation_px(system.detector),
            "separation_note": "array B's centre line this many rows along track from A's "
            "(detector.stagger_separation_px; default tdi_stages + 1/2); the simulation images B half a GSD "
            "from A without the time between them",
        },  # fmt: skip
        "units": images.units,
        "noise": bool(config.simulation.noise),
        "seed": int(config.simulation.seed),
        "prediction": "the system MTF (as the run predicts its edges) x the combination's H(fx, fy), along each "
        "edge's normal; bars: Coltman's CTF of that MTF along the bars' axis",
        "mtf_curves": prediction_curves(mtf2d, p),
        "edges": edges,
        "bars": bars,
        "resolution_threshold": float(config.measurement.wedge_threshold),
        "beyond_single_nyquist_resolved": beyond,
        "skipped": skipped,
        "images": list(FILES),
    }


def _write_files(images: StaggeredImages, units: str, system, out_dir: Path) -> list[str]:
    """Array A, array B (each on its own GSD grid, B's corner half a GSD from A's) and the combination (half-GSD
    pixels, its corner a quarter GSD from A's) under ``images/staggered/``, georeferenced as ``simulated.tif``."""
    from satchain.io import images as io

    g = images.gsd_m[0]
    x0, y0 = images.window.col0 * g, images.window.row0 * g
    meta = {"system": system.name, "layout": "staggered", "combination": images.combination}
    bit_depth = system.detector.bit_depth
    (out_dir / FILES[0]).parent.mkdir(parents=True, exist_ok=True)
    rasters = (
        (FILES[1], images.a, g, (x0, y0), "array A"),
        (FILES[2], images.b, g, (x0 + g / 2, y0 + g / 2), "array B: half a GSD along and across track from A"),
        (FILES[0], images.combined, g / 2, (x0 + g / 4, y0 + g / 4), f"A and B combined ({images.combination})"),
    )
    for rel, img, px, origin, what in rasters:
        a = np.asarray(img)
        m = {**meta, "array": what, "units": units}
        if units == "dn" and rel != FILES[0]:  # one array's DN as the run writes them; the fill's means are float
            top = 2.0 ** (12 if bit_depth is None else int(bit_depth)) - 1
            m["bit_depth"] = 12 if bit_depth is None else int(bit_depth)
            a = np.clip(np.round(a), 0, top).astype(io.simulated_dtype(units, bit_depth))
        else:
            a = a.astype(np.float32)
        io.write_tiff(out_dir / rel, a, pixel_m=px, origin_m=origin, metadata=m)
    return list(FILES)
