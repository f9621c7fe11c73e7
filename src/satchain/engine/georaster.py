"""Imagery in, imagery out: the satellite image of a georeferenced raster, every band, as a Cloud-Optimized GeoTIFF
in the input's CRS (what ``satchain simulate`` does with a GDAL raster).

Geometry
    Output pixel (row i, column j) is the detector pixel whose pitch cell covers the input pixels
    ``[i k_y, (i+1) k_y) x [j k_x, (j+1) k_x)`` (``k = GSD / input pixel``: the engine's grid, phase 0, see
    :class:`satchain.engine.tiling.AxisSampling`). Its transform is the input's composed with that scale,
    ``T_out = T_in * Affine.scale(k_x, k_y)``: the pixel size is the GSD (ACT along the rows, ALT down the
    columns), the origin is the input's (exactly: within one output pixel), a rotation is kept, the CRS is the
    input's. The output covers the whole output pixels that fit inside the input.
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
    (DEFLATE, 512-px tiles, averaged overviews), written atomically.
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
from typing import Any

import numpy as np

from satchain.engine.tiling import Window
from satchain.errors import ConfigError, InputError, SatchainError

__all__ = ["WORK_BYTES", "RasterBandSource", "check_scales", "invalid_cells", "output_transform", "simulate_raster"]

#: working memory a raster simulation plans for by default (the machine's limit when lower)
WORK_BYTES = 1.25 * 2**30
#: reflectance an input may hold after scaling (as for every image input of ``satchain simulate``)
REFLECTANCE_RANGE = (-0.5, 4.0)
#: output rows per strip when the nodata cells are found (and the in-memory image written)
_STRIP_ROWS = 256
_PREVIEW_MAX_PX = 2048
#: a pixel size given for a raster that states its own agrees with it within this relative difference
PIXEL_RTOL = 1e-3

Progress = Callable[[str, int, int], None]


class RasterBandSource:
    """One band of a raster file as ground truth (the engine's ``read(window)``): reflectance ``(stored x
    scale + offset) x gain``, invalid pixels replaced by ``fill``. Picklable (reopened from the path)."""

    def __init__(self, path: str | os.PathLike, band: int, *, pixel_m: float, gain: float, offset: float = 0.0,
                 fill: float = 0.0, scaled: bool = False, check_finite: bool = False,
                 valid_range: tuple[float, float] | None = REFLECTANCE_RANGE):  # fmt: skip
        self.path, self.band, self.pixel_m = Path(path), int(band), float(pixel_m)
        self.gain, self.offset, self.fill, self.scaled = float(gain), float(offset), float(fill), bool(scaled)
        self.valid_range = valid_range
        self._reader = None
        r = self._open()
        self.shape_px = r.shape
        self.masked = r.has_mask or check_finite or r.dtype.kind == "f"

    def _open(self):
        if self._reader is None:
            from satchain.raster import open_raster

            self._reader = open_raster(self.path, band=self.band)
        return self._reader

    def values(self, window: Window) -> tuple[np.ndarray, np.ndarray | None]:
        """``(reflectance, valid)`` of a window (``valid`` None when every pixel of the band is valid)."""
        r = self._open()
        v = r.read(*window, scaled=self.scaled).astype(np.float64) * self.gain + self.offset
        if not self.masked:
            return v, None
        valid = np.isfinite(v)
        if r.has_mask:
            valid &= r.read_mask(*window)
        return v, valid

    def valid(self, window: Window) -> np.ndarray | None:
        """Validity of a window (the values are read only where they can be NaN)."""
        r = self._open()
        if not self.masked:
            return None
        if r.dtype.kind == "f":
            return self.values(window)[1]
        return r.read_mask(*window) if r.has_mask else None

    def read(self, window: Window) -> np.ndarray:
        v, valid = self.values(window)
        if valid is not None:
            v[~valid] = self.fill
        if self.valid_range is not None and v.size:
            lo, hi = float(v.min()), float(v.max())
            if lo < self.valid_range[0] or hi > self.valid_range[1]:
                raise InputError(
                    f"image = {str(self.path)!r}: band {self.band} values {lo:g}..{hi:g} (as reflectance, x "
                    f"{self.gain:g}) in window {tuple(window)} are not reflectance (allowed {self.valid_range[0]:g}"
                    f"..{self.valid_range[1]:g}); give --input-scale"
                )
        return v

    def invalid_cells(self, sim, rows: tuple[int, int]) -> np.ndarray | None:
        """See :func:`invalid_cells`."""
        return invalid_cells(self, sim, rows) if self.masked else None

    def __getstate__(self) -> dict:
        return {k: v for k, v in self.__dict__.items() if k != "_reader"} | {"_reader": None}

    def close(self) -> None:
        if self._reader is not None:
            self._reader.close()
            self._reader = None


def invalid_cells(src, sim, rows: tuple[int, int]) -> np.ndarray | None:
    """True at the output pixels of ``rows`` (all columns) whose pitch cell touches an invalid pixel of
    ``src`` (anything with ``shape_px`` and ``valid(window) -> bool array or None``); None when there is none."""
    (ry0, ry1), (cx0, cx1) = _cells(sim.ys, *rows), _cells(sim.xs, 0, sim.output_shape[1])
    a, b = int(ry0[0]), int(ry1[-1])
    valid = src.valid(Window(a, 0, b - a, src.shape_px[1]))
    if valid is None or valid.all():
        return None
    cs = np.zeros((b - a + 1, valid.shape[1]), dtype=np.int32)
    np.cumsum(~valid, axis=0, out=cs[1:])
    by_rows = cs[ry1 - a] - cs[ry0 - a]  # invalid pixels per output row's cell, per input column
    cs = np.zeros((by_rows.shape[0], by_rows.shape[1] + 1), dtype=np.int32)
    np.cumsum(by_rows, axis=1, out=cs[:, 1:])
    return (cs[:, cx1] - cs[:, cx0]) > 0


def _cells(axis, i0: int, i1: int) -> tuple[np.ndarray, np.ndarray]:
    """First and one-past-last input pixel that the pitch cells of output pixels ``i0 .. i1-1`` touch."""
    i = np.arange(i0, i1, dtype=np.float64)
    lo = np.floor(axis.phase_px + i * axis.k + 1e-9).astype(np.int64)
    hi = np.ceil(axis.phase_px + (i + 1) * axis.k - 1e-9).astype(np.int64)
    return lo, np.minimum(hi, axis.n_input)


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


@dataclass(frozen=True)
class _Plan:
    path: Path
    count: int
    shape: tuple[int, int]
    pixel_m: float
    crs: Any
    transform: Any
    descriptions: tuple[str | None, ...]
    meta: dict[str, Any]


def _plan_input(path: Path, band: int | None, scene_pixel_m: float | None, name: Callable[[str], str]) -> _Plan:
    from satchain._imagemeta import _gdal_meta
    from satchain.raster import open_raster

    with open_raster(path) as r:
        if band is not None and (isinstance(band, bool) or not isinstance(band, int) or not 1 <= band <= r.count):
            raise ConfigError(f"{name('band')} {band!r}: must be an integer in [1, {r.count}] ({str(path)!r} has "
                              f"{r.count} data band{'s' * (r.count > 1)})")  # fmt: skip
        meta = _gdal_meta(r)
        _check_grid(r, path, scene_pixel_m, name)
        own = _own_pixel_m(r, meta)
        if scene_pixel_m is None and r.pixel_m is None and own is not None:
            pixel_m = own
        elif scene_pixel_m is None:
            pixel_m = r.require_pixel_m(name("scene_pixel_m"))[0]
        else:
            pixel_m = _given_pixel_m(float(scene_pixel_m), own, path, name)
        transform = r.transform
        if not r.georeferenced:  # local metric grid, origin (0, 0), north up (as satchain's own TIFFs)
            from affine import Affine

            transform = Affine(pixel_m, 0.0, 0.0, 0.0, -pixel_m, 0.0)
        return _Plan(path, r.count, r.shape, pixel_m, r.crs, transform, r.descriptions, meta)


def check_scales(scene_pixel_m: float | None, input_scale: float | None, name: Callable[[str], str]) -> None:
    """Refuse a ground pixel size or an input scale that is not a finite number > 0 (a NaN pixel size has no
    output size; a zero or NaN scale makes every value 0 or NaN), naming the option."""
    from satchain._validate import check_positive, check_range

    if scene_pixel_m is not None:
        check_range(name("scene_pixel_m"), scene_pixel_m, 0.0, 1e6, lo_open=True)
    if input_scale is not None:
        check_positive(name("input_scale"), input_scale)


def _own_pixel_m(r, meta: Mapping[str, Any]) -> float | None:
    """The pixel size a raster states: its transform's, or satchain's tags of a local TIFF; None without one."""
    own = r.pixel_m[0] if r.pixel_m is not None else meta.get("pixel_m")
    return own if isinstance(own, float) else None


def check_pixel_m(path: str | os.PathLike, scene_pixel_m: float | None, name: Callable[[str], str]) -> None:
    """Refuse a ``scene_pixel_m`` that contradicts the pixel size the raster ``path`` states (see
    :func:`_given_pixel_m`), for the paths that read it without its georeference (``--focal-plane``)."""
    from satchain._imagemeta import _gdal_meta
    from satchain.raster import open_raster

    if scene_pixel_m is None:
        return
    with open_raster(path) as r:
        _given_pixel_m(float(scene_pixel_m), _own_pixel_m(r, _gdal_meta(r)), Path(path), name)


def _given_pixel_m(given: float, own: float | None, path: Path, name: Callable[[str], str]) -> float:
    """The pixel size to use when one is given: the file's where they agree (to :data:`PIXEL_RTOL`: the output's
    transform is the file's, so it stays exact), refused where they contradict; the given one without the file's."""
    if own is None:
        return given
    if not math.isclose(given, own, rel_tol=PIXEL_RTOL):
        raise ConfigError(f"{name('scene_pixel_m')} = {given:g}: contradicts {str(path)!r}, whose pixels are "
                          f"{own:.6g} m (its georeference); leave {name('scene_pixel_m')} out to use the file's, "
                          "or resample the file to the size you mean (e.g. gdalwarp -tr RES RES)")  # fmt: skip
    return own


def _check_grid(r, path: Path, scene_pixel_m: float | None, name: Callable[[str], str]) -> None:
    """A sheared (or degenerate) transform, or metric pixels that are not square, is refused whether or not
    ``scene_pixel_m`` is given: the output keeps the input's transform, so a pixel size cannot mend its grid."""
    if r.pixel_m is None and r.pixel_m_problem.startswith("its transform"):
        problem = r.pixel_m_problem
    elif r.pixel_m is not None and not math.isclose(*r.pixel_m, rel_tol=1e-6):
        problem = f"its pixels are {r.pixel_m[0]:.6g} x {r.pixel_m[1]:.6g} m, not square"
    else:
        return
    why = "" if scene_pixel_m is None else f" ({name('scene_pixel_m')} sets a pixel size, not the grid)"
    raise ConfigError(f"{name('input')} {str(path)!r}: {problem}; the chain needs square ground pixels on a "
                      f"regular grid{why}: resample it first (e.g. gdalwarp -tr RES RES)")  # fmt: skip


