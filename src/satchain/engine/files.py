"""File to file: the satellite image of a scene file or an image file, written as a GeoTIFF (``satchain simulate``).

:func:`simulate_file` is what the ``satchain simulate`` command does, as a library function: read the ground
truth (a scene layout, ``"paper"``, or an image of reflectance), plan the simulation for the system, refuse
what cannot fit in memory or on disk up front, run it in memory -- or streamed through a coarse grid on disk
when the full frame does not fit (:mod:`satchain.engine.stream`) -- and write the image (with its ``.png``
preview) and, on request, the focal-plane image, atomically. The command line only parses its options and
prints what :class:`SimulatedFile` reports.

Examples
--------
>>> import tempfile
>>> from satchain import load_preset
>>> with tempfile.TemporaryDirectory() as d:
...     r = simulate_file("paper", Path(d) / "sim.tif", load_preset("ankarasat3"), scene_pixel_m=2.0,
...                       units="reflectance", noise=False)
>>> r.shape_px, r.streamed, r.preview.name
((612, 408), False, 'sim.png')
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from satchain._safety import (
    check_disk,
    check_distinct_paths,
    check_output_files,
    check_sidecars,
    clean_stale,
    memory_limit_bytes,
)
from satchain._validate import check_choice
from satchain.engine.georaster import _decimate, check_scales
from satchain.engine.memory import check_simulation_memory
from satchain.engine.raster_input import MIN_INPUT_PX
from satchain.engine.sensor import OUTPUT_UNITS, sensor_from_system
from satchain.engine.simulate import Simulator
from satchain.engine.stream import choose_streamed
from satchain.errors import ConfigError
from satchain.io.images import GDAL_SUFFIXES, committed_together

if TYPE_CHECKING:
    from satchain.config.system import ImagingSystem
    from satchain.engine.sensor import SensorModel
    from satchain.engine.sources import SceneSource
    from satchain.scene import Scene

__all__ = [
    "IMAGE_SUFFIXES",
    "REFLECTANCE_RANGE",
    "SimulatedFile",
    "check_case",
    "ground_truth_source",
    "simulate_file",
]

#: Inputs with these suffixes are images of reflectance; any other input is a scene (``"paper"`` or a layout).
IMAGE_SUFFIXES = (*GDAL_SUFFIXES, ".png", ".npy")
#: Reflectance an image input may hold after scaling (glints above 1 allowed; 255 or 65535 are not reflectance).
REFLECTANCE_RANGE = (-0.5, 4.0)

Progress = Callable[[str, int, int], None]


@dataclass(frozen=True)
class SimulatedFile:
    """What :func:`simulate_file` wrote: ``path`` (the image, ``shape_px`` rows x cols in ``units``) and its
    ``preview`` (.png), ``focal_plane_path`` with its sample size ``focal_plane_pixel_m`` (None when not asked
    for), whether the image was ``streamed`` through a coarse grid on disk, the ``metadata`` stored in it, its
    band ``count`` and, for a raster input, its ``crs`` and affine ``transform`` (the input's, at the GSD)."""

    path: Path
    preview: Path
    shape_px: tuple[int, int]
    units: str
    streamed: bool
    focal_plane_path: Path | None
    focal_plane_pixel_m: float | None
    metadata: Mapping[str, Any]
    count: int = 1
    crs: Any = None
    transform: Any = None


def ground_truth_source(
    input_: str | os.PathLike,
    *,
    pixel_m: float | None = None,
    input_scale: float | None = None,
    names: Mapping[str, str] | None = None,
) -> tuple[SceneSource, Scene | None]:
    """The ground truth of ``input_``: an image of reflectance (``IMAGE_SUFFIXES``; ``input_scale`` turns its
    values into reflectance) or a scene (``"paper"`` or a layout file, rendered exactly at ``pixel_m``).

    Returns the source and the scene (None for an image); ``names`` as in :func:`simulate_file`.

    Examples
    --------
    >>> src, scene = ground_truth_source("paper", pixel_m=2.0)
    >>> src.shape_px, src.pixel_m, type(scene).__name__
    ((150, 100), 2.0, 'Scene')
    """
    from satchain.engine.sources import SceneSource
    from satchain.scene import ImageScene, load_layout

    name = dict(names or {}).get
    if Path(input_).suffix.lower() in IMAGE_SUFFIXES:
        img = ImageScene(input_, pixel_m=pixel_m, scale=input_scale, valid_range=REFLECTANCE_RANGE)
        _check_not_too_dark(img, input_, input_scale is None)
        return SceneSource(img), None
    if input_scale is not None:
        raise ConfigError(
            f"{name('input_scale', 'input_scale')} {input_scale:g}: applies to image inputs only, not to scene "
            f"{str(input_)!r}"
        )
    sc = load_layout(input_)
    return SceneSource(sc, pixel_m=pixel_m), sc


def _check_not_too_dark(img, input_, default: bool, n: int = 4, side: int = 256) -> None:
    """The rule of :func:`satchain.engine.raster_input.check_not_too_dark` on a fixed sample of the image (``n x n``
    windows of ``side`` px spread evenly, or the whole image), before any work."""
    from satchain.engine.raster_input import check_not_too_dark

    rows, cols = img.shape_px()
    ys = np.unique(np.linspace(0, max(rows - side, 0), n).astype(int))
    xs = np.unique(np.linspace(0, max(cols - side, 0), n).astype(int))
    lo, hi = np.inf, -np.inf
    for y in ys:
        for x in xs:
            v = img.render((int(y), int(x), min(side, rows), min(side, cols))).astype(np.float64)
            lo, hi = min(lo, float(v.min())), max(hi, float(v.max()))
    check_not_too_dark(f"image = {str(input_)!r}:", lo, hi, img.scale, default)


def _check_options(units: str, noise: bool, seed: int, fp_grid: str, name: Callable[[str], str]) -> None:
    check_choice(name("units"), units, OUTPUT_UNITS)
    check_choice(name("focal_plane_grid"), fp_grid, ("input", "coarse"))
    if not isinstance(noise, (bool, np.bool_)):
        raise ConfigError(f"{name('noise')} = {noise!r}: must be True or False")
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ConfigError(f"{name('seed')} {seed!r}: must be an integer >= 0")


def simulate_file(
    input_: str | os.PathLike,
    out: str | os.PathLike,
    system: ImagingSystem,
    *,
    scene_pixel_m: float | None = None,
    input_scale: float | None = None,
    units: str = "dn",
    noise: bool = True,
    seed: int = 0,
    focal_plane: str | os.PathLike | None = None,
    focal_plane_grid: str = "input",
    scheduler: str | None = None,
    progress: Progress | None = None,
    notify: Callable[[str], None] | None = None,
    names: Mapping[str, str] | None = None,
    band: int | None = None,
) -> SimulatedFile:
    """Simulate the satellite image of a scene or an image file and write it (a GeoTIFF and a .png preview).

    Parameters
    ----------
    input_ : str or path
        ``"paper"``, a scene layout (.toml / .json), or an image of reflectance: a GDAL raster (GeoTIFF, COG,
        JP2, NITF, VRT: :data:`satchain.io.images.GDAL_SUFFIXES`), a PNG or an NPY. A GDAL raster goes through
        :func:`satchain.engine.georaster.simulate_raster`: every band (or ``band``), its georeference, nodata
        and scale kept, written as a Cloud-Optimized GeoTIFF.
    out : path
        The output TIFF; its ``.png`` preview is written beside it.
    system : ImagingSystem
    scene_pixel_m : float, optional
        Ground pixel size of the input (m): a scene is rendered at it (default: the layout's); an image
        without a pixel size in its metadata needs it.
    input_scale : float, optional
        Multiply image values by this to get reflectance (default: integer images / (2^bits - 1)).
    units : {"dn", "electrons", "radiance", "reflectance"}
    noise : bool
        Photon, dark and read noise and quantisation (off: deterministic).
    seed : int
        Noise seed (>= 0); the noise does not depend on the tiling.
    focal_plane : path, optional
        Also write the focal-plane image (input reflectance filtered by optics and motion) there, on the
        input grid (``focal_plane_grid="input"``, exact) or every D-th input pixel (``"coarse"``).
    scheduler : str, optional
        A Dask scheduler address, or ``"local"``, for the first stage.
    progress : callable, optional
        ``progress(stage, done, total)``; ``stage`` is a description such as ``"simulating 800x600 px"``.
    notify : callable, optional
        ``notify(message)``: what the user should know before the work starts (the streamed path's plan).
    names : mapping, optional
        How to name the parameters in error messages (the command line passes its option names, e.g.
        ``{"out": "-o", "seed": "--seed"}``).
    band : int, optional
        Only this band (1-based) of a multiband raster (default: every band).

    Returns
    -------
    SimulatedFile

    Raises
    ------
    ConfigError, InputError, ResourceLimitError
        Before anything is written: a bad option, an output that is an input or a directory, a ground truth
        under 8 px a side, or work that does not fit in memory or on disk.
    """
    name: Callable[[str], str] = (lambda k: dict(names).get(k, k)) if names else (lambda k: k)
    _check_options(units, noise, seed, focal_plane_grid, name)
    check_scales(scene_pixel_m, input_scale, name)
    out, fp_path = Path(out), (None if focal_plane is None else Path(focal_plane))
    _check_paths(input_, out, fp_path, name)
    if Path(input_).suffix.lower() in GDAL_SUFFIXES:  # georeference, nodata and bands kept (focal plane too)
        from satchain.engine.georaster import simulate_raster

        r = simulate_raster(input_, out, system, band=band, scene_pixel_m=scene_pixel_m, input_scale=input_scale,
                            units=units, noise=noise, seed=seed, scheduler=scheduler, progress=progress,
                            notify=notify, names=names, focal_plane=fp_path,
                            focal_plane_grid=focal_plane_grid)  # fmt: skip
        assert r is not None  # not check_only: the result
        return SimulatedFile(out, r["preview"], r["shape_px"], units, r["streamed"], fp_path,
                             r["focal_plane_pixel_m"], r["metadata"], r["count"], r["crs"], r["transform"])  # fmt: skip
    if band is not None:
        raise ConfigError(f"{name('band')} {band!r}: applies to a GDAL raster input (one of "
                          f"{', '.join(GDAL_SUFFIXES)})")  # fmt: skip
    src, scene = ground_truth_source(input_, pixel_m=scene_pixel_m, input_scale=input_scale, names=names)
    sim, streamed = _plan(system, src, focal_plane_grid if fp_path is not None else None, seed)
    if min(src.shape_px) < MIN_INPUT_PX:
        raise ConfigError(
            f"{name('input')} {str(input_)!r} at {src.pixel_m:g} m per pixel is only {src.shape_px[0]} x "
            f"{src.shape_px[1]} px; a ground truth needs at least {MIN_INPUT_PX} px a side: check "
            f"{name('scene_pixel_m')}"
        )
    if scene is not None:  # a layout rendered at src.pixel_m: items finer than the raster resolves are named
        from satchain.scene.layout import check_scene_pixel

        given = "the layout's pixel_m" if scene_pixel_m is None else name("scene_pixel_m")
        check_scene_pixel(scene, src.pixel_m, name=given)
    out.parent.mkdir(parents=True, exist_ok=True)
    meta = {"system": system.name, "seed": int(seed), "noise": bool(noise), "gsd_act_m": system.gsd_act_m,
            "gsd_alt_m": system.gsd_alt_m, "input": str(input_), "input_pixel_m": src.pixel_m}  # fmt: skip
    sensor = sensor_from_system(system) if (units != "reflectance" or noise) else None
    bits = sensor.bit_depth if sensor is not None else system.detector.bit_depth
    run: dict[str, Any] = dict(sensor=sensor, units=units, noise=bool(noise), seed=int(seed), bits=bits, meta=meta)
    report = progress or (lambda stage, done, total: None)
    if streamed:
        with committed_together():  # the image and its preview
            shape = _simulate_streamed(sim, src, out, scheduler=scheduler, progress=report, notify=notify, **run)
        return SimulatedFile(out, out.with_suffix(".png"), shape, units, True, None, None, meta)
    coarse = _decimate(sim, src, scheduler, f"simulating {src.shape_px[0]}x{src.shape_px[1]} px", report)
    with committed_together():  # the image, its preview and the focal plane
        shape, fp_pixel = _write_in_memory(sim, src, coarse, out, fp_path, focal_plane_grid, **run)
    return SimulatedFile(out, out.with_suffix(".png"), shape, units, False, fp_path, fp_pixel, meta)


def check_case(system: ImagingSystem, src: SceneSource, *, names: Mapping[str, str] | None = None) -> None:
    """What :func:`simulate_file` checks of ``system`` on the ground truth ``src`` before it writes anything
    (the ground truth's size in detector pixels, memory); a sweep checks every case with it first."""
    name: Callable[[str], str] = (lambda k: dict(names).get(k, k)) if names else (lambda k: k)
    _plan(system, src, None)
    if min(src.shape_px) < MIN_INPUT_PX:
        raise ConfigError(
            f"{name('input')} at {src.pixel_m:g} m per pixel is only {src.shape_px[0]} x {src.shape_px[1]} px; a "
            f"ground truth needs at least {MIN_INPUT_PX} px a side: check {name('scene_pixel_m')}"
        )


def _check_paths(input_: str | os.PathLike, out: Path, fp_path: Path | None, name: Callable[[str], str]) -> None:
    """Outputs are files, never an input or each other, and the preview replaces only a satchain file."""
    in_file = input_ if Path(input_).exists() else None
    check_output_files({name("out"): out, name("focal_plane"): fp_path})
    preview = {f"{name('out')} (preview)": out.with_suffix(".png")}
    check_distinct_paths({name("out"): out, **preview, name("focal_plane"): fp_path}, {name("input"): in_file})
    check_sidecars(preview)  # a user's .png of that name is not replaced


def _plan(system: ImagingSystem, src: SceneSource, fp_grid: str | None, seed: int = 0) -> tuple[Simulator, bool]:
    """The simulator and whether it streams; the full-frame path is refused up front when it cannot fit."""
    sim = Simulator(system, input_pixel_m=src.pixel_m, input_shape=src.shape_px, motion_seed=seed)
    streamed = choose_streamed(sim, focal_plane=fp_grid)
    if not streamed:
        check_simulation_memory(sim, focal_plane=fp_grid)
        sim.check_frame()
    return sim, streamed


def _write_in_memory(sim: Simulator, src: SceneSource, coarse: np.ndarray, out: Path, fp_path: Path | None,
                     fp_grid: str, *, sensor: SensorModel | None, units: str, noise: bool, seed: int, bits,
                     meta: dict[str, Any]) -> tuple[tuple[int, int], float | None]:  # fmt: skip
    """The second stage in memory; write the image and the focal-plane image. Returns the image's shape and
    the focal-plane sample size (None without one)."""
    from satchain.io import images as io

    s = sim.system
    img = sim.run(src, sensor=sensor, units=units, noise=noise, seed=seed, coarse=coarse)
    io.write_simulated(out, img, units=units, bit_depth=bits, pixel_m=s.gsd_act_m, metadata=meta)
    if fp_path is None:
        return (int(img.shape[0]), int(img.shape[1])), None
    fp_path.parent.mkdir(parents=True, exist_ok=True)
    fp = sim.focal_plane(coarse, grid=fp_grid)
    fp_pixel = src.pixel_m * (sim.D if fp_grid == "coarse" else 1)
    fp_meta = {"units": "input (reflectance) filtered by the optics and motion", "system": s.name, "grid": fp_grid}
    io.write_tiff(fp_path, fp.astype(np.float32), pixel_m=fp_pixel, metadata=fp_meta)
    return (int(img.shape[0]), int(img.shape[1])), fp_pixel


def _simulate_streamed(sim: Simulator, src: SceneSource, out: Path, *, sensor: SensorModel | None, units: str,
                       noise: bool, seed: int, bits, meta: dict[str, Any], scheduler: str | None, progress: Progress,
                       notify: Callable[[str], None] | None) -> tuple[int, int]:  # fmt: skip
    """For an input whose coarse frame does not fit in memory: the coarse grid on disk beside ``out``, stage 2
    tile by tile, the image written band by band (:mod:`satchain.engine.stream`). Returns the image's shape."""
    from satchain.engine.stream import coarse_store, stream_bytes, stream_tile_px, write_streamed
    from satchain.io.images import simulated_dtype

    ny, nx = sim.n_coarse
    oy, ox = sim.output_shape
    image_bytes = float(oy) * ox * simulated_dtype(units, bits).itemsize
    check_disk(4.0 * ny * nx + image_bytes, [out], f"streaming {sim.input_shape[0]} x {sim.input_shape[1]} input px")
    clean_stale(out)  # scratch folders of killed runs
    t, m = stream_tile_px(sim), sim.params.stream_margin_px
    if notify is not None:
        notify(
            f"streamed: the full-frame path would exceed the memory limit ({memory_limit_bytes() / 2**30:.1f} GiB); "
            f"the coarse grid ({ny} x {nx}, {4.0 * ny * nx / 2**30:.2f} GiB) goes to disk beside {out}, the image "
            f"is formed in {t} x {t} px tiles with {m} px margins (about {stream_bytes(sim) / 2**30:.2f} GiB of "
            "memory)"
        )
    with coarse_store(sim, out.parent, prefix=f".{out.name}.staging-") as coarse:
        _decimate(sim, src, scheduler, f"stage 1: {sim.input_shape[0]}x{sim.input_shape[1]} px", progress, out=coarse)
        stage = f"stage 2: {oy}x{ox} px in {t}-px tiles"
        write_streamed(
            out,
            sim,
            coarse,
            sensor=sensor,
            units=units,
            noise=noise,
            seed=seed,
            bit_depth=bits,
            pixel_m=sim.system.gsd_act_m,
            metadata=meta,
            progress=lambda done, total: progress(stage, done, total),
        )
    n_bands = -(-oy // t)
    progress(stage, n_bands, n_bands)  # the last band's report can be lost when the TIFF writer stops early
    return int(oy), int(ox)
