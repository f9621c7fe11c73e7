"""The stages of ``satchain run`` / :func:`satchain.run`: predict, simulate, measure, compare and report.

Stages: budget (MTF, CTF, radiometry, SNR, GIQE) -> scene (ground truth and its truth record) -> simulation
(the satellite image and the focal-plane image) -> measurement of every target and of the SNR -> prediction
of each measured figure and comparison -> the focal plane as flown (:mod:`satchain.focal`: bands, colour
planes, staggered arrays; nothing for one monochrome array) -> report (``report.html``, ``results.json``,
``summary.csv``, images, ``manifest.json``).
Each stage is a function of the typed results before it (:mod:`satchain.results`); only the report writes files.
The truth record travels typed (:class:`satchain.scene.truth.Truth`); the JSON dict is made only where a
function still reads that form (measure_auto, the report figures) and where it is written.

Everything is written into a staging directory beside ``out_dir`` and swapped in only when the run has
succeeded, so an existing ``out_dir`` is never left holding a mix of old and new results, and a failed
run leaves the previous results untouched.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import platform
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from satchain.results import BudgetResult, Measurements, RunResult, SceneResult, SimulationResult

if TYPE_CHECKING:
    from satchain.comparison import Comparison
    from satchain.config.run import RunConfig
    from satchain.config.system import ImagingSystem
    from satchain.prediction.core import Predictions
    from satchain.report.truth_crops import TruthCrops

__all__ = ["STAGES", "ReportInputs", "run_in_memory", "run_pipeline", "run_to_directory", "write_run_directory"]

#: The stages, in order, as the progress display names them.
STAGES = ("budget", "scene", "simulate", "measure", "compare", "focal", "report")
Progress = Callable[[str, int, int], None]
MANIFEST = "manifest.json"


def _stage_budget(config: RunConfig, progress: Progress) -> BudgetResult:
    from satchain.prediction.budget import budget_results
    from satchain.tf.budget import SystemOTF

    s = config.load_system()
    _check_square(s, "system")
    _check_square(config.load_as_built_system(s), "as_built")  # refused before any work is done
    otf = SystemOTF(s)
    result = BudgetResult(s, otf, budget_results(s, otf=otf))
    progress("budget", 1, 1)
    return result


def _check_square(s, what: str) -> None:
    if s is not None and abs(s.gsd_act_m - s.gsd_alt_m) > 1e-6 * s.gsd_alt_m:
        from satchain.errors import ConfigError

        raise ConfigError(
            f"{what} {s.name!r}: ground pixels of {s.gsd_act_m:.4g} m (ACT) x {s.gsd_alt_m:.4g} m (ALT); satchain run "
            "measures square ground pixels only (nadir, square pitch). Use 'satchain budget' and 'satchain simulate' "
            "for this system"
        )


def _stage_scene(config: RunConfig, progress: Progress) -> SceneResult:
    from satchain.scene import load_layout
    from satchain.scene.layout import check_scene_pixel
    from satchain.scene.truth import read_truth

    sc = config.scene
    scene = load_layout(config.layout_source())
    check_scene_pixel(scene, sc.pixel_m, name="scene.pixel_m")
    result = SceneResult(scene, read_truth(scene.truth(pixel_m=sc.pixel_m)), sc.pixel_m)
    progress("scene", 1, 1)
    return result


def _stage_simulate(
    config: RunConfig, budget: BudgetResult, scene: SceneResult, progress: Progress, *, scene_view=None
) -> SimulationResult:
    from satchain.engine.memory import check_simulation_memory
    from satchain.engine.sensor import sensor_from_system
    from satchain.engine.simulate import SimParams, Simulator
    from satchain.engine.sources import SceneSource
    from satchain.tf.budget import SystemOTF

    c = config.simulation
    built = config.load_as_built_system(budget.system)  # the camera as built; None: as designed
    system, otf = (budget.system, budget.otf) if built is None else (built, SystemOTF(built))
    src = SceneSource(scene.scene if scene_view is None else scene_view(scene.scene), pixel_m=scene.pixel_m)
    params = SimParams(far_margin_px=c.far_margin_px, border=c.border)
    sim = Simulator(system, input_pixel_m=src.pixel_m, input_shape=src.shape_px, params=params, otf=otf,
                    motion_seed=c.seed)  # fmt: skip
    check_simulation_memory(sim, focal_plane="coarse")
    coarse = sim.decimate(src, progress=lambda d, t: progress("simulate", d, t + 1))
    sensor = sensor_from_system(system)
    image = sim.run(src, sensor=sensor, units=c.units, noise=c.noise, seed=c.seed, coarse=coarse)
    focal_plane = sim.focal_plane(coarse, grid="coarse")  # D x smaller; exact band-limited samples
    progress("simulate", len(sim.tiles) + 1, len(sim.tiles) + 1)
    return SimulationResult(image, focal_plane, src.pixel_m * sim.D, c.units, sensor, sim, system=system)


def _stage_measure(
    system: ImagingSystem, scene: SceneResult, sim: SimulationResult, noise: bool, progress: Progress
) -> Measurements:
    """Every target measured; clipping is named where pixels reach the simulated detector's full scale (in the
    image's units: ``2**bit_depth - 1`` DN, or the full well) or on the data's own evidence."""
    from satchain.measure.auto import measure_auto
    from satchain.measure.snr import measure_snr

    full_scale = sim.sensor.full_scale(sim.units, noise=noise)
    geo = _image_affine(system, scene.truth_dict, sim.image.shape)
    auto = measure_auto(sim.image, scene.truth_dict, pixel_m=system.gsd_act_m, full_scale=full_scale,
                        **({} if geo is None else {"image_affine": geo}),
                        **_row_offsets(system, scene, sim))  # fmt: skip
    cal = auto.calibration  # its gain models the diffraction tail that pulls the plateaus' medians
    gain = cal.get("gain") if cal.get("fitted") else None
    snr = measure_snr(sim.image, scene.truth, pixel_m=system.gsd_act_m, gain=gain, image_affine=geo)
    if not noise:  # the background's scatter is the scene's and the optics' own: no noise, so no SNR (nor NIIRS)
        why = "the image is noise-free ([simulation] noise = false): it has no noise to measure an SNR from"
        snr = dataclasses.replace(snr, snr=float("nan"), noise_dn=None, reason=why, snr_sigma=None,
                                  snr_sigma_null_means=f"the SNR is not measured: {why}")  # fmt: skip
    progress("measure", 1, 1)
    return Measurements(auto, snr)


def _row_offsets(system: ImagingSystem, scene: SceneResult, sim: SimulationResult) -> dict:
    """``{"row_offsets_px": (du, dv)}`` when the line of sight moves the image's rows (oscillations, jitter, a log):
    row ``i`` sees the mean map's point of image pixel ``(j + du_i, i + dv_i)``
    (:class:`~satchain.prediction.image_geometry.ImageGeometry`; the star aligns its rows with them), else {}."""
    from satchain.prediction.image_geometry import run_geometry

    g = run_geometry(system, scene.truth_dict, sim.simulator, sim.image.shape)
    if g is None or not g.moves:
        return {}
    return {"row_offsets_px": g._row_offsets(np.arange(sim.image.shape[0], dtype=float))}


def _image_affine(system: ImagingSystem, truth: dict, shape: tuple[int, int]):
    """The simulated image's geometry for :func:`~satchain.measure.auto.measure_auto` when the system's pushbroom
    terms shear or scale it (Earth rotation, a line-rate error): scene metres -> image pixels, the engine's mean
    map (:meth:`~satchain.tf.pushbroom.PushbroomTerms.image_affine`; a yaw turns the image of ``shape`` about its
    centre) from the corner the measurement uses; None for a static system (its plain grid)."""
    from affine import Affine

    from satchain.measure.auto import truth_origin_m
    from satchain.tf.pushbroom import PushbroomTerms

    terms = PushbroomTerms(system)
    if not terms.active:
        return None
    ox, oy = truth_origin_m(truth)
    return terms.image_affine((shape[0], shape[1])) @ Affine.translation(-ox, -oy)


def _stage_compare(config: RunConfig, budget: BudgetResult, scene: SceneResult, sim: SimulationResult,
                   measured: Measurements, progress: Progress) -> tuple[Predictions, Comparison]:  # fmt: skip
    from satchain.comparison import compare

    predicted = _predict(config, budget, scene.truth, sim)
    comparison = _with_as_built(config, budget, scene.truth, sim, measured,
                                compare(measured, predicted, config.tolerances))  # fmt: skip
    progress("compare", 1, 1)
    return predicted, comparison


def _with_as_built(config: RunConfig, budget: BudgetResult, truth, sim: SimulationResult, measured: Measurements,
                   comparison: Comparison) -> Comparison:  # fmt: skip
    """``comparison`` (against the design) with the prediction for the camera as built beside each row and
    target (:func:`satchain.comparison.as_built.with_as_built`) when ``[as_built]`` changed the camera."""
    if config.as_built is None or sim.system is None or sim.system == budget.system:
        return comparison
    from satchain.comparison import compare
    from satchain.comparison.as_built import with_as_built

    built = BudgetResult(sim.system, sim.simulator.otf, {"quality": None})  # its quality from its own budget
    return with_as_built(comparison, compare(measured, _predict(config, built, truth, sim), config.tolerances))


def _predict(config: RunConfig, budget: BudgetResult, truth, sim: SimulationResult) -> Predictions:
    """The predictions, with the simulated image's geometry row by row when its system moves the line of sight
    in time (:func:`satchain.prediction.image_geometry.run_geometry`: the edges' angles are predicted through it, the
    wedges' widths in metres on the image's own ground steps, an along-track scale included)."""
    from satchain.prediction.core import predict
    from satchain.prediction.image_geometry import run_geometry

    truth_d = truth if isinstance(truth, dict) else truth.to_dict()
    geo = run_geometry(sim.system or budget.system, truth_d, sim.simulator, sim.image.shape)
    p = predict(
        budget.system,
        truth,
        otf=budget.otf,
        quality=budget.budget["quality"],
        sensor=sim.sensor,
        wedge_threshold=config.measurement.wedge_threshold,
        image_grid_m=None if geo is None else (geo.steps_m, (~geo.to_image) @ (-0.5, -0.5)),
    )
    return p if geo is None else dataclasses.replace(p, geometry=geo)


def _edge_results(config: RunConfig, budget: BudgetResult, scene: SceneResult, sim: SimulationResult,
                  measured: Measurements) -> list[dict]:  # fmt: skip
    """results.json's slanted edges as :func:`_stage_compare` will give them, from the edges alone (their
    prediction is the system MTF along each normal: a millisecond, where the stars' and wedges' take most of the
    stage), so that a run folder's edge figures are drawn while the other targets are compared."""
    from satchain.comparison import compare
    from satchain.report.kinds import EDGES
    from satchain.results import strict_json

    truth = scene.truth_dict
    edges_only = dict(truth, items=[it for it in truth["items"] if it.get("kind") == EDGES.kind])
    auto = measured.auto
    auto = dataclasses.replace(auto, items=tuple(it for it in auto.items if it.kind == EDGES.kind), skipped=())
    edges = Measurements(auto, measured.snr)
    c = compare(edges, _predict(config, budget, edges_only, sim), config.tolerances)
    c = _with_as_built(config, budget, edges_only, sim, edges, c)
    return strict_json([d.to_dict() for d in c.details[EDGES.key]])