def _band_source(plan: _Plan, band: int, input_scale: float | None) -> RasterBandSource:
    """The band as reflectance: the file's scale/offset when it has them (then ``input_scale`` defaults to 1),
    else ``input_scale`` (default ``1 / (2**bits - 1)`` for integers); the fill is its valid mean."""
    from satchain.io import integer_scale
    from satchain.raster import open_raster

    path = plan.path
    with open_raster(path, band=band) as r:
        own = r.scales[band - 1] != 1.0 or r.offsets[band - 1] != 0.0
        gain = input_scale if input_scale is not None else 1.0 if own else integer_scale(r.dtype, plan.meta)
        src = RasterBandSource(path, band, pixel_m=plan.pixel_m, gain=gain, scaled=own, valid_range=None)
        values, valid = _sample(r, band, own)
        v = values * gain
        ok = np.isfinite(v) & (valid if valid is not None else True)
        fill = float(v[ok].mean()) if ok.any() else _valid_mean(r, band, own, gain)
    if fill is None:
        raise InputError(f"image = {str(path)!r}: band {band}: every pixel is nodata or masked; nothing to simulate")
    if ok.any():  # values that are not reflectance are refused before any work, not in the middle of it
        _check_reflectance(path, band, float(v[ok].min()), float(v[ok].max()), gain, input_scale is None)
    src.fill, src.valid_range = fill, REFLECTANCE_RANGE
    return src


