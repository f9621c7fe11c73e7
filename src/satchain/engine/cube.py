"""A multiband reflectance cube as the ground truth of a banded system (issue 32 point 1): every ``[[bands]]``
entry's reflectance image formed from one image whose bands carry their centre wavelengths.

A cube is any raster GDAL reads (:mod:`satchain.io.raster`) whose ``K`` data bands hold reflectance (scaled as
every image input: the file's scale/offset, else ``input_scale``, else ``1 / (2^bits - 1)`` for integers;
:mod:`satchain.engine.raster_input`) at centre wavelengths ``lam_1 < ... < lam_K``, given by (first found):
``wavelengths_nm`` (``--wavelengths-nm 490,560,665,842``), each band's GDAL metadata (``IMAGERY``
``CENTRAL_WAVELENGTH_UM``, or ENVI-style ``wavelength`` with ``wavelength_units``), satchain's JSON description
(``center_wavelengths_m``, as :func:`satchain.engine.bands.write_band_rasters` writes it, or ``wavelengths_nm``),
or the ENVI header's ``wavelength = {...}`` list (domain ``ENVI``). A wavelength without units is read as nm
when it lies in 200-20000, as um in 0.2-20, and refused otherwise.

**Band images.** Each pixel's spectrum is the cube's values joined linearly between the band centres (the end
value beyond them), and a system band sees its response-weighted mean (the weighting of
:func:`satchain.scene.materials.band_reflectance` with :func:`satchain.engine.bands.band_response`: QE times
response, piecewise linear, integrated exactly). Linear in the cube, so band ``b``'s image is
``sum_k w_bk R_k`` with ``w_bk = integral phi_k S_b / integral S_b`` (``phi_k`` the hat function of centre ``k``):
the weights are computed once, and a pixel's value needs only the cube bands whose weight is not zero. A flat
spectrum gives its value (``sum_k w_bk = 1``), a linear one ``a + b lam_b`` (``lam_b`` the band's weighted mean
wavelength) while the band lies inside the cube's range. A band with more than
:data:`~satchain.scene.materials.OUTSIDE_WEIGHT` of its response outside ``[lam_1, lam_K]`` is refused, as a
material's spectrum is.

**Streaming.** A band's ground truth (:class:`CubeBandScene`) reads the cube window by window (the engine's tiles),
never whole; the band images are formed by :func:`satchain.engine.bands.simulate_bands` (one band per call: each
its own grey ground), which holds each band's output image. Pixels that are nodata or masked are refused where a
window holds them (the banded output has no nodata).

Examples
--------
>>> cube_weights([500e-9, 600e-9, 700e-9], np.array([550e-9, 650e-9]), np.array([1.0, 1.0])).round(6).tolist()
[0.125, 0.75, 0.125]
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import re
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from satchain.engine.simulate import SimParams
from satchain.engine.tiling import Window
from satchain.errors import ConfigError, InputError

__all__ = [
    "CubeBandScene",
    "ReflectanceCube",
    "cube_wavelengths_m",
    "cube_weights",
    "simulate_cube",
    "states_wavelengths",
    "write_cube_rasters",
]

#: Wavelength units GDAL / ENVI metadata may name (lower case, without spaces) -> metres per unit.
_UNITS_M = {"nm": 1e-9, "nanometers": 1e-9, "nanometer": 1e-9, "nanometres": 1e-9, "nanometre": 1e-9,
            "um": 1e-6, "µm": 1e-6, "micrometers": 1e-6, "micrometer": 1e-6, "micrometres": 1e-6,
            "micrometre": 1e-6, "microns": 1e-6, "micron": 1e-6, "mm": 1e-3, "millimeters": 1e-3, "m": 1.0,
            "meters": 1.0, "metres": 1.0}  # fmt: skip


def _unitless_m(v: float) -> float | None:
    """A wavelength stated without units: nm in 200-20000, um in 0.2-20, else None (not guessed)."""
    if 200.0 <= v <= 20000.0:
        return v * 1e-9
    if 0.2 <= v <= 20.0:
        return v * 1e-6
    return None


def _to_m(values: Sequence[float], units: str | None, where: str) -> np.ndarray:
    if units is not None:
        key = units.strip().lower().replace(" ", "")
        if key not in _UNITS_M:
            raise ConfigError(f"{where}: wavelength_units = {units!r}; allowed: nanometers, micrometers, meters "
                              "(nm, um, m)")  # fmt: skip
        return np.asarray(values, dtype=float) * _UNITS_M[key]
    out = [_unitless_m(float(v)) for v in values]
    if any(m is None for m in out):
        bad = next(v for v, m in zip(values, out, strict=True) if m is None)
        raise ConfigError(f"{where}: wavelength {bad!r} has no units and is neither nm (200-20000) nor um (0.2-20); "
                          "give wavelength_units or --wavelengths-nm")  # fmt: skip
    return np.asarray(out, dtype=float)


def _numbers(text: str) -> list[float]:
    return [float(t) for t in re.split(r"[,\s{}]+", text.strip()) if t]


def _from_band_tags(ds, bands: list[int], where: str) -> np.ndarray | None:
    """Each band's ``IMAGERY`` ``CENTRAL_WAVELENGTH_UM``, else its ``wavelength`` (+ ``wavelength_units``, the
    band's or the dataset's); None unless every band states one."""
    imagery = [ds.tags(b, ns="IMAGERY").get("CENTRAL_WAVELENGTH_UM") for b in bands]
    if all(v is not None for v in imagery):
        return _to_m([float(v) for v in imagery], "um", where)
    dataset = {k.lower(): v for k, v in ds.tags().items()}
    envi = {k.lower(): v for k, v in ds.tags(ns="ENVI").items()}
    values, units = [], []
    for b in bands:
        t = {k.lower(): v for k, v in ds.tags(b).items()}
        if "wavelength" not in t:
            return None
        values.append(float(t["wavelength"]))
        units.append(t.get("wavelength_units") or dataset.get("wavelength_units") or envi.get("wavelength_units"))
    if len(set(units)) > 1:
        raise ConfigError(f"{where}: the bands' wavelength_units differ ({', '.join(sorted(map(str, set(units))))})")
    return _to_m(values, units[0], where)


def _from_dataset(ds, n: int, where: str) -> np.ndarray | None:
    """satchain's JSON description (``center_wavelengths_m`` or ``wavelengths_nm``), else the ENVI header's
    ``wavelength`` list; None without either."""
    desc = ds.tags().get("TIFFTAG_IMAGEDESCRIPTION")
    meta: Mapping[str, Any] = {}
    if desc:
        try:
            got = json.loads(desc).get("satchain", {})
            meta = got if isinstance(got, dict) else {}
        except (ValueError, AttributeError):
            meta = {}
    if meta.get("center_wavelengths_m") is not None:
        return np.asarray(meta["center_wavelengths_m"], dtype=float)
    if meta.get("wavelengths_nm") is not None:
        return np.asarray(meta["wavelengths_nm"], dtype=float) * 1e-9
    envi = {k.lower(): v for k, v in ds.tags(ns="ENVI").items()}
    if "wavelength" in envi:
        return _to_m(_numbers(envi["wavelength"]), envi.get("wavelength_units"), where)
    return None


def _check_wavelengths(lam: np.ndarray, n: int, where: str) -> np.ndarray:
    lam = np.asarray(lam, dtype=float).ravel()
    if lam.size != n:
        raise ConfigError(f"{where}: {lam.size} wavelengths for {n} bands; give one per band")
    if n < 2:
        raise ConfigError(f"{where}: a reflectance cube needs at least 2 bands with wavelengths, got {n}")
    if not np.all(np.isfinite(lam)) or lam.min() <= 0:
        raise ConfigError(f"{where}: wavelengths {[f'{v * 1e9:g}' for v in lam]} nm must be finite and > 0")
    d = np.diff(lam)
    if np.any(d <= 0):
        i = int(np.argmax(d <= 0))
        raise ConfigError(f"{where}: wavelengths must be strictly increasing, band by band; band {i + 2} "
                          f"({lam[i + 1] * 1e9:g} nm) follows {lam[i] * 1e9:g} nm")  # fmt: skip
    return lam


def states_wavelengths(path: str | os.PathLike) -> bool:
    """True when the raster ``path`` states its bands' centre wavelengths in any of the forms
    :func:`cube_wavelengths_m` reads (a cube for a banded system); a unit it cannot read is a ConfigError."""
    from satchain.io.raster import _gdal_env, _rasterio

    rasterio = _rasterio()
    where = f"image = {str(path)!r}"
    with _gdal_env(), rasterio.open(path) as ds:
        bands = [i + 1 for i, c in enumerate(ds.colorinterp) if c.name != "alpha"]
        return _from_band_tags(ds, bands, where) is not None or _from_dataset(ds, len(bands), where) is not None


def cube_wavelengths_m(path: str | os.PathLike, *, wavelengths_nm: Sequence[float] | None = None,
                       name: str = "--wavelengths-nm") -> np.ndarray:  # fmt: skip
    """The centre wavelengths (m) of the data bands of the raster ``path`` (module docstring: ``wavelengths_nm``
    first, then the file's metadata); a raster without them, a count that is not the bands', fewer than 2 bands,
    or wavelengths not strictly increasing are a one-line ConfigError."""
    from satchain.io.raster import _gdal_env, _rasterio

    rasterio = _rasterio()
    where = f"image = {str(path)!r}"
    with _gdal_env(), rasterio.open(path) as ds:
        bands = [i + 1 for i, c in enumerate(ds.colorinterp) if c.name != "alpha"]
        if wavelengths_nm is not None:
            vals = list(wavelengths_nm)
            if len(vals) != len(bands):
                raise ConfigError(f"{name} {','.join(f'{v:g}' for v in vals)}: {len(vals)} wavelengths for the "
                                  f"{len(bands)} bands of {str(path)!r}; give one per band")  # fmt: skip
            return _check_wavelengths(np.asarray(vals, dtype=float) * 1e-9, len(bands), name)
        lam = _from_band_tags(ds, bands, where)
        if lam is None:
            lam = _from_dataset(ds, len(bands), where)
    if lam is None:
        raise ConfigError(f"{where}: a reflectance cube needs each band's centre wavelength (GDAL band metadata "
                          f"wavelength + wavelength_units, IMAGERY CENTRAL_WAVELENGTH_UM) or {name}")  # fmt: skip
    return _check_wavelengths(lam, len(bands), where)


def cube_weights(cube_wavelengths_m: Sequence[float] | np.ndarray, wavelengths_m: np.ndarray, response: np.ndarray, *,
                 band: str = "band") -> np.ndarray:  # fmt: skip
    """``w_k``: the share of cube band ``k`` in the reflectance a band of response ``response`` (sampled at
    ``wavelengths_m``) sees -- :func:`satchain.scene.materials.band_reflectance` of the hat function of centre
    ``k`` (the end ones extended flat), normalised to sum 1. A response with more than ``OUTSIDE_WEIGHT`` of its
    weight outside the cube's range is a ConfigError naming both."""
    from satchain.scene.materials import OUTSIDE_WEIGHT, Material, _weight_outside, band_extent_m, band_reflectance

    lam = np.asarray(cube_wavelengths_m, dtype=float)
    w, s = np.asarray(wavelengths_m, dtype=float), np.asarray(response, dtype=float)
    lo, hi = float(lam[0]), float(lam[-1])
    b_lo, b_hi = band_extent_m(w, s)
    outside = _weight_outside(w, s, lo, hi)
    if outside > OUTSIDE_WEIGHT:
        raise ConfigError(f"{band}: its response {b_lo * 1e9:.1f}-{b_hi * 1e9:.1f} nm reaches outside the cube's "
                          f"{lo * 1e9:.1f}-{hi * 1e9:.1f} nm ({outside:.2%} of its response; at most "
                          f"{OUTSIDE_WEIGHT:.1%} may lie outside, where the end band's value is taken)")  # fmt: skip
    out = np.empty(lam.size)
    for k in range(lam.size):
        hat = Material(f"cube band {k + 1}", lam, np.eye(lam.size)[k], source="a reflectance cube's band")
        out[k] = band_reflectance(hat, w, s)
    return out / out.sum()


class CubeBandScene:
    """One system band's ground truth from a cube: ``render(window) = sum_k w_k R_k(window)`` (the cube bands
    whose weight is not zero, read window by window through :class:`satchain.engine.raster_input.RasterBandSource`),
    at the cube's ``pixel_m`` only; the scene interface of :class:`satchain.engine.sources.SceneSource`. It has no
    ground beyond the cube (``bounded``): a band whose grid is displaced beyond it (the Earth's rotation or a
    line-rate error over its delay) sees the cube continued by the engine's border rule there."""

    #: Windows outside the cube are refused: the bands' engine continues it by the border rule instead.
    bounded = True

    def __init__(self, sources: Sequence[Any], weights: np.ndarray, pixel_m: float, shape: tuple[int, int],
                 name: str = "cube"):  # fmt: skip
        keep = [k for k, v in enumerate(weights) if v != 0.0]
        self.sources, self.weights = [sources[k] for k in keep], np.asarray(weights, dtype=float)[keep]
        self.pixel_m, self.name, self._shape = float(pixel_m), name, (int(shape[0]), int(shape[1]))

    def shape_px(self, pixel_m: float | None = None) -> tuple[int, int]:
        self._check_pixel(pixel_m)
        return self._shape

    def _check_pixel(self, pixel_m: float | None) -> None:
        if pixel_m is not None and not math.isclose(pixel_m, self.pixel_m, rel_tol=1e-9):
            raise ConfigError(f"pixel_m = {pixel_m}: a reflectance cube renders only at its own pixel size "
                              f"{self.pixel_m} m; resample it upstream")  # fmt: skip

    def render(self, window=None, *, pixel_m: float | None = None) -> np.ndarray:
        self._check_pixel(pixel_m)
        rows, cols = self._shape
        r0, c0, h, w = (0, 0, rows, cols) if window is None else (int(v) for v in window)
        if r0 < 0 or c0 < 0 or r0 + h > rows or c0 + w > cols:
            raise InputError(f"window = {(r0, c0, h, w)!r}: outside the cube of shape ({rows}, {cols})")
        out = np.zeros((h, w), dtype=np.float64)
        for src, wk in zip(self.sources, self.weights, strict=True):
            v, valid = src.values(Window(r0, c0, h, w))
            if valid is not None and not valid.all():
                raise InputError(f"image = {str(src.path)!r}: band {src.band} has nodata or masked pixels in window "
                                 f"{(r0, c0, h, w)}; a banded simulation of a cube has no nodata output: fill or "
                                 "crop the cube first")  # fmt: skip
            lo, hi = float(v.min()), float(v.max())
            if src.valid_range is not None and (lo < src.valid_range[0] or hi > src.valid_range[1]):
                raise InputError(f"image = {str(src.path)!r}: band {src.band} values {lo:g}..{hi:g} (as reflectance, "
                                 f"x {src.gain:g}) in window {(r0, c0, h, w)} are not reflectance (allowed "
                                 f"{src.valid_range[0]:g}..{src.valid_range[1]:g}); give --input-scale")  # fmt: skip
            out += wk * v
        return out


class ReflectanceCube:
    """A reflectance cube opened for a banded system: ``path`` (any raster GDAL reads), its ``wavelengths_m``
    (:func:`cube_wavelengths_m`), ``pixel_m``, ``shape`` (rows, cols), ``crs`` and ``transform`` (a local metric
    grid, north up, when it has none: as the band-by-band path); the grid, pixel size and values are checked as
    every raster input's (:mod:`satchain.engine.raster_input`). ``names``: how messages name the parameters."""

    def __init__(self, path: str | os.PathLike, *, wavelengths_nm: Sequence[float] | None = None,
                 scene_pixel_m: float | None = None, input_scale: float | None = None,
                 names: Mapping[str, str] | None = None):  # fmt: skip
        from satchain.engine.raster_input import MIN_INPUT_PX, _plan_input, check_scales

        name: Callable[[str], str] = (lambda k: dict(names).get(k, k)) if names else (lambda k: k)
        check_scales(scene_pixel_m, input_scale, name)
        self.path = Path(path)
        self.wavelengths_m = cube_wavelengths_m(self.path, wavelengths_nm=wavelengths_nm,
                                                name=name("wavelengths_nm"))  # fmt: skip
        self._plan = _plan_input(self.path, None, scene_pixel_m, name)
        if min(self._plan.shape) < MIN_INPUT_PX:
            raise ConfigError(f"{name('input')} {str(path)!r} is only {self._plan.shape[0]} x {self._plan.shape[1]} "
                              f"px; a ground truth needs at least {MIN_INPUT_PX} px a side")  # fmt: skip
        self.pixel_m, self.shape = self._plan.pixel_m, self._plan.shape
        self.crs, self.transform = self._plan.crs, self._plan.transform
        self.input_scale = input_scale
        self._sources: dict[int, Any] = {}

    def weights(self, system, index: int) -> np.ndarray:
        """The cube bands' weights for band ``index`` of ``system`` (:func:`cube_weights` of
        :func:`satchain.engine.bands.band_response`)."""
        from satchain.engine.bands import band_response

        label = f"band {system.band_names[index]!r}" if system.bands else "the system's band"
        return cube_weights(self.wavelengths_m, *band_response(system, index), band=label)

    def band_scene(self, system, index: int) -> CubeBandScene:
        """Band ``index``'s ground truth (:class:`CubeBandScene`); the cube bands it needs are opened (and their
        values sampled and checked as reflectance) once per cube."""
        from satchain.engine.raster_input import _band_source

        w = self.weights(system, index)
        for k in np.flatnonzero(w):
            if int(k) not in self._sources:
                self._sources[int(k)] = _band_source(self._plan, int(k) + 1, self.input_scale)
        srcs = [self._sources.get(k) for k in range(w.size)]
        return CubeBandScene(srcs, w, self.pixel_m, self.shape, name=f"{self.path.name}:{index}")

    def output_transform(self, gsd_act_m: float, gsd_alt_m: float):
        """The transform of a band grid of these GSDs over the cube (its origin kept)."""
        from satchain.engine.georaster import output_transform

        return output_transform(self.transform, (gsd_alt_m / self.pixel_m, gsd_act_m / self.pixel_m))

    def close(self) -> None:
        for src in self._sources.values():
            src.close()
        self._sources.clear()

    def __enter__(self) -> ReflectanceCube:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def simulate_cube(cube: ReflectanceCube | str | os.PathLike, system, *, wavelengths_nm: Sequence[float] | None = None,
                  scene_pixel_m: float | None = None, input_scale: float | None = None, bands=None,
                  params: SimParams = SimParams(), units: str = "reflectance", noise: bool = True,  # noqa: B008
                  seed: int = 0):  # fmt: skip
    """Every band of the banded ``system`` (or ``bands``: indices or names) formed from the reflectance cube
    ``cube`` (a :class:`ReflectanceCube`, or a path opened with ``wavelengths_nm``, ``scene_pixel_m``,
    ``input_scale``): band ``i`` is :func:`satchain.engine.bands.simulate_bands` of its own ground truth
    (:meth:`ReflectanceCube.band_scene`), with ``band_seed(seed, i)``; the transforms are the cube's at each band's
    GSD. Returns :class:`satchain.engine.bands.BandImages` (write it with :func:`write_cube_rasters`).

    Examples
    --------
    >>> import tempfile, rasterio
    >>> from affine import Affine
    >>> from satchain import load_preset
    >>> p = tempfile.mkdtemp() + "/cube.tif"
    >>> with rasterio.open(p, "w", driver="GTiff", width=40, height=40, count=3, dtype="float32",
    ...                    transform=Affine(0.49, 0, 0, 0, -0.49, 0)) as d:
    ...     d.write(np.full((3, 40, 40), 0.3, np.float32))
    >>> r = simulate_cube(p, load_preset("ankarasat3-pms"), wavelengths_nm=[400, 700, 1000], noise=False)
    >>> r.names, r["pan"].image.shape, round(float(r["nir"].image.mean()), 4)
    (('pan', 'blue', 'green', 'red', 'nir'), (40, 40), 0.3)
    """
    from satchain.engine.bands import BandImages, simulate_bands

    opened = not isinstance(cube, ReflectanceCube)
    if isinstance(cube, ReflectanceCube):
        c = cube
    else:
        c = ReflectanceCube(cube, wavelengths_nm=wavelengths_nm, scene_pixel_m=scene_pixel_m, input_scale=input_scale)
    try:
        n = max(len(system.bands), 1)
        which = list(range(n)) if bands is None else [system.band_index(b) if isinstance(b, str) else int(b)
                                                      for b in bands]  # fmt: skip
        if not which or any(not 0 <= b < n for b in which):
            raise ConfigError(f"bands = {bands!r}: give band names or indices 0 to {n - 1}")
        scenes = [c.band_scene(system, i) for i in which]  # every weight checked before any band is formed
        out = []
        for i, scene in zip(which, scenes, strict=True):
            r = simulate_bands(scene, system, pixel_m=c.pixel_m, bands=[i], params=params, units=units, noise=noise,
                               seed=seed)  # fmt: skip
            b = r.bands[0]
            out.append(dataclasses.replace(b, transform=c.output_transform(b.gsd_act_m, b.gsd_alt_m)))
        return BandImages(tuple(out), r.units, r.noise, r.seed, r.pixel_m, r.window)
    finally:
        if opened:
            c.close()


def write_cube_rasters(result, out_dir: str | os.PathLike, *, crs=None, cube: ReflectanceCube | None = None):
    """:func:`satchain.engine.bands.write_band_rasters` of a cube's bands, georeferenced: each GeoTIFF gets the
    cube's ``crs`` (``cube.crs`` when ``cube`` is given) and, in its satchain description, the cube's path and
    wavelengths instead of the local ``origin_m``. Inside a :func:`satchain.io.committed_together` group the files
    are completed under their temporary names (committed with the group). Returns the paths by stem."""
    from satchain.engine.bands import write_band_rasters
    from satchain.io._commit import staged
    from satchain.io.raster import _gdal_env, _rasterio

    paths = write_band_rasters(result, out_dir)
    crs = cube.crs if (crs is None and cube is not None) else crs
    rasterio = _rasterio()
    for p in paths.values():
        if p.suffix != ".tif":
            continue
        with _gdal_env(), rasterio.open(staged(p), "r+") as dst:
            if crs is not None:
                dst.crs = crs
            meta = json.loads(dst.tags()["TIFFTAG_IMAGEDESCRIPTION"])
            sat = meta["satchain"]
            if crs is not None:
                sat.pop("origin_m", None)  # the transform is the cube's georeference
            if cube is not None:
                sat.update(input=str(cube.path), input_pixel_m=cube.pixel_m,
                           input_wavelengths_m=[float(v) for v in cube.wavelengths_m])  # fmt: skip
            dst.update_tags(TIFFTAG_IMAGEDESCRIPTION=json.dumps(meta))
    return paths