def run_in_memory(
    config: RunConfig, *, progress: Progress | None = None, after_stage=None, scene_view=None
) -> RunResult:
    """Every stage but the report, in memory (see :func:`satchain.run`). ``after_stage(name, **outputs)``, if
    given, is called once the scene, the simulation and the measurements are ready (the run folder's figure
    helpers start on what those alone decide while the run goes on). ``scene_view(scene)``, if given: what the
    simulation renders the scene's windows from (the run folder keeps the thumbnails' ground truth as they are
    rendered: :class:`satchain.report.truth_crops.TruthCrops`)."""
    report = progress or (lambda stage, done, total: None)
    timings: dict[str, float] = {}

    def timed(name, fn, *args):
        t0 = time.perf_counter()
        out = fn(*args, report)
        timings[name] = round(time.perf_counter() - t0, 3)
        return out

    after = after_stage or (lambda name, **outputs: None)
    budget = timed("budget", _stage_budget, config)
    scene = timed("scene", _stage_scene, config)
    after("scene", budget=budget, scene=scene)
    sim = timed("simulate", functools.partial(_stage_simulate, scene_view=scene_view), config, budget, scene)
    after("simulate", budget=budget, scene=scene, sim=sim)
    measured = timed(  # the image's own GSD and the simulated detector's full scale
        "measure", _stage_measure, sim.system or budget.system, scene, sim, config.simulation.noise
    )
    after("measure", budget=budget, scene=scene, sim=sim, measured=measured)
    predicted, comparison = timed("compare", _stage_compare, config, budget, scene, sim, measured)
    focal = timed("focal", _stage_focal, config, budget, scene)  # bands, colour planes, staggered arrays
    if focal:  # their checks join the run's
        comparison = dataclasses.replace(comparison, rows=comparison.rows + tuple(r for f in focal for r in f.rows))
    return RunResult(config, budget, scene, sim, measured, predicted, comparison, timings, focal=focal)


