"""Every band of a banded system (``[[bands]]``: PAN + MS) formed from one spectral scene, and written as rasters.

Each band is the unchanged image chain (:class:`~satchain.engine.simulate.Simulator`, the path of
:func:`~satchain.engine.simulate.simulate` and ``satchain run``) run with the system that forms it
(:meth:`~satchain.config.system.ImagingSystem.for_band`: its optics wavelengths, radiometric band, QE, pixel, TDI)
on the grey scene that band sees (:func:`~satchain.scene.spectral.layout_for_band`: every material replaced by its
reflectance integrated over the band's response). Nothing is resampled: every band is sampled from the ground
truth on its own pixel grid. Within one call the bands share what they can (:mod:`~satchain.engine.bands_shared`):
the ground's render, and on each pixel grid the engine's stage 1 and the coarse frame's transform, made for the
grid's widest optical band; each band's image is the one it gets alone within 1e-6 of the scene's range (next to
the ground's edge: at the engine's accuracy there, :data:`~satchain.engine.bands_shared.GROUP_STOPBAND_RATIO`).

**Grids.** All bands share the ground window's top-left corner: band ``i``'s pixel ``(r, c)`` nominally covers
``[x0 + c g, x0 + (c + 1) g) x [y0 + r g, y0 + (r + 1) g)`` (``g`` its GSD), so the PAN and MS grids are
co-registered by their transforms (:attr:`BandImage.transform`; the MS grid's pixel is 4 PAN pixels).

**Time and registration.** A band ``offset_alt_mm`` from the reference sees the ground ``offset / image speed``
later; registered by that nominal delay (and ``offset_act_mm`` / pitch columns), its static offset is its injected
``registration_offset_px = (dy_alt, dx_act)`` in its own pixels -- what
:func:`satchain.prediction.budget.band_budgets` predicts as ``static_px`` (band minus PAN). It is applied where it
arises, on the ground: the band's detector grid starts ``(-dy g_alt, -dx g_act)`` metres from the window's corner
(its integer part a shifted scene window, its fraction the detector grid's phase on the ground-truth grid,
:class:`~satchain.engine.simulate.SimParams` ``phase_px``), so the band's content lies ``(+dy, +dx)`` px from where
its transform puts it, in the sign convention of :func:`satchain.measure.registration.measure_registration`
(``image(y, x) = reference(y - dy, x - dx)``). Where the image is a sheared, scaled or turned map of the ground (a
drift a line: Earth rotation, ``motion.line_rate_error``; yaw steering) the ground is displaced by that map of the
offset (:mod:`~satchain.engine.band_ground`), so that the image still shows it as given (within 0.0001 px on
band-limited ground: tests/engine/test_bands_yaw.py). The transforms stay nominal: the offset is a misregistration,
which measuring two bands recovers. Line-of-sight motion in time is formed per band along its own time path
(:mod:`satchain.engine.timepath`); a band's sinusoidal oscillations are those of its own time, ``delay_s``
(:func:`band_delay_s`) later than the system's detector line (each phase advanced by ``360 f delay_s``). A pixel
sees the ground at ``x = j + LOS(t)``, so a band's content moves by minus its line of sight: the offset from PAN is
minus the difference of their lines of sight (the budget's ``oscillations`` give that difference, line-of-sight
signed; tests/engine/test_bands.py).
Under ``orbit.earth_rotation`` (with or without yaw steering) and ``motion.line_rate_error`` each band's detector
grid starts where the ground has moved by its own time (:mod:`~satchain.engine.band_ground`), so its content lies
where the budget's ``earth_rotation`` and ``line_rate`` put it.
Not applied yet: the delay's effect on jitter PSD realisations (each band draws its own on its own line times),
on line-of-sight logs, and the actual delay (``offset / pitch / a`` lines) in the oscillations' phases.

**Noise** per band from its own radiometry (:func:`~satchain.engine.sensor.sensor_from_system` of the band's
system), its generator derived from ``(seed, band index)`` (:func:`band_seed`; band 0 uses ``seed`` itself, so a
single-band system's image is today's exactly).

Examples
--------
>>> from satchain import load_preset
>>> from satchain.scene.layout import Scene
>>> r = simulate_bands(Scene(19.6, 19.6, background=0.3), load_preset("ankarasat3-pms"), pixel_m=0.245,
...                    noise=False)
>>> r.names, r["pan"].image.shape, r["red"].image.shape
(('pan', 'blue', 'green', 'red', 'nir'), (40, 40), (10, 10))
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from satchain._validate import check_choice, check_positive
from satchain.config.system import ImagingSystem
from satchain.engine.band_ground import _band_source, _ground_shift_px, _warn_beyond
from satchain.engine.bands_shared import (
    band_otf,
    band_params,
    group_decimation,
    shared_coarse,
    shared_render,
    shared_spectrum,
)
from satchain.engine.sensor import OUTPUT_UNITS, sensor_from_system
from satchain.engine.simulate import SimParams, Simulator
from satchain.engine.sources import SceneSource
from satchain.engine.tiling import Window
from satchain.errors import ConfigError

__all__ = [
    "COLOUR_RANGES_M",
    "PREVIEW_STRETCH_PCT",
    "BandImage",
    "BandImages",
    "at_own_time",
    "band_delay_s",
    "band_response",
    "band_seed",
    "simulate_bands",
    "write_band_rasters",
]

#: The previews' stretch: each channel linearly between these percentiles of its own values (2 %, 98 %).
PREVIEW_STRETCH_PCT = (2.0, 98.0)
#: The previews written by :func:`write_band_rasters`: file stem -> the bands (red, green, blue channels).
PREVIEWS = {"rgb": ("red", "green", "blue"), "false_colour": ("nir", "red", "green")}
#: A colour's band when no band bears its name: the first whose centre wavelength lies in this range (m).
COLOUR_RANGES_M = {"blue": (4.0e-7, 5.2e-7), "green": (5.0e-7, 6.0e-7), "red": (6.0e-7, 7.0e-7),
                   "nir": (7.4e-7, 1.0e-6)}  # fmt: skip


@dataclasses.dataclass(frozen=True, eq=False)
class BandImage:
    """One band's image: ``image`` (2-D, on the band's own pixel grid, in ``units``), its GSD (m; ALT, ACT),
    centre wavelength (m), ``transform`` (an :class:`affine.Affine` from pixel corners to ground metres with Y up,
    as today's GeoTIFFs: ``x = x0 + c g_act``, ``Y = -(y0 + r g_alt)``), the system that formed it, the static
    offset applied (``offset_px``: (ALT, ACT) of its own pixels) and the noise seed it used."""

    index: int
    name: str
    image: np.ndarray
    gsd_alt_m: float
    gsd_act_m: float
    center_wavelength_m: float
    transform: Any
    system: ImagingSystem
    offset_px: tuple[float, float]
    seed: int

    @property
    def gsd_m(self) -> float:
        """The GSD across track (the pixel size written to the files)."""
        return self.gsd_act_m

    @property
    def grid(self) -> tuple[float, float, int, int]:
        """What a pixel grid is: (GSD ALT, GSD ACT, rows, cols); bands with equal grids share one raster."""
        return (round(self.gsd_alt_m, 9), round(self.gsd_act_m, 9), *self.image.shape)


@dataclasses.dataclass(frozen=True, eq=False)
class BandImages:
    """Every band's :class:`BandImage` (in the system's order), the ``units``, ``noise`` and ``seed`` of the run,
    the ground-truth pixel ``pixel_m`` and ``window`` (scene pixels) simulated. Index it by band name or index."""

    bands: tuple[BandImage, ...]
    units: str
    noise: bool
    seed: int
    pixel_m: float
    window: Window

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(b.name for b in self.bands)

    def __getitem__(self, key: int | str) -> BandImage:
        if isinstance(key, str):
            names = [n.casefold() for n in self.names]
            if key.casefold() not in names:
                raise ConfigError(f"band = {key!r}: not simulated; the bands are {', '.join(self.names)}")
            return self.bands[names.index(key.casefold())]
        return self.bands[key]

    def __iter__(self) -> Iterator[BandImage]:
        return iter(self.bands)

    def __len__(self) -> int:
        return len(self.bands)

    def grids(self) -> list[tuple[BandImage, ...]]:
        """The bands grouped by pixel grid (:attr:`BandImage.grid`), finest grid first, bands in order."""
        groups: dict[tuple, list[BandImage]] = {}
        for b in self.bands:
            groups.setdefault(b.grid, []).append(b)
        return [tuple(v) for _, v in sorted(groups.items(), key=lambda kv: (kv[0][1], kv[0][0]))]


def band_seed(seed: int, index: int) -> int:
    """The noise seed of band ``index``: ``seed`` itself for band 0, else drawn from ``SeedSequence([seed,
    index])`` (the convention of :func:`satchain.engine.georaster.simulate_raster`'s bands).

    Examples
    --------
    >>> band_seed(7, 0), band_seed(7, 1) == band_seed(7, 1), band_seed(7, 1) != band_seed(7, 2)
    (7, True, True)
    """
    if index == 0:
        return int(seed)
    return int(np.random.SeedSequence([int(seed), int(index)]).generate_state(1, dtype=np.uint32)[0])


def band_response(system: ImagingSystem, index: int) -> tuple[np.ndarray, np.ndarray]:
    """``(wavelengths_m, weight)`` through which band ``index`` sees reflectance: its QE times its response as
    :meth:`~satchain.config.system.ImagingSystem.for_band` tabulates them (a band with a response or a QE curve),
    else its response, else a flat weight over its radiometric band (a band given by its wavelengths).

    Examples
    --------
    >>> from satchain import load_preset
    >>> lam, r = band_response(load_preset("ankarasat3-pms"), 3)
    >>> round(float(lam[np.argmax(r)]) * 1e9 / 10) * 10, round(float(lam[0]) * 1e9) < 630
    (660, True)
    """
    from satchain.config.response import response_table

    s = system.for_band(index)
    det = s.detector
    if isinstance(det.qe, tuple) and det.qe_wavelengths_m is not None:  # for_band's QE x response
        return np.asarray(det.qe_wavelengths_m, dtype=np.float64), np.asarray(det.qe, dtype=np.float64)
    curve = system.bands[index].spectral_response if system.bands else None
    if curve is not None:
        lam, r = response_table(curve)
        return lam, np.asarray(r, dtype=np.float64)
    lo, hi = s.radiometry.band_m
    lam = np.linspace(lo, hi, 181)
    return lam, np.ones_like(lam)


def _check_window(window, full: tuple[int, int]) -> Window:
    if window is None:
        return Window(0, 0, *full)
    try:
        w = Window(*(int(v) for v in window))
    except (TypeError, ValueError):
        raise ConfigError(f"window = {window!r}: must be (row0, col0, height, width) in scene pixels") from None
    if w.height < 1 or w.width < 1:
        raise ConfigError(f"window = {tuple(window)!r}: height and width must be >= 1")
    return w


def _form_band(layout, system: ImagingSystem, i: int, window: Window, pixel_m: float, *, params: SimParams,
               units: str, noise: bool, seed: int, reuse: dict | None = None) -> BandImage:  # fmt: skip
    """Band ``i`` (of a system without bands: the system itself) formed through the unchanged engine; ``reuse``
    (one call's store, :func:`simulate_bands`): the ground rendered once per grey layout, the OTF of
    :func:`band_otf`, stage 1 and the frame's transform once per pixel grid (:func:`_plan_stage1`)."""
    from affine import Affine

    from satchain.scene.spectral import layout_for_band

    banded = bool(system.bands)
    s = _band_system(system, i, reuse) if banded else system
    scene = layout_for_band(layout, *band_response(system, i)) if banded else layout
    o = system.bands[i].registration_offset_px if banded else (0.0, 0.0)
    offset = (float(o[0]), float(o[1]))
    if reuse is not None and banded:  # one render per distinct grey layout (reuse["ground"]); the band's lighter OTF
        scene = shared_render(reuse, scene, pixel_m, params.max_tile_bytes)
    shift = _ground_shift_px(system, i, s, offset) if banded else (0.0, 0.0)  # its offset and its own time's lead
    src_scene, phase, n_out = _band_source(scene, window, pixel_m, s, shift, params)
    if banded:
        _warn_beyond(scene, src_scene, pixel_m, s, system.band_names[i], params)
    src = SceneSource(src_scene, pixel_m=pixel_m)
    p = params if phase == params.phase_px else dataclasses.replace(params, phase_px=phase)
    p = band_params(p, system, s) if banded and reuse is not None else p  # its far margin: the system's metres
    otf = _band_otf(reuse, s, system, i) if banded and reuse is not None else None
    stage1 = reuse.get("stage1", {}).get(i) if banded and reuse is not None else None
    if stage1 is not None and stage1[0] > 0.0:  # its grid's shared stage 1 (bands_shared.group_decimation)
        p = dataclasses.replace(p, pass_cy_per_px=stage1[0], stopband_ratio=stage1[1])
    sim = Simulator(s, input_pixel_m=pixel_m, input_shape=src.shape_px, params=p, motion_seed=seed, otf=otf)
    if sim.output_shape != n_out:  # _band_source sized the input for exactly these pixels
        raise ConfigError(f"band {i}: output {sim.output_shape} differs from the window's {n_out} pixels")
    sensor = None if (not noise and units == "reflectance") else sensor_from_system(s)
    bs = band_seed(seed, i)
    coarse = shared_coarse(reuse, sim, src_scene, src) if banded and reuse is not None else None
    spectrum = None  # its grid's frame transform, shared (bands_shared.shared_spectrum)
    if reuse is not None and coarse is not None and stage1 is not None and stage1[0] > 0.0:
        spectrum = shared_spectrum(reuse, sim, coarse)
    image = sim.run(src, sensor=sensor, units=units, noise=noise, seed=bs, coarse=coarse, spectrum=spectrum)
    x0, y0 = window.col0 * pixel_m, window.row0 * pixel_m
    lam = system.bands[i].center_wavelength_m if banded else _centre(s)
    name = system.band_names[i] if banded else (s.name or "band1")
    return BandImage(i, name, image, s.gsd_alt_m, s.gsd_act_m, float(lam),
                     Affine(s.gsd_act_m, 0.0, x0, 0.0, -s.gsd_alt_m, -y0), s, (offset[0], offset[1]), bs)  # fmt: skip


def _band_system(system: ImagingSystem, i: int, reuse: dict | None) -> ImagingSystem:
    """Band ``i``'s system at its own time (made once per call when ``reuse`` holds them)."""
    held = None if reuse is None else reuse.setdefault("systems", {})
    if held is not None and i in held:
        return held[i]
    s = at_own_time(system.for_band(i), band_delay_s(system, i))
    if held is not None:
        held[i] = s
    return s


def _band_otf(reuse: dict, s: ImagingSystem, system: ImagingSystem, i: int):
    held = reuse.setdefault("otfs", {})
    if i not in held:
        held[i] = band_otf(s, system.bands[i])
    return held[i]


def _plan_stage1(reuse: dict, system: ImagingSystem, which: list[int], pixel_m: float, params: SimParams) -> None:
    """``reuse["stage1"]``: each band's stage-1 pass band and stopband ratio (:func:`group_decimation`), the bands
    grouped by pixel grid (GSD, active width) and their optics' cutoffs on the ground truth's pixel."""
    from satchain.engine.simulate import cutoff_cy_per_px

    if not system.bands:
        return
    bands = {}
    for i in which:
        s = _band_system(system, i, reuse)
        det = s.detector
        grid = (round(s.gsd_alt_m, 12), round(s.gsd_act_m, 12), det.active_width_y_m, det.active_width_x_m)
        bands[i] = (grid, cutoff_cy_per_px(s, _band_otf(reuse, s, system, i), pixel_m))
    reuse["stage1"] = group_decimation(bands, params.stopband_ratio)


def band_delay_s(system: ImagingSystem, index: int) -> float:
    """When band ``index`` sees a ground point after the system's own detector line: its ``offset_alt_mm`` over the
    image's speed on the focal plane (``pitch_y / line_time``), s (the budget's ``delay_s`` is the difference of
    two bands' delays).

    Examples
    --------
    >>> from satchain import load_preset
    >>> round(band_delay_s(load_preset("ankarasat3-pms"), 1) * 1e3, 1)  # blue, 6 mm behind the PAN line
    71.8
    """
    if not system.bands:
        return 0.0
    return system.bands[index].offset_alt_mm * 1e-3 * system.line_time_s / system.detector.pitch_y_m


def at_own_time(s: ImagingSystem, delay_s: float) -> ImagingSystem:
    """``s`` with its sinusoidal line-of-sight oscillations seen ``delay_s`` later (each phase advanced by ``360 f
    delay_s`` degrees): the rows of a band behind the reference line see the motion of a later instant.

    Examples
    --------
    >>> from satchain import load_preset
    >>> s = load_preset("ankarasat3").replace(
    ...     {"motion.oscillation": [{"axis": "act", "amplitude_px": 1.0, "frequency_hz": 20.0}]})
    >>> at_own_time(s, 0.0125).motion.oscillation[0].phase_deg  # a quarter period later
    90.0
    """
    m = s.motion
    if not delay_s or not m.oscillation:
        return s
    osc = tuple(o.model_copy(update={"phase_deg": math.remainder(o.phase_deg + 360.0 * o.frequency_hz * delay_s,
                                                                  360.0)}) for o in m.oscillation)  # fmt: skip
    return s.model_copy(update={"motion": m.model_copy(update={"oscillation": osc})})


def _centre(s: ImagingSystem) -> float:
    lam = np.asarray(s.optics.wavelengths_m, dtype=float)
    w = s.optics.wavelength_weights
    return float(np.average(lam, weights=None if w is None else np.asarray(w, dtype=float)))


def simulate_bands(
    layout,
    system: ImagingSystem,
    *,
    pixel_m: float | None = None,
    window=None,
    bands=None,
    params: SimParams = SimParams(),  # noqa: B008
    units: str = "reflectance",
    noise: bool = True,
    seed: int = 0,
) -> BandImages:
    """Every band of ``system`` formed from ``layout`` (a scene, spectral or grey), each on its own pixel grid.

    Parameters
    ----------
    layout : Scene or ImageScene
        The ground truth (``render(window, *, pixel_m)``, ``shape_px(pixel_m)``); its materials are integrated over
        each band's response (:func:`band_response`).
    system : ImagingSystem
        A system with ``[[bands]]``; one without is one band, formed exactly as
        :func:`~satchain.engine.simulate.simulate` forms it.
    pixel_m : float, optional
        The ground-truth pixel (m); default the scene's own. Every band's GSD over it should be an integer (the
        engine's exact path).
    window : (row0, col0, height, width), optional
        The ground simulated, in ground-truth pixels at ``pixel_m``; default the whole scene. Each band gets the
        whole pixels of its grid that fit in it.
    bands : sequence of int or str, optional
        The bands formed (indices or names); default all.
    params : SimParams
        The engine's knobs; ``phase_px`` is set per band (the band's static offset).
    units, noise, seed
        As :func:`~satchain.engine.simulate.simulate`; band ``i``'s noise uses :func:`band_seed` ``(seed, i)``, its
        line-of-sight motion ``seed``.

    Returns
    -------
    BandImages

    Examples
    --------
    >>> from satchain import load_preset
    >>> from satchain.scene.layout import Scene
    >>> r = simulate_bands(Scene(8.0, 8.0, background=0.25), load_preset("ankarasat3"), pixel_m=0.035,
    ...                    noise=False)
    >>> len(r), r[0].image.shape, bool(np.allclose(r[0].image, 0.25, atol=1e-6))
    (1, (16, 16), True)
    """
    check_choice("units", units, OUTPUT_UNITS)
    p = check_positive("pixel_m", layout.pixel_m if pixel_m is None else pixel_m)
    rows, cols = layout.shape_px(p)
    win = _check_window(window, (int(rows), int(cols)))
    n = max(len(system.bands), 1)
    if bands is None:
        which = list(range(n))
    else:
        which = [system.band_index(b) if isinstance(b, str) else int(b) for b in bands]
        bad = [b for b in which if not 0 <= b < n]
        if bad or not which:
            raise ConfigError(f"bands = {bands!r}: give band names or indices 0 to {n - 1}")
    reuse: dict = {}  # this call's shared render, stage 1 and transform (no state outlives the call)
    _plan_stage1(reuse, system, which, p, params)
    out = tuple(_form_band(layout, system, i, win, p, params=params, units=units, noise=noise, seed=seed,
                           reuse=reuse) for i in which)  # fmt: skip
    return BandImages(out, units, bool(noise), int(seed), p, win)


# ---------------------------------------------------------------------------------------------- files


def _raster_name(group: tuple[BandImage, ...], k: int, n_multi: int) -> str:
    if len(group) == 1:
        return "".join(c if c.isalnum() or c in "-_" else "_" for c in group[0].name)
    return "ms" if n_multi <= 1 or k == 0 else f"ms{k + 1}"


def _file_values(image: np.ndarray, units: str, bit_depth: int | None) -> np.ndarray:
    from satchain.io.images import simulated_dtype

    a = np.asarray(image)
    if units == "dn":
        a = np.clip(np.round(a), 0, 2.0 ** (12 if bit_depth is None else int(bit_depth)) - 1)
    return a.astype(simulated_dtype(units, bit_depth))


def _write_grid(path: Path, group: tuple[BandImage, ...], result: BandImages) -> None:
    """One GeoTIFF of the bands of one grid, atomically: band descriptions = names, per-band tags (centre
    wavelength, GSD, applied offset), GDAL's IMAGERY CENTRAL_WAVELENGTH_UM, and the satchain JSON description."""
    from satchain.io.images import atomic_path
    from satchain.io.raster import _gdal_env, _rasterio

    rasterio = _rasterio()
    first = group[0]
    bits = first.system.detector.bit_depth if result.units == "dn" else None
    data = [_file_values(b.image, result.units, bits) for b in group]
    ny, nx = first.image.shape
    profile = dict(driver="GTiff", width=nx, height=ny, count=len(group), dtype=data[0].dtype.name,
                   transform=first.transform, tiled=True, blockxsize=256, blockysize=256, compress="deflate",
                   BIGTIFF="IF_SAFER")  # fmt: skip
    x0, y0 = first.transform.c, -first.transform.f
    meta: dict[str, Any] = {"pixel_m": first.gsd_act_m, "gsd_alt_m": first.gsd_alt_m, "origin_m": [x0, y0],
                            "units": result.units, "noise": result.noise, "seed": result.seed,
                            "system": first.system.name, "band_names": [b.name for b in group],
                            "center_wavelengths_m": [b.center_wavelength_m for b in group]}  # fmt: skip
    if bits is not None:
        meta["bit_depth"] = int(bits or 12)
    with atomic_path(path) as tmp, _gdal_env(), rasterio.open(tmp, "w", **profile) as dst:
        dst.update_tags(TIFFTAG_IMAGEDESCRIPTION=json.dumps({"satchain": meta}), units=result.units)
        for j, (b, a) in enumerate(zip(group, data, strict=True), start=1):
            dst.write(a, j)
            dst.set_band_description(j, b.name)
            dst.update_tags(j, name=b.name, center_wavelength_m=repr(b.center_wavelength_m),
                            gsd_m=repr(b.gsd_act_m), registration_offset_px=json.dumps(list(b.offset_px)))  # fmt: skip
            dst.update_tags(j, ns="IMAGERY", CENTRAL_WAVELENGTH_UM=f"{b.center_wavelength_m * 1e6:.6g}")


def _stretch(a: np.ndarray) -> np.ndarray:
    from satchain.io.images import preview_uint8

    lo, hi = PREVIEW_STRETCH_PCT
    return preview_uint8(a, low_pct=lo, high_pct=hi)


def _write_preview(path: Path, channels: tuple[BandImage, ...]) -> None:
    from PIL import Image, PngImagePlugin

    from satchain.io.images import PNG_COMPRESS_LEVEL, atomic_path

    rgb = np.stack([_stretch(b.image) for b in channels], axis=-1)
    info = PngImagePlugin.PngInfo()
    lo, hi = PREVIEW_STRETCH_PCT
    info.add_text("satchain", json.dumps({"pixel_m": channels[0].gsd_act_m, "channels": [b.name for b in channels],
                                          "stretch": f"each channel linear between its {lo:g} and {hi:g} "
                                          "percentiles"}))  # fmt: skip
    with atomic_path(path) as tmp:
        Image.fromarray(rgb, mode="RGB").save(tmp, format="PNG", pnginfo=info, compress_level=PNG_COMPRESS_LEVEL)


def write_band_rasters(result: BandImages, out_dir: str | os.PathLike) -> dict[str, Path]:
    """Write ``result`` into ``out_dir``: one GeoTIFF per pixel grid -- a grid of one band as ``<name>.tif`` (the
    PAN image: ``pan.tif``), a grid of several as ``ms.tif`` (``ms2.tif``, ... for more) -- with band names
    (descriptions) and centre wavelengths (tags), georeferenced as today's images (pixel size, the window's
    corner at ``(x0, -y0)``, no CRS), each written atomically; and, where the bands exist on one grid (by name,
    else by centre wavelength: :data:`COLOUR_RANGES_M`), an RGB (``rgb.png``: red, green, blue) and a false-colour
    (``false_colour.png``: NIR, red, green) preview, each channel stretched between its 2nd and 98th percentiles
    (:data:`PREVIEW_STRETCH_PCT`). Returns the paths by stem.

    Examples
    --------
    >>> import tempfile
    >>> from satchain import load_preset
    >>> from satchain.scene.layout import Scene
    >>> r = simulate_bands(Scene(20.0, 20.0), load_preset("ankarasat3-pms"), pixel_m=0.245, noise=False)
    >>> sorted(write_band_rasters(r, tempfile.mkdtemp()))
    ['false_colour', 'ms', 'pan', 'rgb']
    """
    out = Path(out_dir)
    if not out.is_dir():
        raise ConfigError(f"out_dir = {str(out)!r}: not a directory")
    grids = result.grids()
    n_multi = sum(len(g) > 1 for g in grids)
    paths: dict[str, Path] = {}
    multi = 0
    for g in grids:
        stem = _raster_name(g, multi, n_multi)
        multi += len(g) > 1
        paths[stem] = out / f"{stem}.tif"
        _write_grid(paths[stem], g, result)
    for stem, want in PREVIEWS.items():
        for g in grids:
            picked = [_colour_band(g, w) for w in want]
            if all(b is not None for b in picked) and len({id(b) for b in picked}) == len(want):
                paths[stem] = out / f"{stem}.png"
                _write_preview(paths[stem], tuple(b for b in picked if b is not None))
                break
    return paths


def _colour_band(group: tuple[BandImage, ...], colour: str) -> BandImage | None:
    """The band of ``group`` named ``colour``, else the first whose centre lies in :data:`COLOUR_RANGES_M`."""
    for b in group:
        if b.name.casefold() == colour:
            return b
    lo, hi = COLOUR_RANGES_M[colour]
    return next((b for b in group if lo <= b.center_wavelength_m < hi), None)