def _check_reflectance(path: Path, band: int, lo: float, hi: float, gain: float, default: bool) -> None:
    """Refuse sampled values that are not reflectance, naming ``--input-scale``."""
    if REFLECTANCE_RANGE[0] <= lo and hi <= REFLECTANCE_RANGE[1]:
        return
    how = "the default scale" if default else "--input-scale"
    raise InputError(
        f"image = {str(path)!r}: band {band} values {lo:g}..{hi:g} (as reflectance, x {gain:g}: {how}) are not "
        f"reflectance (allowed {REFLECTANCE_RANGE[0]:g}..{REFLECTANCE_RANGE[1]:g}); give --input-scale, the factor "
        "that makes them reflectance (e.g. 0.0001 for reflectance x 10000)"
    )


def _sample(r, band: int, scaled: bool, n: int = 8, side: int = 256) -> tuple[np.ndarray, np.ndarray | None]:
    """``(values, valid)`` of a fixed sample of the band: along an axis longer than ``n x side`` px, ``n``
    windows of ``side`` px spread evenly (a few of the file's blocks), else the whole axis."""

    def axis(size: int) -> tuple[np.ndarray, int]:
        if size <= n * side:
            return np.array([0]), size
        return np.unique(np.linspace(0, size - side, n).astype(int)), side

    (ys, h), (xs, w) = axis(r.shape[0]), axis(r.shape[1])
    vals, oks = [], []
    for y in ys:
        for x in xs:
            vals.append(r.read(int(y), int(x), h, w, band=band, scaled=scaled).astype(np.float64).ravel())
            if r.has_mask:
                oks.append(r.read_mask(int(y), int(x), h, w, band=band).ravel())
    return np.concatenate(vals), (np.concatenate(oks) if oks else None)