def _stage_focal(config: RunConfig, budget: BudgetResult, scene: SceneResult, progress: Progress) -> tuple:
    """The focal plane as flown (:mod:`satchain.focal`): () for a single monochrome array."""
    from satchain.focal import focal_sections

    out = focal_sections(config, budget, scene, progress)
    progress("focal", 1, 1)
    return out


@dataclass(frozen=True)
class ReportInputs:
    """The read-only view of a run that the report code (report/html.py, report/run_figures.py) reads:
    ``out`` (the directory being written), ``config``, ``system``, ``otf``, ``budget`` (dict), ``scene``,
    ``truth`` (the JSON dict the figures read), ``simulator``, ``image``, ``focal_plane``, ``sensor``,
    ``measured`` (dict), ``comparison`` (``{"results": results.json's content}``), ``timings_s`` and
    ``image_gsd_m`` (the simulated image's pixel: the as-built camera's, which may differ from ``system``'s)."""

    result: RunResult
    out: Path
    results: dict[str, Any]

    config = property(lambda self: self.result.config)
    system = property(lambda self: self.result.budget.system)
    otf = property(lambda self: self.result.budget.otf)
    budget = property(lambda self: self.result.budget.budget)
    scene = property(lambda self: self.result.scene.scene)
    simulator = property(lambda self: self.result.simulation.simulator)
    image = property(lambda self: self.result.simulation.image)
    focal_plane = property(lambda self: self.result.simulation.focal_plane)
    sensor = property(lambda self: self.result.simulation.sensor)
    comparison = property(lambda self: {"results": self.results})
    timings_s = property(lambda self: self.result.timings_s)
    #: The simulated image's pixel on the ground (m): the camera as built when ``[as_built]`` changes it.
    image_gsd_m = property(lambda self: float((self.result.simulation.system or self.result.budget.system).gsd_act_m))

    @cached_property
    def truth(self) -> dict[str, Any]:
        return self.result.scene.truth_dict

    @cached_property
    def image_affine(self):
        """The simulated image's map from truth metres to its pixels when pushbroom terms shear, scale or turn
        it (the one the measurement used), else None: the report draws its overlays through it."""
        sim = self.result.simulation
        return _image_affine(sim.system or self.system, self.truth, sim.image.shape)

    @cached_property
    def measured(self) -> dict[str, Any]:
        """The measurements as results.json's ``measured`` holds them (built once per view: the report's pages
        and figures read them many times)."""
        return self.result.measurements.to_dict()

    @cached_property
    def edge_results(self) -> dict[str, Any]:
        """The slanted edges' :class:`~satchain.measure.edge.EdgeResult` objects by truth id: their ESF and LSF,
        as measured, for the comparison figures."""
        from satchain.scene import SlantedEdge

        return {it.id: it.result for it in self.result.measurements.auto.by_kind(SlantedEdge.kind)}


