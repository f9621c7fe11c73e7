"""Imagery in, imagery out: the satellite image of a georeferenced raster, every band, as a Cloud-Optimized GeoTIFF
in the input's CRS (what ``satchain simulate`` does with a GDAL raster).

Geometry
    Output pixel (row i, column j) is the detector pixel whose pitch cell covers the input pixels
    ``[i k_y, (i+1) k_y) x [j k_x, (j+1) k_x)`` (``k = GSD / input pixel``: the engine's grid, phase 0, see
    :class:`satchain.engine.tiling.AxisSampling`). Its transform is the input's composed with that scale,
    ``T_out = T_in * Affine.scale(k_x, k_y)``: the pixel size is the GSD (ACT along the rows, ALT down the
    columns), the origin is the input's (exactly: within one output pixel), a rotation is kept, the CRS is the
    input's. Under pushbroom geometry (a drift: Earth rotation, line-rate error; yaw steering) it is the input's
    composed with the image's mean map instead (:func:`image_transform`: the inverse of
    :func:`satchain.engine.yaw.image_affine`, turned, sheared and scaled as the image is), so every output pixel
    lies over the ground it images; the description then says ``georeference = "image_map"`` and the file is
    read back with the GSD as its pixel size. The output covers the whole output pixels that fit inside the input.
Nodata
    Invalid input pixels (the nodata value, an internal mask, alpha 0, NaN) are replaced, before the optics, by
    one value per band: the mean of the band's valid pixels from a decimated read (a constant, so the image
    does not depend on the tiling). Every output pixel whose pitch cell touches an invalid input pixel is
    nodata: NaN for float units; for DN the largest value of the file type when the camera's bit depth leaves
    it unused (12-bit DN in uint16: 65535), else 0 (valid DN are then at least 1). Valid output pixels within
    the PSF's reach of a nodata area see the fill value through the PSF's tails.
Bands
    Every data band goes through the chain (an alpha band is the mask, not a band); band i uses
    ``system.for_band(i)`` (its ``[[bands]]`` wavelengths), else the system's own optics. Band i's noise seed
    is ``seed`` for band 1 and a :class:`numpy.random.SeedSequence` of ``(seed, i)`` for the others.
Memory
    The input is read by windows; the work runs in memory when its estimate fits ``memory_bytes`` (default:
    :data:`WORK_BYTES` or the machine's limit if lower), else streamed (the coarse grid on disk, stage 2 in
    tiles sized to fit), so a 20000^2 input needs well under 2 GB (``benchmarks/bench_georaster.py``). Each band
    is written by windows into a tiled staging GeoTIFF, which GDAL's COG driver turns into the output
    (DEFLATE, 512-px tiles, averaged overviews). The image, its preview and the focal plane are committed
    together (:func:`satchain.io.images.committed_together`): an error or an interruption replaces none of them.
Focal plane
    ``focal_plane``: also the focal-plane image (every band; float32 reflectance, in memory only) as a GeoTIFF
    in the input's CRS. On the input grid its transform is the input's; on the coarse grid (every D-th pixel)
    sample (j, i) is the D x D input block it is centred on, so its transform is ``T_in * Affine.scale(D)`` (the
    ground footprint of the samples). The input's invalid pixels are filled as for the image; a sample on an
    invalid input pixel (coarse: whose block touches one) is NaN, the file's nodata. Under yaw steering the
    focal plane is the ground turned as the image sees it (:meth:`Simulator.focal_plane`), and its transform is
    turned with it (:func:`focal_plane_transform`: about the pivot the engine turns the ground about).
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import shutil
import tempfile
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from satchain.engine.raster_input import (  # noqa: F401 (the input side, named here as before)
    MIN_INPUT_PX,
    PIXEL_RTOL,
    REFLECTANCE_RANGE,
    RasterBandSource,
    _band_source,
    _Plan,
    _plan_input,
    check_pixel_m,
    check_scales,
    invalid_cells,
)
from satchain.engine.tiling import Window
from satchain.errors import ConfigError, InputError, SatchainError
from satchain.io.images import committed_together

if TYPE_CHECKING:
    from satchain.engine.simulate import Simulator
    from satchain.engine.sources import SceneSource

__all__ = ["WORK_BYTES", "RasterBandSource", "check_scales", "invalid_cells", "output_transform", "simulate_raster"]

#: working memory a raster simulation plans for by default (the machine's limit when lower)
WORK_BYTES = 1.25 * 2**30
#: output rows per strip when the nodata cells are found (and the in-memory image written)
_STRIP_ROWS = 256
_PREVIEW_MAX_PX = 2048

Progress = Callable[[str, int, int], None]


def output_transform(transform, k: tuple[float, float]):
    """The output's affine transform: the input's ``transform`` with pixels ``k = (k_y, k_x)`` input pixels
    big (rows, columns), origin kept.

    Examples
    --------
    >>> from affine import Affine
    >>> t = output_transform(Affine(0.1, 0, 500000.0, 0, -0.1, 4e6), (4.9, 5.0))
    >>> round(t.a, 6), round(t.e, 6), t.c, t.f
    (0.5, -0.49, 500000.0, 4000000.0)
    """
    from affine import Affine

    return transform @ Affine.scale(float(k[1]), float(k[0]))


def image_transform(transform, sim, pixel_m: float):
    """The output's affine transform through the image's mean map: output pixel (corner coordinates) ->
    ground-truth metres (the inverse of :func:`satchain.engine.yaw.image_affine`, whose pixel centres are at
    integers) -> input pixels (``pixel_m`` each) -> the input's ``transform``. Under pushbroom geometry (yaw
    steering, Earth rotation, a line-rate error) it is turned, sheared and scaled as the image is; without any
    (no drift, no yaw: the map is the plain grid) it is :func:`output_transform` exactly."""
    from affine import Affine

    from satchain.engine.yaw import image_affine
    from satchain.tf.pushbroom import PushbroomTerms

    if PushbroomTerms(sim.system).drift_px is None and not sim.yaw_deg:
        return output_transform(transform, sim.k)
    to_ground_m = ~image_affine(sim) @ Affine.translation(-0.5, -0.5)
    return transform @ Affine.scale(1.0 / pixel_m) @ to_ground_m


def focal_plane_transform(transform, sim, pixel_m: float, d: int):
    """The focal plane's affine transform: its samples are ``d`` input pixels apart, of the ground turned as the
    image sees it (:func:`satchain.engine.yaw.rotated_frame`: ``B'(q) = B(P + M (q - P))`` about the pivot
    :func:`satchain.tf.pushbroom.yaw_pivot_m` that :func:`~satchain.engine.yaw.image_affine` turns about), so
    sample corner ``q`` (metres) lies over the ground ``P + M (q - P)``; without a yaw ``T_in * scale(d)``."""
    from affine import Affine

    from satchain.engine.yaw import grid_origin_m
    from satchain.tf.pushbroom import yaw_pivot_m

    if not sim.yaw_deg:
        return transform @ Affine.scale(d, d)
    a = sim.input_pixel_m
    pivot = yaw_pivot_m(sim.output_shape, (sim.xs.k * a, sim.ys.k * a), grid_origin_m(sim))  # rotated_frame's
    turn = Affine.rotation(-sim.yaw_deg, pivot=pivot)  # M (Affine.rotation is counter-clockwise in (x, y))
    return transform @ Affine.scale(1.0 / pixel_m) @ turn @ Affine.scale(d * a)


def _nodata_for(units: str, bits: int | None) -> tuple[np.dtype, float, float]:
    """(file dtype, nodata value, the lowest valid value) of the output; ``bits`` (the camera's ADC bits) is
    needed for DN only."""
    from satchain.io.images import simulated_dtype

    dt = simulated_dtype(units, bits)
    if dt.kind == "f":
        return dt, float("nan"), -np.inf
    assert bits is not None  # DN: formed by a sensor, whose bit depth _plan_case passes
    top = 2**bits - 1
    if top < np.iinfo(dt).max:
        return dt, float(np.iinfo(dt).max), 0.0
    return dt, 0.0, 1.0


def _seed(seed: int, band_index: int) -> int:
    if band_index == 0:
        return int(seed)
    return int(np.random.SeedSequence([int(seed), band_index]).generate_state(1, dtype=np.uint32)[0])


@contextlib.contextmanager
def _staging(out: Path) -> Iterator[Path]:
    from satchain._safety import claim

    d = Path(tempfile.mkdtemp(prefix=f".{out.name}.staging-", dir=out.parent))
    try:
        claim(d)
        yield d
    finally:
        shutil.rmtree(d, ignore_errors=True)


def simulate_raster(
    input_: str | os.PathLike,
    out: str | os.PathLike,
    system,
    *,
    band: int | None = None,
    scene_pixel_m: float | None = None,
    input_scale: float | None = None,
    units: str = "dn",
    noise: bool = True,
    seed: int = 0,
    memory_bytes: float | None = None,
    scheduler: str | None = None,
    progress: Progress | None = None,
    notify: Callable[[str], None] | None = None,
    names: Mapping[str, str] | None = None,
    check_only: bool = False,
    also_check: Sequence[tuple[Any, str | os.PathLike]] = (),
    focal_plane: str | os.PathLike | None = None,
    focal_plane_grid: str = "input",
) -> dict[str, Any] | None:
    """Simulate every band (or only ``band``) of a raster file and write the COG ``out`` (and its ``.png``
    preview); see the module docstring. Returns ``{"shape_px", "count", "streamed", "metadata", "preview"}``.
    Options and inputs are checked before anything is written; a failure leaves nothing under ``out``.
    ``check_only``: only those checks (the input, its values' sample, memory and disk); returns None.
    ``also_check``: ``(system, out)`` of other simulations of this input (a sweep's cases), whose checks that
    depend on the system are made too, before anything is written. ``focal_plane``: also write the focal-plane
    image there (see the module docstring); the result then holds its ``focal_plane_pixel_m``."""
    from satchain._safety import clean_stale
    from satchain.engine.sensor import sensor_from_system

    name: Callable[[str], str] = (lambda k: dict(names).get(k, k)) if names else (lambda k: k)
    path, out = Path(input_), Path(out)
    check_scales(scene_pixel_m, input_scale, name)
    plan = _plan_input(path, band, scene_pixel_m, name)
    if min(plan.shape) < MIN_INPUT_PX:
        raise ConfigError(
            f"{name('input')} {str(path)!r} at {plan.pixel_m:g} m per pixel is only {plan.shape[0]} x "
            f"{plan.shape[1]} px; a ground truth needs at least {MIN_INPUT_PX} px a side: check "
            f"{name('scene_pixel_m')}"
        )
    bands = [band] if band is not None else list(range(1, plan.count + 1))
    sources = [_band_source(plan, b, input_scale) for b in bands]
    fp_grid = None if focal_plane is None else focal_plane_grid
    try:
        for other, other_out in also_check:  # a sweep's other cases of this input: their system's checks alone
            try:
                _plan_case(plan, bands, sources, other, Path(other_out), units, noise, seed, memory_bytes, name,
                           fp_grid)  # fmt: skip
            except SatchainError as exc:
                raise type(exc)(f"case {Path(other_out).stem}: {exc}") from None
        job = _plan_case(plan, bands, sources, system, out, units, noise, seed, memory_bytes, name, fp_grid)
    except BaseException:
        for src in sources:
            src.close()
        raise
    systems, planned, sims, streamed, budget = job.systems, job.planned, job.sims, job.streamed, job.budget
    sensor, bits, dtype, nodata, lowest = job.sensor, job.bits, job.dtype, job.nodata, job.lowest
    sim0 = sims[0]
    transform = image_transform(plan.transform, sim0, plan.pixel_m)
    meta = {"system": system.name, "seed": int(seed), "noise": bool(noise), "gsd_act_m": system.gsd_act_m,
            "gsd_alt_m": system.gsd_alt_m, "input": str(path), "input_pixel_m": plan.pixel_m, "units": units,
            "bands": bands, "pixel_m": system.gsd_act_m,
            "wavelength_m": [s.optics.effective_wavelength_m for s in systems]}  # fmt: skip
    if units == "dn":
        assert bits is not None  # DN: formed by a sensor (_plan_case)
        meta["bit_depth"] = int(bits)
    if not math.isclose(system.gsd_act_m, system.gsd_alt_m, rel_tol=1e-9):
        meta["pixel_m_xy"] = [system.gsd_act_m, system.gsd_alt_m]
    if transform != output_transform(plan.transform, sim0.k):  # read back with the GSD as its pixel size
        meta["georeference"] = "image_map"
    if check_only:
        for src in sources:
            src.close()
        return None
    if notify is not None and streamed:
        notify(f"streamed: {plan.shape[0]} x {plan.shape[1]} px x {len(bands)} band(s) in {budget / 2**30:.2f} GiB: "
               f"the coarse grid goes to disk beside {out}, the image is formed in "
               f"{sims[0].params.stream_tile_px}-px tiles")  # fmt: skip
    out.parent.mkdir(parents=True, exist_ok=True)
    clean_stale(out)
    report = progress or (lambda stage, done, total: None)
    fp = None if focal_plane is None else _FocalPlane(Path(focal_plane), focal_plane_grid, plan, sim0, len(bands), meta)
    with committed_together(), _staging(out) as d:
        stage_tif = d / "stage.tif"
        with _open_staging(stage_tif, plan, sim0.output_shape, len(bands), dtype, nodata, transform, meta) as dst:
            for i, (b, sim, src, s) in enumerate(zip(bands, sims, sources, systems, strict=True)):
                sensor_b = sensor_from_system(s) if sensor is not None else None
                tag = f"band {b}/{plan.count}: " if len(bands) > 1 else ""
                write = _Writer(dst, i + 1, src, sim, dtype, nodata, lowest, bits)
                _form_band(sim, src, write, d, planned[i][1], tag, report, fp=fp, sensor=sensor_b, units=units,
                           noise=noise, seed=_seed(seed, i), scheduler=scheduler)  # fmt: skip
                dst.set_band_description(i + 1, plan.descriptions[b - 1] or f"band {b}")
                dst.update_tags(i + 1, wavelength_m=f"{s.optics.effective_wavelength_m:.6g}", input_band=str(b))
                src.close()
        _write_cog(stage_tif, out)
        preview = _write_preview(out, nodata)
        if fp is not None:
            fp.write()
    return {"shape_px": sim0.output_shape, "count": len(bands), "streamed": streamed, "metadata": meta,
            "preview": preview, "transform": transform, "crs": plan.crs,
            "focal_plane_pixel_m": None if fp is None else fp.pixel_m}  # fmt: skip


@dataclass(frozen=True)
class _Job:
    """What one system makes of a planned input: the band systems, their simulators (and whether they stream),
    the memory budget, the sensor and the output's DN bits, file type, nodata and lowest valid value."""

    systems: list
    planned: list
    sims: list
    streamed: bool
    budget: float
    sensor: Any
    bits: int | None
    dtype: np.dtype
    nodata: float
    lowest: float


def _plan_case(plan: _Plan, bands: list[int], sources: list[RasterBandSource], system, out: Path, units: str,
               noise: bool, seed: int, memory_bytes: float | None, name: Callable[[str], str],
               fp_grid: str | None = None) -> _Job:  # fmt: skip
    """Everything ``system`` needs checked before the input is simulated by it into ``out``: its bands, the
    output's disk, the simulators in the memory budget, an output pixel that is not nodata."""
    from satchain._safety import check_disk, memory_limit_bytes
    from satchain.engine.sensor import sensor_from_system

    if system.bands and len(system.bands) != plan.count:
        raise ConfigError(f"{name('input')} {str(plan.path)!r} has {plan.count} bands but the system "
                          f"{system.name!r} describes {len(system.bands)} ([[bands]]); they must match")  # fmt: skip
    systems = [system.for_band(b - 1) for b in bands]
    _check_output_disk(plan, system, len(bands), units, out)  # before planning, which grows with the input
    budget = min(float(memory_bytes or WORK_BYTES), float(memory_limit_bytes()))
    planned = [_simulator(s, plan, budget, seed, fp_grid) for s in systems]  # one line-of-sight motion for every band
    sims, streamed = [p[0] for p in planned], any(p[1] for p in planned)
    for b, src, sim in zip(bands, sources, sims, strict=True):
        _check_some_valid(src, sim, b, name)
    sensor = sensor_from_system(systems[0]) if (units != "reflectance" or noise) else None
    bits = sensor.bit_depth if sensor is not None else None  # an ADC range only where a sensor forms DN
    dtype, nodata, lowest = _nodata_for(units, bits)
    oy, ox = sims[0].output_shape
    scratch = max(4.0 * s.n_coarse[0] * s.n_coarse[1] for s in sims) if streamed else 0.0
    check_disk(scratch + 2.0 * len(bands) * oy * ox * dtype.itemsize, [out], f"simulating {str(plan.path)!r}")
    return _Job(systems, planned, sims, streamed, budget, sensor, bits, dtype, nodata, lowest)


def _check_some_valid(src: RasterBandSource, sim, band: int, name: Callable[[str], str]) -> None:
    """Refuse a band whose every output pixel would be nodata (each pitch cell touches an invalid input pixel):
    read strip by strip, it stops at the first strip that holds a valid output pixel."""
    if not src.masked:
        return
    ny = sim.output_shape[0]
    for r0 in range(0, ny, _STRIP_ROWS):
        bad = src.invalid_cells(sim, (r0, min(r0 + _STRIP_ROWS, ny)))
        if bad is None or not bad.all():
            return
    ky, kx = sim.k
    raise InputError(
        f"{name('input')} {str(src.path)!r}: band {band}: every output pixel would be nodata: each output pixel "
        f"covers {kx:.3g} x {ky:.3g} input pixels and an output pixel is valid only where all of them are, but no "
        f"such cell of valid data exists (the valid data is narrower than one output pixel of "
        f"{sim.system.gsd_act_m:g} x {sim.system.gsd_alt_m:g} m); nothing was written"
    )


def _check_output_disk(plan: _Plan, system, n_bands: int, units: str, out: Path) -> None:
    """Refuse, from the sizes alone, an output (staging and COG) larger than the free disk: a header that
    claims 10^12 px is refused at once, before a plan whose cost grows with the input is made."""
    from satchain._safety import check_disk
    from satchain.io.images import simulated_dtype

    (iy, ix), px = plan.shape, plan.pixel_m
    oy, ox = int(iy * px / system.gsd_alt_m), int(ix * px / system.gsd_act_m)
    size = simulated_dtype(units, system.detector.bit_depth).itemsize
    check_disk(2.0 * n_bands * oy * ox * size, [out], f"image = {str(plan.path)!r}: simulating its {iy} x {ix} px "
               f"({iy * ix / 1e9:.3g} Gpx at {px:g} m) into {oy} x {ox} px x {n_bands} band(s)",
               fix="crop or resample it first (e.g. gdal_translate -srcwin, gdalwarp -tr)")  # fmt: skip


def _decimate(sim: Simulator, src: SceneSource, scheduler: str | None, stage: str, report: Progress, **kw):
    """The first stage (the coarse grid), in process or on a Dask cluster."""

    def update(done: int, total: int) -> None:
        report(stage, done, total)

    if scheduler is not None:
        from satchain.engine.distributed import decimate_distributed

        return decimate_distributed(sim, src, scheduler=scheduler, progress=update, **kw)
    return sim.decimate(src, progress=update, **kw)


def _in_memory(sim, budget: float) -> bool:
    """Whether the whole band's work fits ``budget`` in memory (else it streams)."""
    from satchain.engine.memory import simulation_bytes

    return simulation_bytes(sim) <= budget and sim.frame_bytes <= sim.params.max_frame_bytes


def _simulator(system, plan: _Plan, budget: float, seed: int = 0, fp_grid: str | None = None):
    """``(simulator, streamed)`` of a band: in memory when its estimate fits ``budget``, else streamed in tiles
    that fit; with a focal plane (``fp_grid``) in memory, or refused when it cannot fit."""
    from satchain.engine.simulate import SimParams, Simulator
    from satchain.engine.stream import stream_bytes
    from satchain.errors import ResourceLimitError

    sim = Simulator(system, input_pixel_m=plan.pixel_m, input_shape=plan.shape, motion_seed=seed)
    if fp_grid is not None:  # the focal plane is a full-frame product
        from satchain.engine.memory import check_simulation_memory

        check_simulation_memory(sim, focal_plane=fp_grid)
        sim.check_frame()
        return sim, False
    if _in_memory(sim, budget):
        return sim, False
    if min(sim.k) < 1:  # an output finer than the input is not a streaming job: in memory, if it fits at all
        from satchain.engine.memory import check_simulation_memory

        check_simulation_memory(sim)
        sim.check_frame()
        return sim, False
    from satchain._safety import memory_limit_bytes

    # the far field of the streamed path grows with the frame: a scene too big for the planned budget may use
    # the machine's limit before it is refused
    for b in sorted({budget, max(budget, float(memory_limit_bytes()))}):
        for t in (2048, 1024, 512, 256, 128):
            p = SimParams(stream_tile_px=t, max_tile_bytes=int(min(640 * 2**20, b / 3)))
            s = Simulator(system, input_pixel_m=plan.pixel_m, input_shape=plan.shape, params=p, otf=sim.otf,
                          motion_seed=seed)  # fmt: skip
            if stream_bytes(s) <= b:
                return s, True
        budget = b
    (iy, ix), (oy, ox) = plan.shape, sim.output_shape
    raise ResourceLimitError(f"image = {str(plan.path)!r}: simulating its {iy} x {ix} px ({iy * ix / 1e9:.3g} Gpx at "
                             f"{plan.pixel_m:g} m) into {oy} x {ox} px needs more than {budget / 2**30:.2f} GiB of "
                             "memory even streamed in 128-px tiles: crop or resample it first (e.g. gdal_translate "
                             "-srcwin, gdalwarp -tr); nothing was written")  # fmt: skip


class _Writer:
    """Writes output rows of one band into the staging dataset: DN rounded and clipped, nodata where the
    pitch cell touches an invalid input pixel (found in strips of :data:`_STRIP_ROWS` rows)."""

    def __init__(self, dst, index: int, src: RasterBandSource, sim, dtype, nodata: float, lowest: float,
                 bits: int | None):  # fmt: skip
        self.dst, self.index, self.src, self.sim = dst, index, src, sim
        self.dtype, self.nodata, self.lowest = np.dtype(dtype), nodata, lowest
        self.top: float | None = None  # DN only: float units have no ADC range
        if self.dtype.kind != "f":
            assert bits is not None  # DN: formed by a sensor, whose bit depth _plan_case passes
            self.top = 2.0**bits - 1
        self.n_nodata = 0

    def rows(self, r0: int, img: np.ndarray) -> None:
        from rasterio.windows import Window as RWindow

        for a in range(0, img.shape[0], _STRIP_ROWS):
            block = img[a : a + _STRIP_ROWS]
            if self.dtype.kind != "f":
                block = np.clip(np.round(block), max(self.lowest, 0.0), self.top)
            block = block.astype(self.dtype)
            bad = self.src.invalid_cells(self.sim, (r0 + a, r0 + a + block.shape[0]))
            if bad is not None:
                block[bad] = self.nodata
                self.n_nodata += int(bad.sum())
            win = RWindow(0, r0 + a, block.shape[1], block.shape[0])
            self.dst.write(block, self.index, window=win)


@contextlib.contextmanager
def _open_staging(path: Path, plan: _Plan, shape, count: int, dtype, nodata: float, transform, meta):
    from satchain.io.raster import _gdal_env, _rasterio

    rasterio = _rasterio()
    profile = dict(driver="GTiff", width=int(shape[1]), height=int(shape[0]), count=count, dtype=np.dtype(dtype).name,
                   crs=plan.crs, transform=transform, nodata=nodata, tiled=True, blockxsize=512, blockysize=512,
                   BIGTIFF="IF_SAFER")  # fmt: skip
    with _gdal_env(), rasterio.open(path, "w", **profile) as dst:
        dst.update_tags(TIFFTAG_IMAGEDESCRIPTION=json.dumps({"satchain": meta}))
        yield dst


def _form_band(sim, src, write: _Writer, scratch: Path, streamed: bool, tag: str, report: Progress, *, sensor,
               units: str, noise: bool, seed: int, scheduler: str | None, fp=None) -> None:  # fmt: skip
    """Both stages and the sensor for one band, in memory or streamed (stage 1 on a Dask ``scheduler`` when
    given); rows go to ``write``, the band's focal plane (in memory only) to ``fp``."""
    from satchain.engine.stream import FarField, coarse_store, stream_tile_px, stream_tiles

    def stage(text: str):
        return lambda done, total: report(f"{tag}{text}", done, total)

    (iy, ix), (ny, nx) = sim.input_shape, sim.output_shape
    if not streamed:
        coarse = _decimate(sim, src, scheduler, f"{tag}simulating {iy}x{ix} px", report)
        if fp is not None:
            fp.add(src, sim.focal_plane(coarse, grid=fp.grid))
        img = sim.form_image(coarse)
        del coarse
        if sensor is not None:
            img = sensor.convert(img, origin=(0, 0), units=units, noise=noise, seed=seed,
                                 block_px=sim.params.noise_block_px)  # fmt: skip
        write.rows(0, img)
        return
    t, m = stream_tile_px(sim), int(sim.params.stream_margin_px)
    with coarse_store(sim, scratch, prefix=".coarse-") as coarse:
        _decimate(sim, src, scheduler, f"{tag}stage 1: {iy}x{ix} px", report, out=coarse)
        far = FarField(sim, coarse, margin_px=m)
        rows_done = stage(f"stage 2: {ny}x{nx} px in {t}-px tiles")
        n = -(-ny // t)
        for j, r0 in enumerate(range(0, ny, t)):
            band = np.empty((min(t, ny - r0), nx), dtype=np.float64)
            tiles = stream_tiles(sim, coarse, rows=(r0, r0 + t), sensor=sensor, units=units, noise=noise, seed=seed,
                                 far=far)  # fmt: skip
            for _, c0, img in tiles:
                band[:, c0 : c0 + img.shape[1]] = img
            write.rows(r0, band)
            rows_done(j + 1, n)


def _write_cog(stage: Path, out: Path) -> None:
    """The staging GeoTIFF as a Cloud-Optimized GeoTIFF at ``out`` (atomically)."""
    from satchain.errors import SatchainIOError
    from satchain.io.images import atomic_path
    from satchain.io.raster import _gdal_env, _one_line, _rasterio

    _rasterio()
    import rasterio.shutil

    try:
        with atomic_path(out) as tmp, _gdal_env():
            rasterio.shutil.copy(str(stage), str(tmp), driver="COG", COMPRESS="DEFLATE", PREDICTOR="YES",
                                 BLOCKSIZE=512, OVERVIEW_RESAMPLING="AVERAGE", BIGTIFF="IF_SAFER")  # fmt: skip
    except Exception as exc:
        if isinstance(exc, (SatchainIOError, OSError)):
            raise
        raise SatchainIOError(f"-o {str(out)!r}: cannot write the COG: {_one_line(exc)}") from None


def _write_preview(out: Path, nodata: float) -> Path:
    """A PNG of band 1 beside ``out`` (from the COG's overviews; at most :data:`_PREVIEW_MAX_PX` a side)."""
    from satchain.io import images as io
    from satchain.io.images import staged
    from satchain.io.raster import open_raster

    with open_raster(staged(out), band=1) as r:  # the COG, committed with the preview
        values, valid = r.overview(_PREVIEW_MAX_PX)
        step = r.shape[1] / values.shape[1]
        pixel = r.pixel_m[0] * step if r.pixel_m else None
    v = values.astype(np.float64)
    ok = np.isfinite(v) & (valid if valid is not None else True)
    v[~ok] = np.median(v[ok]) if ok.any() else 0.0
    png = out.with_suffix(".png")
    io.write_png(png, io.preview_uint8(v), pixel_m=pixel)
    return png


class _FocalPlane:
    """The focal-plane images of the bands (see the module docstring), gathered in memory and written as one
    GeoTIFF at ``path``."""

    def __init__(self, path: Path, grid: str, plan: _Plan, sim, count: int, meta: Mapping[str, Any]):
        self.path, self.grid, self.plan, self.count = path, grid, plan, count
        self.bands: list[np.ndarray] = []
        d = int(sim.D) if grid == "coarse" else 1
        self.d, self.pixel_m = d, plan.pixel_m * d
        self.transform = focal_plane_transform(plan.transform, sim, plan.pixel_m, d)  # the samples' ground
        self.meta = {"units": "input (reflectance) filtered by the optics and motion", "system": meta["system"],
                     "grid": grid, "pixel_m": self.pixel_m, "input": meta["input"]}  # fmt: skip

    def add(self, src: RasterBandSource, image: np.ndarray) -> None:
        """One band's focal plane, NaN where it sits on invalid input."""
        a = image.astype(np.float32)
        valid = src.valid(Window(0, 0, *src.shape_px)) if src.masked else None
        if valid is not None and not valid.all():
            a[_blocks_invalid(valid, self.d, a.shape)] = np.nan
        self.bands.append(a)

    def write(self) -> None:
        from satchain.io.images import atomic_path
        from satchain.io.raster import _gdal_env, _rasterio

        rasterio = _rasterio()
        ny, nx = self.bands[0].shape
        profile = dict(driver="GTiff", width=nx, height=ny, count=len(self.bands), dtype="float32",
                       crs=self.plan.crs, transform=self.transform, nodata=float("nan"), tiled=True,
                       blockxsize=256, blockysize=256, compress="deflate", BIGTIFF="IF_SAFER")  # fmt: skip
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(self.path) as tmp, _gdal_env(), rasterio.open(tmp, "w", **profile) as dst:
            dst.update_tags(TIFFTAG_IMAGEDESCRIPTION=json.dumps({"satchain": self.meta}))
            for i, a in enumerate(self.bands):
                dst.write(a, i + 1)


def _blocks_invalid(valid: np.ndarray, d: int, shape: tuple[int, int]) -> np.ndarray:
    """True at the samples (``shape``; sample (j, i) = input block ``[d j, d j + d) x [d i, d i + d)``) that
    touch an invalid input pixel (beyond the input counts as valid: the image's fill)."""
    ny, nx = shape
    pad = np.ones((ny * d, nx * d), dtype=bool)
    h, w = min(valid.shape[0], ny * d), min(valid.shape[1], nx * d)
    pad[:h, :w] = valid[:h, :w]
    return ~pad.reshape(ny, d, nx, d).all(axis=(1, 3))  # type: ignore[return-value]  # an array: the stubs say bool | array