def _valid_mean(r, band: int, scaled: bool, gain: float, rows: int = 512) -> float | None:
    """The mean of every valid pixel of the band, read in strips (when the sample found none); None if none."""
    total, count = 0.0, 0
    for y in range(0, r.shape[0], rows):
        h = min(rows, r.shape[0] - y)
        v = r.read(y, 0, h, None, band=band, scaled=scaled).astype(np.float64) * gain
        ok = np.isfinite(v) & (r.read_mask(y, 0, h, None, band=band) if r.has_mask else True)
        total, count = total + float(v[ok].sum()), count + int(ok.sum())
    return total / count if count else None


def _nodata_for(units: str, bits: int | None) -> tuple[np.dtype, float, float]:
    """(file dtype, nodata value, the lowest valid value) of the output; ``bits`` (the camera's ADC bits) is
    needed for DN only."""
    from satchain.io import simulated_dtype

    dt = simulated_dtype(units, bits)
    if dt.kind == "f":
        return dt, float("nan"), -np.inf
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
) -> dict[str, Any] | None:
    """Simulate every band (or only ``band``) of a raster file and write the COG ``out`` (and its ``.png``
    preview); see the module docstring. Returns ``{"shape_px", "count", "streamed", "metadata", "preview"}``.
    Options and inputs are checked before anything is written; a failure leaves nothing under ``out``.
    ``check_only``: only those checks (the input, its values' sample, memory and disk); returns None.
    ``also_check``: ``(system, out)`` of other simulations of this input (a sweep's cases), whose checks that
    depend on the system are made too, before anything is written."""
    from satchain._safety import clean_stale
    from satchain.engine.sensor import sensor_from_system

    name = (lambda k: dict(names).get(k, k)) if names else (lambda k: k)
    path, out = Path(input_), Path(out)
    check_scales(scene_pixel_m, input_scale, name)
    plan = _plan_input(path, band, scene_pixel_m, name)
    from satchain.engine.files import MIN_INPUT_PX

    if min(plan.shape) < MIN_INPUT_PX:
        raise ConfigError(
            f"{name('input')} {str(path)!r} at {plan.pixel_m:g} m per pixel is only {plan.shape[0]} x "
            f"{plan.shape[1]} px; a ground truth needs at least {MIN_INPUT_PX} px a side: check "
            f"{name('scene_pixel_m')}"
        )
    bands = [band] if band is not None else list(range(1, plan.count + 1))
    sources = [_band_source(plan, b, input_scale) for b in bands]
    try:
        for other, other_out in also_check:  # a sweep's other cases of this input: their system's checks alone
            try:
                _plan_case(plan, bands, sources, other, Path(other_out), units, noise, seed, memory_bytes, name)
            except SatchainError as exc:
                raise type(exc)(f"case {Path(other_out).stem}: {exc}") from None
        job = _plan_case(plan, bands, sources, system, out, units, noise, seed, memory_bytes, name)
    except BaseException:
        for src in sources:
            src.close()
        raise
    systems, planned, sims, streamed, budget = job.systems, job.planned, job.sims, job.streamed, job.budget
    sensor, bits, dtype, nodata, lowest = job.sensor, job.bits, job.dtype, job.nodata, job.lowest
    sim0 = sims[0]
    transform = output_transform(plan.transform, sim0.k)
    meta = {"system": system.name, "seed": int(seed), "noise": bool(noise), "gsd_act_m": system.gsd_act_m,
            "gsd_alt_m": system.gsd_alt_m, "input": str(path), "input_pixel_m": plan.pixel_m, "units": units,
            "bands": bands, "pixel_m": system.gsd_act_m,
            "wavelength_m": [s.optics.effective_wavelength_m for s in systems]}  # fmt: skip
    if units == "dn":
        meta["bit_depth"] = int(bits)
    if not math.isclose(system.gsd_act_m, system.gsd_alt_m, rel_tol=1e-9):
        meta["pixel_m_xy"] = [system.gsd_act_m, system.gsd_alt_m]
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
    with _staging(out) as d:
        stage_tif = d / "stage.tif"
        with _open_staging(stage_tif, plan, sim0.output_shape, len(bands), dtype, nodata, transform, meta) as dst:
            for i, (b, sim, src, s) in enumerate(zip(bands, sims, sources, systems, strict=True)):
                sensor_b = sensor_from_system(s) if sensor is not None else None
                tag = f"band {b}/{plan.count}: " if len(bands) > 1 else ""
                write = _Writer(dst, i + 1, src, sim, dtype, nodata, lowest, bits)
                run = dict(sensor=sensor_b, units=units, noise=noise, seed=_seed(seed, i), scheduler=scheduler)
                _form_band(sim, src, write, d, planned[i][1], tag, report, **run)
                dst.set_band_description(i + 1, plan.descriptions[b - 1] or f"band {b}")
                dst.update_tags(i + 1, wavelength_m=f"{s.optics.effective_wavelength_m:.6g}", input_band=str(b))
                src.close()
        _write_cog(stage_tif, out)
    preview = _write_preview(out, nodata)
    return {"shape_px": sim0.output_shape, "count": len(bands), "streamed": streamed, "metadata": meta,
            "preview": preview, "transform": transform, "crs": plan.crs}  # fmt: skip


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
               noise: bool, seed: int, memory_bytes: float | None, name: Callable[[str], str]) -> _Job:  # fmt: skip
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
    planned = [_simulator(s, plan, budget, seed) for s in systems]  # one line-of-sight motion for every band
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
    from satchain.io import simulated_dtype

    (iy, ix), px = plan.shape, plan.pixel_m
    oy, ox = int(iy * px / system.gsd_alt_m), int(ix * px / system.gsd_act_m)
    size = simulated_dtype(units, system.detector.bit_depth).itemsize
    check_disk(2.0 * n_bands * oy * ox * size, [out], f"image = {str(plan.path)!r}: simulating its {iy} x {ix} px "
               f"({iy * ix / 1e9:.3g} Gpx at {px:g} m) into {oy} x {ox} px x {n_bands} band(s)",
               fix="crop or resample it first (e.g. gdal_translate -srcwin, gdalwarp -tr)")  # fmt: skip