class _EarlyFigures:
    """The run folder's outputs that the budget and scene alone decide (budget tables and figures, the scene
    overview), the thumbnails' ground-truth panels once the simulation fixes the image's extent, and the
    figures the measurement decides (:func:`~satchain.report.run_figures.submit_measured_figures`), handed to
    ``jobs`` (:class:`satchain.report._jobs.FigureJobs`: all their inputs pickle; the OTF is rebuilt from the
    system) as the run reaches them: the helpers draw them while this process simulates, measures and compares.
    Called as :func:`run_in_memory`'s ``after_stage``."""

    def __init__(self, config: RunConfig, out: Path, jobs) -> None:
        self.config, self.out, self.jobs = config, out, jobs
        self.thumbnails: list[tuple[dict, tuple, int]] = []  # (item, box, job of its ground-truth panel)
        self.measured = False  # the measured figures handed over
        self.crops: TruthCrops | None = None  # the thumbnails' ground truth, kept as the simulation renders it
        self.edges: list[dict] | None = None  # results.json's edges, their figures handed over
        self.edge_curves: list[dict] | None = None

    def scene_view(self, scene):
        """:func:`run_in_memory`'s ``scene_view``: the scene, keeping the thumbnails' ground truth."""
        return scene if self.crops is None else self.crops

    def __call__(self, stage: str, *, budget: BudgetResult, scene: SceneResult, sim=None, measured=None) -> None:
        from satchain.report import run_figures
        from satchain.report._save import write_text
        from satchain.report.budget import write_budget_outputs
        from satchain.report.gallery import grey8_truth_panel, thumbnail_boxes, truth_panel
        from satchain.report.truth_crops import TruthCrops
        from satchain.scene import SiemensStar

        out, jobs = self.out, self.jobs
        if stage == "scene":
            jobs.submit(write_budget_outputs, budget.system, dict(budget.budget), out / "budget")
            (out / "images").mkdir(parents=True, exist_ok=True)
            truth = scene.truth_dict
            write_text(out / "images" / "scene.truth.json", json.dumps(truth, indent=1))
            p = self.config.scene.overview_pixel_m
            jobs.submit(run_figures.render_scene_overview, scene.scene, truth, p, out / "figures" / "fig1_scene.png")
            rows, cols = scene.scene.shape_px(scene.pixel_m)  # the image's extent is not known yet: the scene's
            boxes = [box for _, box in thumbnail_boxes(truth, (cols * scene.pixel_m, rows * scene.pixel_m))]
            self.crops = TruthCrops(scene.scene, boxes, scene.pixel_m)
        elif stage == "simulate":
            system = sim.system or budget.system  # the camera simulated (as built)
            args, kwargs = _images_call(self.config, system, sim, out)
            jobs.submit(write_images, *args, **kwargs)
            gsd, p = float(system.gsd_act_m), float(self.config.scene.pixel_m)
            extent = (sim.image.shape[1] * gsd, sim.image.shape[0] * gsd)
            crops, self.crops = self.crops, None
            for it, box in thumbnail_boxes(scene.truth_dict, extent):
                grey = None if crops is None else crops.take(box)
                if grey is not None:  # as the simulation rendered it: only the PNG is left to make
                    job = jobs.submit(grey8_truth_panel, grey, p)
                else:  # rendered again; the exact star first, the longest render
                    job = jobs.submit(truth_panel, scene.scene, box, p, first=it["kind"] == SiemensStar.kind)
                self.thumbnails.append((it, box, job))
            if crops is not None:
                crops.release()
        elif stage == "measure":  # a view of the run so far: what those figures read
            partial = RunResult(self.config, budget, scene, sim, measured, None, None, {})  # type: ignore[arg-type]
            run_figures.submit_measured_figures(ReportInputs(partial, out, {}), jobs)
            self.measured = True
            self._edge_figures(partial, budget, scene, sim, measured)

    def _edge_figures(self, partial: RunResult, budget, scene, sim, measured) -> None:
        """Hand over the edges' figures, from the edges' results as the compare stage will give them."""
        from satchain.report import run_figures
        from satchain.report.curves import edge_curves
        from satchain.report.kinds import EDGES

        edges = _edge_results(self.config, budget, scene, sim, measured)
        if edges:
            view = ReportInputs(partial, self.out, {EDGES.key: edges})
            self.edges, self.edge_curves = edges, edge_curves(view)
            run_figures.submit_edge_figures(view, self.edge_curves, self.jobs)


