"""The input side of :func:`satchain.engine.georaster.simulate_raster`: a raster band as ground truth
(:class:`RasterBandSource`, its values as reflectance, its invalid pixels filled), the input's plan (grid, pixel
size, CRS, bands) and the checks made before any work: a pixel size or scale that is not a finite number > 0, a
pixel size that contradicts the file's, a sheared or non-square grid, values that are not reflectance; and
which output pixels touch invalid input (:func:`invalid_cells`)."""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from satchain.engine.tiling import Window
from satchain.errors import ConfigError, InputError

__all__ = [
    "DARKEST_GROUND",
    "MIN_INPUT_PX",
    "PIXEL_RTOL",
    "REFLECTANCE_RANGE",
    "RasterBandSource",
    "check_not_too_dark",
    "check_pixel_m",
    "check_scales",
    "invalid_cells",
]

#: the smallest ground truth (px a side) worth simulating
MIN_INPUT_PX = 8
#: reflectance an input may hold after scaling (as for every image input of ``satchain simulate``)
REFLECTANCE_RANGE = (-0.5, 4.0)
#: the largest reflectance an input's valid values must reach (unless all are 0): real ground is brighter
DARKEST_GROUND = 1e-3
#: a pixel size given for a raster that states its own agrees with it within this relative difference
PIXEL_RTOL = 1e-3


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
            from satchain.io.raster import open_raster

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
    from satchain.io.imagemeta import _gdal_meta
    from satchain.io.raster import open_raster

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
            pixel_m = _given_pixel_m(float(scene_pixel_m), _georeferenced_pixel_m(r), path, name)
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


def check_pixel_m(path: str | os.PathLike, scene_pixel_m: float | None, name: Callable[[str], str]) -> float | None:
    """Refuse a ``scene_pixel_m`` that contradicts the pixel size the georeference of the raster ``path``
    states (see :func:`_given_pixel_m`; e.g. ``measure --pixel-m``); returns the pixel size to use (the file's
    where they agree), None when none is given."""
    from satchain.io.raster import open_raster

    if scene_pixel_m is None:
        return None
    with open_raster(path) as r:
        return _given_pixel_m(float(scene_pixel_m), _georeferenced_pixel_m(r), Path(path), name)


def _georeferenced_pixel_m(r) -> float | None:
    """The pixel size a raster's georeference states (a projected CRS's transform), which the output keeps;
    None without one (satchain's tags of a local TIFF are a default that ``scene_pixel_m`` may replace)."""
    return r.pixel_m[0] if r.pixel_m is not None and r.georeferenced else None


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
    from satchain.io.images import integer_scale
    from satchain.io.raster import open_raster

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


def check_not_too_dark(what: str, lo: float, hi: float, gain: float, default: bool) -> None:
    """Refuse values whose largest magnitude, as reflectance, is above 0 but below :data:`DARKEST_GROUND`: darker
    than any real ground (dark water is 0.02-0.05), so the scale is wrong (e.g. ``--input-scale 1e-30``, or
    12-bit DN read as 16-bit ones). An all-zero image is left alone (a black scene is what it says)."""
    top = max(abs(lo), abs(hi))
    if not 0.0 < top < DARKEST_GROUND:
        return
    how = "the default scale" if default else "--input-scale"
    raise InputError(
        f"{what} values {lo:.3g}..{hi:.3g} (as reflectance, x {gain:g}: {how}) are all darker than "
        f"{DARKEST_GROUND:g}, darker than any real ground (dark water is about 0.02): the scale is wrong; give "
        "--input-scale, the factor that makes them reflectance (e.g. 0.0001 for reflectance x 10000)"
    )


def _check_reflectance(path: Path, band: int, lo: float, hi: float, gain: float, default: bool) -> None:
    """Refuse sampled values that are not reflectance, naming ``--input-scale``."""
    check_not_too_dark(f"image = {str(path)!r}: band {band}", lo, hi, gain, default)
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