def _in_memory(sim, budget: float) -> bool:
    """Whether the whole band's work fits ``budget`` in memory (else it streams)."""
    from satchain.engine.memory import simulation_bytes

    return simulation_bytes(sim) <= budget and sim.frame_bytes <= sim.params.max_frame_bytes


def _simulator(system, plan: _Plan, budget: float, seed: int = 0):
    """``(simulator, streamed)`` of a band: in memory when its estimate fits ``budget``, else streamed in tiles
    that fit."""
    from satchain.engine.simulate import SimParams, Simulator
    from satchain.engine.stream import stream_bytes
    from satchain.errors import ResourceLimitError

    sim = Simulator(system, input_pixel_m=plan.pixel_m, input_shape=plan.shape, motion_seed=seed)
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
        self.top = None if self.dtype.kind == "f" else 2.0**bits - 1  # DN only: float units have no ADC range
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
    from satchain.raster import _gdal_env, _rasterio

    rasterio = _rasterio()
    profile = dict(driver="GTiff", width=int(shape[1]), height=int(shape[0]), count=count, dtype=np.dtype(dtype).name,
                   crs=plan.crs, transform=transform, nodata=nodata, tiled=True, blockxsize=512, blockysize=512,
                   BIGTIFF="IF_SAFER")  # fmt: skip
    with _gdal_env(), rasterio.open(path, "w", **profile) as dst:
        dst.update_tags(TIFFTAG_IMAGEDESCRIPTION=json.dumps({"satchain": meta}))
        yield dst