def write_images(d: Path, image: np.ndarray, focal_plane: np.ndarray, *, units: str, bit_depth: int, pixel_m: float,
                 focal_plane_pixel_m: float, metadata: dict) -> None:  # fmt: skip
    """The simulated image (TIFF, PNG preview) and the focal-plane image (TIFF, PNG) into ``d``: plain data, so
    that a figure helper writes them while the run measures."""
    from satchain.io import images as io
    io.write_simulated(d / "simulated.tif", image, units=units, bit_depth=bit_depth, pixel_m=pixel_m, metadata=metadata)
    fp_meta = {"units": "scene reflectance filtered by the optics and motion", "system": metadata["system"]}
    io.write_tiff(d / "focal_plane.tif", focal_plane.astype(np.float32), pixel_m=focal_plane_pixel_m, metadata=fp_meta)
    io.write_png(d / "focal_plane.png", io.preview_uint8(focal_plane), pixel_m=focal_plane_pixel_m)


def _images_call(config: RunConfig, system: ImagingSystem, sim: SimulationResult, out: Path) -> tuple:
    """:func:`write_images`'s arguments for the run's simulation (``system``: the camera simulated, as built)."""
    c = config.simulation
    meta = {"units": c.units, "noise": c.noise, "seed": c.seed, "system": system.name, "gsd_alt_m": system.gsd_alt_m}
    args = (out / "images", sim.image, sim.focal_plane)
    return args, {"units": c.units, "bit_depth": sim.sensor.bit_depth, "pixel_m": system.gsd_act_m,
                  "focal_plane_pixel_m": sim.focal_plane_pixel_m, "metadata": meta}  # fmt: skip


