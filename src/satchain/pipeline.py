"""``satchain run``: predict, simulate, measure, compare and report, in one command.

Stages: budget (MTF, CTF, radiometry, SNR, GIQE) -> scene (ground truth and its truth file) -> simulation
(the satellite image and the focal-plane image) -> measurement of every target -> comparison of measured
and predicted figures of merit -> report (``report.html``, ``results.json``, images, ``manifest.json``).

Everything is written into a staging directory beside ``out_dir`` and swapped in only when the run has
succeeded, so an existing ``out_dir`` is never left holding a mix of old and new results, and a failed
run leaves the previous results untouched.
"""

from __future__ import annotations

import contextlib
import json
import os
import platform
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from satchain.runconfig import RunConfig

__all__ = ["STAGES", "RunContext", "run_pipeline"]

#: The stages, in order, as the progress display names them.
STAGES = ("budget", "scene", "simulate", "measure", "compare", "report")
Progress = Callable[[str, int, int], None]
MANIFEST = "manifest.json"


@dataclass
class RunContext:
    """What the stages hand each other (internal to one run)."""

    config: RunConfig
    out: Path
    system: Any = None
    otf: Any = None
    budget: dict | None = None
    scene: Any = None
    truth: dict | None = None
    simulator: Any = None
    image: np.ndarray | None = None
    focal_plane: np.ndarray | None = None
    sensor: Any = None
    measured: dict | None = None
    comparison: dict | None = None
    timings_s: dict | None = None


def _stage_budget(ctx: RunContext, progress: Progress) -> None:
    from satchain.report.budget import budget_results, write_budget_outputs
    from satchain.tf.budget import SystemOTF

    ctx.system = ctx.config.load_system()
    s = ctx.system
    if abs(s.gsd_act_m - s.gsd_alt_m) > 1e-6 * s.gsd_alt_m:
        from satchain.errors import ConfigError

        raise ConfigError(
            f"system {s.name!r}: ground pixels of {s.gsd_act_m:.4g} m (ACT) x {s.gsd_alt_m:.4g} m (ALT); satchain run "
            "measures square ground pixels only (nadir, square pitch). Use 'satchain budget' and 'satchain simulate' "
            "for this system"
        )
    ctx.otf = SystemOTF(ctx.system)
    ctx.budget = budget_results(ctx.system, otf=ctx.otf)
    write_budget_outputs(ctx.system, ctx.budget, ctx.out / "budget", otf=ctx.otf)
    progress("budget", 1, 1)


def _stage_scene(ctx: RunContext, progress: Progress) -> None:
    from satchain.report import run_figures
    from satchain.scene import load_layout

    sc = ctx.config.scene
    ctx.scene = load_layout(ctx.config.layout_source())
    ctx.truth = ctx.scene.truth(pixel_m=sc.pixel_m)
    (ctx.out / "images").mkdir(parents=True, exist_ok=True)
    from satchain.report._save import write_text

    write_text(ctx.out / "images" / "scene.truth.json", json.dumps(ctx.truth, indent=1))
    overview = ctx.scene.render(pixel_m=sc.overview_pixel_m)
    run_figures.plot_scene_overview(overview, ctx.truth, sc.overview_pixel_m, ctx.out / "figures" / "fig1_scene.png")
    progress("scene", 1, 1)


def _stage_simulate(ctx: RunContext, progress: Progress) -> None:
    from satchain import io
    from satchain.engine.memory import check_simulation_memory
    from satchain.engine.sensor import sensor_from_system
    from satchain.engine.simulate import SimParams, Simulator
    from satchain.engine.sources import SceneSource

    c = ctx.config.simulation
    src = SceneSource(ctx.scene, pixel_m=ctx.config.scene.pixel_m)
    params = SimParams(far_margin_px=c.far_margin_px, border=c.border)
    ctx.simulator = sim = Simulator(
        ctx.system, input_pixel_m=src.pixel_m, input_shape=src.shape_px, params=params, otf=ctx.otf
    )
    check_simulation_memory(sim, focal_plane="coarse")
    coarse = sim.decimate(src, progress=lambda d, t: progress("simulate", d, t + 1))
    ctx.sensor = sensor_from_system(ctx.system)
    ctx.image = sim.run(src, sensor=ctx.sensor, units=c.units, noise=c.noise, seed=c.seed, coarse=coarse)
    ctx.focal_plane = sim.focal_plane(coarse, grid="coarse")  # D x smaller; exact band-limited samples
    s, d = ctx.system, ctx.out / "images"
    meta = {"units": c.units, "noise": c.noise, "seed": c.seed, "system": s.name, "gsd_alt_m": s.gsd_alt_m}
    bits = ctx.sensor.bit_depth
    io.write_simulated(
        d / "simulated.tif", ctx.image, units=c.units, bit_depth=bits, pixel_m=s.gsd_act_m, metadata=meta
    )
    fp_pixel = src.pixel_m * sim.D
    io.write_tiff(
        d / "focal_plane.tif",
        ctx.focal_plane.astype(np.float32),
        pixel_m=fp_pixel,
        metadata={"units": "scene reflectance filtered by the optics and motion", "system": s.name},
    )
    io.write_png(d / "focal_plane.png", io.preview_uint8(ctx.focal_plane), pixel_m=fp_pixel)
    progress("simulate", len(sim.tiles) + 1, len(sim.tiles) + 1)