def _form_band(sim, src, write: _Writer, scratch: Path, streamed: bool, tag: str, report: Progress, *, sensor,
               units: str, noise: bool, seed: int, scheduler: str | None) -> None:  # fmt: skip
    """Both stages and the sensor for one band, in memory or streamed (stage 1 on a Dask ``scheduler`` when
    given); rows go to ``write``."""
    from satchain.engine.files import _decimate
    from satchain.engine.stream import FarField, coarse_store, stream_tile_px, stream_tiles

    def stage(text: str):
        return lambda done, total: report(f"{tag}{text}", done, total)

    (iy, ix), (ny, nx) = sim.input_shape, sim.output_shape
    if not streamed:
        coarse = _decimate(sim, src, scheduler, f"{tag}simulating {iy}x{ix} px", report)
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
    from satchain.io import atomic_path
    from satchain.raster import _gdal_env, _one_line, _rasterio

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
    from satchain import io
    from satchain.raster import open_raster

    with open_raster(out, band=1) as r:
        values, valid = r.overview(_PREVIEW_MAX_PX)
        step = r.shape[1] / values.shape[1]
        pixel = r.pixel_m[0] * step if r.pixel_m else None
    v = values.astype(np.float64)
    ok = np.isfinite(v) & (valid if valid is not None else True)
    v[~ok] = np.median(v[ok]) if ok.any() else 0.0
    png = out.with_suffix(".png")
    io.write_png(png, io.preview_uint8(v), pixel_m=pixel)
    return png