#: modules the figure helpers import first (satchain.report._jobs)
_FIGURE_MODULES = ("satchain.report.compare_plots", "satchain.report.gallery", "satchain.report.budget",
                   "satchain.report.run_figures", "satchain.report.motion_plot", "satchain.scene")  # fmt: skip


def write_run_directory(
    result: RunResult, out: Path, *, progress: Progress | None = None, jobs=None, early: _EarlyFigures | None = None
) -> None:
    """Write every output of ``result`` but the manifest into the (new, staging) directory ``out``; ``jobs``: a
    :class:`satchain.report._jobs.FigureJobs` already launched (its helpers warm), else one made here; ``early``:
    the outputs already handed to it while the run computed (:class:`_EarlyFigures`), else handed here."""
    from satchain.config.run import config_to_toml
    from satchain.report import curves, html, run_figures
    from satchain.report._jobs import FigureJobs
    from satchain.report._save import write_text
    from satchain.report.gallery import assemble_thumbnail, thumbnail_crops
    from satchain.report.kinds import EDGES
    from satchain.report.summary_csv import write_summary_csv

    report = progress or (lambda stage, done, total: None)
    results = result.to_json_dict()
    view = ReportInputs(result, out, results)
    if jobs is None:
        jobs = FigureJobs()
        jobs.launch(_FIGURE_MODULES)  # they import while the thumbnails' inputs are cut here
    with jobs:  # plain-data figures in helpers, the rest here
        if early is None:
            early = _EarlyFigures(result.config, out, jobs)
            early("scene", budget=result.budget, scene=result.scene)
            early("simulate", budget=result.budget, scene=result.scene, sim=result.simulation)
        early_edges = early.edges is not None and early.edges == results.get(EDGES.key)  # as compared: drawn
        shown = curves.build_curves(view, edges=early.edge_curves if early_edges else None)
        run_figures.write_run_figures(view, shown, jobs=jobs, measured_figures=not early.measured,
                                      edge_figures=early.edges is None)  # fmt: skip
        curves.write_curves(shown, out / "curves")
        for f in result.focal:  # the bands' rasters, the raw mosaic, the combined grid
            if f.write_files is not None:
                f.write_files(out)
        write_text(out / "results.json", json.dumps(results, indent=1, allow_nan=False))
        write_summary_csv(results, out / "summary.csv")
        crops = thumbnail_crops(view, [box for _, box, _ in early.thumbnails])
    if early.edges is not None and not early_edges:  # never expected: the edges' figures drawn again, as compared
        with FigureJobs(0) as here:
            run_figures.submit_edge_figures(view, shown["edges"], here)
    thumbnails = [assemble_thumbnail(it, box, jobs.result(job), *c)
                  for (it, box, job), c in zip(early.thumbnails, crops, strict=True)]  # fmt: skip
    html.write_report(view, out / "report.html", thumbnails=thumbnails)
    report("report", 1, 1)
    write_text(out / "config.toml", config_to_toml(result.config))