def _stage_measure(ctx: RunContext, progress: Progress) -> None:
    from satchain.measure.auto import measure_auto

    s = ctx.system
    ctx.measured = measure_auto(ctx.image, ctx.truth, pixel_m=s.gsd_act_m).to_dict()
    progress("measure", 1, 1)


def _stage_compare(ctx: RunContext, progress: Progress) -> None:
    from satchain.report.compare import compare_all

    ctx.comparison = compare_all(ctx)
    progress("compare", 1, 1)


def _stage_report(ctx: RunContext, progress: Progress) -> None:
    from satchain.report import html, run_figures
    from satchain.report._save import write_text

    run_figures.write_run_figures(ctx)
    results = ctx.comparison["results"]
    write_text(ctx.out / "results.json", json.dumps(results, indent=1, default=_json_default))
    html.write_report(ctx, ctx.out / "report.html")
    progress("report", 1, 1)


def _json_default(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def _manifest(ctx: RunContext) -> dict[str, Any]:
    import matplotlib
    import scipy

    import satchain

    return {
        "satchain_version": satchain.__version__,
        "config": ctx.config.to_dict(),
        "system": ctx.system.to_dict() if ctx.system is not None else None,
        "seed": ctx.config.simulation.seed,
        "versions": {
            "python": platform.python_version(),
            "numpy": np.__version__,
            "scipy": scipy.__version__,
            "matplotlib": matplotlib.__version__,
        },
        "platform": platform.platform(),
        "timings_s": ctx.timings_s,
        "reproduce": "satchain run --config config.toml -o DIR  (config.toml is beside this manifest)",
    }


def _check_out_dir(out: Path) -> None:
    from satchain._safety import check_run_dir, clean_stale

    check_run_dir(out)  # only a missing, empty or satchain-marked directory may be replaced
    clean_stale(out)  # staging / old folders of killed runs


def run_pipeline(config: RunConfig, out_dir: str | Path, *, progress: Progress | None = None) -> dict[str, Any]:
    """Run every stage into ``out_dir`` (atomically replaced); return ``results.json``'s content."""
    out = Path(out_dir).resolve()
    _check_out_dir(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.staging-", dir=out.parent))
    _claim_run_dir(staging)
    report = progress or (lambda stage, done, total: None)
    ctx = RunContext(config=config, out=staging, timings_s={})
    try:
        stages = (_stage_budget, _stage_scene, _stage_simulate, _stage_measure, _stage_compare, _stage_report)
        for name, fn in zip(STAGES, stages, strict=True):
            t0 = time.perf_counter()
            fn(ctx, report)
            ctx.timings_s[name] = round(time.perf_counter() - t0, 3)
        from satchain.report._save import write_text
        from satchain.runconfig import config_to_toml

        write_text(staging / "config.toml", config_to_toml(config))
        write_text(staging / MANIFEST, json.dumps(_manifest(ctx), indent=1, default=_json_default))
        _swap_in(staging, out)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return ctx.comparison["results"]


def _claim_run_dir(directory: Path, *, marker: bool = True) -> None:
    from satchain._safety import claim, write_run_marker

    claim(directory)
    if marker:
        write_run_marker(directory)


def _swap_in(staging: Path, out: Path) -> None:
    """Replace ``out`` by ``staging`` with two renames; the old results are removed only afterwards."""
    old = None
    if out.exists():
        old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=out.parent))
        os.rmdir(old)
        _claim_run_dir(out, marker=False)  # owned by this process from before it is renamed
        os.replace(out, old)
    try:
        os.replace(staging, out)
    except BaseException:
        if old is not None:
            os.replace(old, out)
        raise
    if old is not None:
        with contextlib.suppress(OSError):
            shutil.rmtree(old)