def _json_default(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def _manifest(result: RunResult) -> dict[str, Any]:
    import matplotlib
    import scipy

    import satchain

    return {
        "satchain_version": satchain.__version__,
        "config": result.config.to_dict(),
        "system": result.system.to_dict(),
        "seed": result.config.simulation.seed,
        "versions": {
            "python": platform.python_version(),
            "numpy": np.__version__,
            "scipy": scipy.__version__,
            "matplotlib": matplotlib.__version__,
        },
        "platform": platform.platform(),
        "timings_s": dict(result.timings_s),
        "reproduce": "satchain run --config config.toml -o DIR  (config.toml is beside this manifest)",
    }


#: the Figure 1 overview: at most this many pixels, each costing about this many bytes while it is plotted
MAX_OVERVIEW_PX = 64e6
_OVERVIEW_BYTES_PER_PX = 40


def _check_overview(config: RunConfig) -> None:
    """Refuse, before anything runs, an overview figure that could not be rendered (``overview_pixel_m``
    far below the scene's size), saying how large and how much memory it would need."""
    from satchain._safety import check_memory
    from satchain.errors import ResourceLimitError
    from satchain.scene import load_layout

    p = config.scene.overview_pixel_m
    rows, cols = load_layout(config.layout_source()).shape_px(p)
    n, need = float(rows) * cols, float(rows) * cols * _OVERVIEW_BYTES_PER_PX
    what = f"scene.overview_pixel_m = {p:g}: the scene overview (Figure 1) would be {cols} x {rows} px"
    if n > MAX_OVERVIEW_PX:
        raise ResourceLimitError(
            f"{what} and need about {need / 2**30:.3g} GiB of memory; must be >= "
            f"{p * (n / MAX_OVERVIEW_PX) ** 0.5:.3g} m (at most {MAX_OVERVIEW_PX / 1e6:.0f} Mpx); nothing was written"
        )
    check_memory(need, what, fix="use a larger scene.overview_pixel_m")


def _check_out_dir(out: Path) -> None:
    from satchain._safety import check_run_dir, clean_stale

    check_run_dir(out)  # only a missing, empty or satchain-marked directory may be replaced
    clean_stale(out)  # staging / old folders of killed runs


def run_to_directory(config: RunConfig, out_dir: str | Path, *, progress: Progress | None = None) -> RunResult:
    """Run every stage and write the run directory ``out_dir`` (atomically replaced); return the result.

    Interrupted (Ctrl-C, or SIGTERM, which raises :class:`satchain._safety.Interrupted` while this runs), failed
    or not, the staging folder is removed and a previous ``out_dir`` is left as it was.
    """
    from satchain._safety import terminate_as_interrupt
    from satchain.io.runfolder import swap_in, written_files

    out = Path(out_dir).resolve()
    _check_out_dir(out)
    _check_overview(config)
    out.parent.mkdir(parents=True, exist_ok=True)
    with terminate_as_interrupt() as received:
        staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.staging-", dir=out.parent))
        try:
            _claim_run_dir(staging)

            def checked(stage: str, done: int, total: int) -> None:  # a swallowed signal stops the run here too
                received.check()
                if progress is not None:
                    progress(stage, done, total)

            from satchain.report._jobs import FigureJobs

            jobs = FigureJobs()  # warm helpers: they draw what each stage decides while the next one runs
            jobs.launch(_FIGURE_MODULES)
            jobs.start()
            early = _EarlyFigures(config, staging, jobs)
            try:
                result = run_in_memory(config, progress=checked, after_stage=early, scene_view=early.scene_view)
            except BaseException:
                jobs.kill()
                raise
            t0 = time.perf_counter()
            timings = dict(result.timings_s)
            write_run_directory(result, staging, progress=checked, jobs=jobs, early=early)
            timings["report"] = round(time.perf_counter() - t0, 3)
            result = dataclasses.replace(result, timings_s=timings)
            from satchain.report._save import write_text

            manifest = _manifest(result) | {"files": written_files(staging)}  # what a rerun may replace
            write_text(staging / MANIFEST, json.dumps(manifest, indent=1, default=_json_default))
            received.check()  # a signal whose exception library code swallowed still stops the run here
            result = dataclasses.replace(result, kept_files=swap_in(staging, out))  # the user's files kept
        except BaseException:
            shutil.rmtree(staging, ignore_errors=True)
            raise
    return result


def run_pipeline(config: RunConfig, out_dir: str | Path, *, progress: Progress | None = None) -> dict[str, Any]:
    """Run every stage into ``out_dir`` (atomically replaced); return ``results.json``'s content."""
    return run_to_directory(config, out_dir, progress=progress).to_json_dict()


def _claim_run_dir(directory: Path, *, marker: bool = True) -> None:
    from satchain._safety import claim, write_run_marker

    claim(directory)
    if marker:
        write_run_marker(directory)
