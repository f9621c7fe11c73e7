"""The raw mosaic of a Bayer colour camera simulated through the engine, and its demosaiced images.

:func:`simulate_cfa` forms the scene once per colour, as that colour's photosites see it: the system is
:func:`satchain.config.sections_cfa.colour_system` (the optics' wavelengths and weights from the colour's spectral
response, its radiometric band and QE x response), the scene :func:`satchain.scene.spectral.layout_for_band` of the
colour's response (each material's reflectance integrated over it; a grey scene is the same for every colour), and
the image the unchanged :class:`satchain.engine.simulate.Simulator` (optics, motion, photosite aperture; one motion
draw for all three, as one array). :func:`satchain.engine.cfa.mosaic` then keeps, at each photosite, its own
colour's value. Noise is drawn once on the raw mosaic, photosite by photosite, by the engine's sensor model
(:class:`satchain.engine.sensor.SensorModel`, block-seeded so it does not depend on tiling) from the mean electrons
of each photosite's own colour (its radiometry: signal and path radiance per unit reflectance); dark current, read
noise, PRNU/DSNU, full well and ADC are the detector's, common to all photosites.

The demosaiced images are formed from the white-balanced mosaic (each photosite back in reflectance, so a neutral
grey scene is grey, as a camera balances before it interpolates) with :func:`satchain.engine.cfa.demosaic`.
Measurement of the result (each colour plane's MTF on its own grid, the luminance's MTF50 and the false colour per
method) is :func:`satchain.prediction.cfa.measure_cfa` (measurement sits beside the engine, not in it).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from satchain._validate import check_choice
from satchain.config.response import response_table
from satchain.config.sections_cfa import CFA_COLOURS, cfa_response, colour_system
from satchain.engine.cfa import DEMOSAIC_METHODS, cfa_masks, demosaic, mosaic
from satchain.engine.sensor import SensorModel, sensor_from_system
from satchain.engine.simulate import SimParams, Simulator
from satchain.engine.sources import as_ground_truth
from satchain.errors import ConfigError

__all__ = ["CFA_UNITS", "CFAImages", "simulate_cfa"]

#: The units a raw mosaic can be formed in (radiance has no single band on a colour array).
CFA_UNITS = ("reflectance", "electrons", "dn")


@dataclass(frozen=True)
class CFAImages:
    """What :func:`simulate_cfa` returns.

    Attributes
    ----------
    raw : ndarray (rows, cols)
        The raw mosaic in ``units`` (each photosite its own colour's value; noise drawn on it when ``noise``).
    planes : mapping colour -> ndarray (rows, cols)
        Each colour's full noise-free image in reflectance, the image its photosites were cut from (for tests and
        for the optics' own colour fringes: the "true" RGB image of a perfect interpolation).
    rgb : mapping method -> ndarray (rows, cols, 3)
        The white-balanced mosaic (reflectance) demosaiced by each method (red, green, blue).
    pattern : str
        The 2x2 cell ("RGGB", ...), read from the full array's pixel (0, 0).
    origin : (int, int)
        The image's first pixel (row, col) in the full array (0, 0 without a window): the pattern's phase.
    units : str
        The units of ``raw``.
    noise : bool
    offset, gain : mapping colour -> float
        A photosite of ``colour`` reads ``offset + gain x reflectance`` in ``units`` (noise-free, before
        quantisation; 0 and 1 in reflectance): the white balance applied before demosaicing.
    """

    raw: np.ndarray
    planes: Mapping[str, np.ndarray]
    rgb: Mapping[str, np.ndarray]
    pattern: str
    origin: tuple[int, int]
    units: str
    noise: bool
    offset: Mapping[str, float]
    gain: Mapping[str, float]

    @property
    def masks(self) -> dict[str, np.ndarray]:
        """Each colour's photosites in ``raw`` (:func:`satchain.engine.cfa.cfa_masks` at ``origin``)."""
        return cfa_masks(self.raw.shape, self.pattern, origin=self.origin)

    @property
    def true_rgb(self) -> np.ndarray:
        """The three colour planes stacked (rows, cols, 3): the image a perfect interpolation would give."""
        return np.stack([self.planes[c] for c in CFA_COLOURS], axis=-1)

    def balanced(self) -> np.ndarray:
        """``raw`` white-balanced back to reflectance, photosite by photosite: ``(raw - offset) / gain``."""
        out = np.empty(self.raw.shape, dtype=float)
        for colour, m in self.masks.items():
            out[m] = (self.raw[m] - self.offset[colour]) / self.gain[colour]
        return out


class _SceneWindow:
    """A window ``(row0, col0, height, width)`` (pixels at ``pixel_m``) of a scene, as a scene of its own."""

    def __init__(self, scene, window, pixel_m: float):
        self.scene, self.window, self.pixel_m = scene, tuple(int(v) for v in window), float(pixel_m)

    def shape_px(self, pixel_m: float) -> tuple[int, int]:
        return self.window[2], self.window[3]

    def render(self, window, *, pixel_m: float) -> np.ndarray:
        r, c, h, w = (int(v) for v in window)
        return self.scene.render((self.window[0] + r, self.window[1] + c, h, w), pixel_m=pixel_m)


def _colour_scene(layout, system, colour: str):
    """The scene as ``colour``'s photosites see it: every material integrated over the colour's response (a
    grey layout, an image scene or an array unchanged)."""
    if not getattr(layout, "materials", ()):
        return layout
    from satchain.scene.spectral import layout_for_band

    lam, resp = response_table(cfa_response(system.detector, colour).as_response())
    return layout_for_band(layout, lam, resp)


def _window_origin(window, pixel_m: float, system) -> tuple[int, int]:
    """The window's first photosite in the full array: its first scene pixel must start a photosite."""
    if window is None:
        return 0, 0
    if len(window) != 4 or any(int(v) != v for v in window) or min(window) < 0 or min(window[2:]) < 1:
        raise ConfigError(f"window = {window!r}: must be (row0, col0, height, width), whole pixels, >= 0, sizes >= 1")
    out = []
    for start, gsd in ((window[0], system.gsd_alt_m), (window[1], system.gsd_act_m)):
        k = start * pixel_m / gsd
        if abs(k - round(k)) > 1e-6:
            raise ConfigError(
                f"window = {tuple(window)!r}: its start ({start} px of {pixel_m} m) must fall on a photosite's "
                f"edge (a multiple of {gsd / pixel_m:.6g} scene pixels), so the pattern's phase is defined"
            )
        out.append(round(k))
    return out[0], out[1]


def _form_planes(layout_or_scene, system, *, window, pixel_m, params, seed) -> tuple[dict, dict]:
    """Each colour's noise-free image (reflectance) and the colour's system."""
    planes, systems = {}, {}
    for colour in CFA_COLOURS:
        s = colour_system(system, colour)
        scene = _colour_scene(layout_or_scene, system, colour)
        if window is not None and isinstance(scene, np.ndarray):
            r0, c0, h, w = (int(v) for v in window)
            scene = scene[r0 : r0 + h, c0 : c0 + w]
        elif window is not None:
            scene = _SceneWindow(scene, window, scene.pixel_m if pixel_m is None else pixel_m)
        src = as_ground_truth(scene, pixel_m=pixel_m)
        sim = Simulator(s, input_pixel_m=src.pixel_m, input_shape=src.shape_px, params=params, motion_seed=seed)
        planes[colour] = sim.run(src)  # reflectance, noise-free: the optics, motion and photosite aperture
        systems[colour] = s
    return planes, systems


def _sensors(systems: Mapping[str, Any]) -> tuple[dict[str, SensorModel], SensorModel]:
    """Each colour's sensor (its signal per unit reflectance and path offset) and the array's own: unit gain,
    the detector's dark current, read noise, fixed-pattern noise and ADC, one full well for every photosite (the
    stated one, or, without one, the largest colour's reflectance-1 signal, so no colour clips below it)."""
    sensors = {c: sensor_from_system(s) for c, s in systems.items()}
    any_s = next(iter(sensors.values()))
    well = max(s.full_well_e for s in sensors.values())
    array = dataclasses.replace(any_s, electrons_per_unit=1.0, offset_e=0.0, full_well_e=well)
    return sensors, array


def _raw_in_units(planes, sensors, array: SensorModel, pattern, origin, *, units, noise, seed, params):
    """The raw mosaic in ``units`` and each colour's (offset, gain) in them."""
    if units == "reflectance" and not noise:
        ones = {c: 1.0 for c in CFA_COLOURS}
        return mosaic(planes, pattern, origin=origin), {c: 0.0 for c in CFA_COLOURS}, ones
    mean_e = mosaic({c: sensors[c].offset_e + sensors[c].electrons_per_unit * planes[c] for c in CFA_COLOURS},
                    pattern, origin=origin)  # fmt: skip
    e = array.convert(mean_e, origin=(0, 0), units="electrons", noise=noise, seed=seed,
                      block_px=params.noise_block_px)  # fmt: skip
    offset = {c: sensors[c].offset_e + array.dark_e for c in CFA_COLOURS}
    gain = {c: sensors[c].electrons_per_unit for c in CFA_COLOURS}
    if units == "electrons":
        return e, offset, gain
    if units == "dn":
        g = array.gain_e_per_dn
        dn = np.clip(np.floor(e / g), 0, 2 ** int(array.bit_depth) - 1)
        return dn, {c: v / g for c, v in offset.items()}, {c: v / g for c, v in gain.items()}
    out = np.empty(e.shape, dtype=float)
    for c, m in cfa_masks(e.shape, pattern, origin=origin).items():
        out[m] = (e[m] - offset[c]) / gain[c]
    return out, {c: 0.0 for c in CFA_COLOURS}, {c: 1.0 for c in CFA_COLOURS}


def simulate_cfa(
    layout_or_scene,
    system,
    *,
    window: tuple[int, int, int, int] | None = None,
    pixel_m: float | None = None,
    seed: int = 0,
    noise: bool = False,
    units: str = "reflectance",
    methods: tuple[str, ...] = ("bilinear", "malvar2004", "menon2007"),
    params: SimParams = SimParams(),  # noqa: B008
) -> CFAImages:
    """The raw mosaic of a colour filter array camera and its demosaiced RGB images.

    Parameters
    ----------
    layout_or_scene : scene, image scene or array
        A scene layout (:class:`satchain.scene.Scene`, materials allowed: each colour sees them through its own
        response), an image scene, or a 2-D reflectance array (with ``pixel_m``): grey, the same for every colour.
    system : ImagingSystem
        With ``[detector] cfa`` (and optionally ``cfa_responses``).
    window : (row0, col0, height, width), optional
        The part of the scene to image, in scene pixels at ``pixel_m`` (the scene continued beyond it by the
        engine's border rule); its start must fall on a photosite's edge. The pattern keeps the full array's
        phase (``CFAImages.origin``). A system moving in time images the window as if its first row were the
        first line.
    pixel_m : float, optional
        The scene's (or array's) ground pixel size, m.
    seed : int
        The noise (and the line-of-sight motion, one draw for all three colours).
    noise : bool
        Shot, dark, read and fixed-pattern noise on the raw mosaic, per photosite from its own colour's signal.
    units : {"reflectance", "electrons", "dn"}
        The raw mosaic's units.
    methods : tuple of str
        Demosaicing methods (:data:`satchain.engine.cfa.DEMOSAIC_METHODS`).
    params : SimParams
        The engine's accuracy knobs (as :func:`satchain.engine.simulate.simulate`).

    Returns
    -------
    CFAImages

    Examples
    --------
    >>> from satchain import load_preset
    >>> cam = load_preset("ankarasat3").replace({"detector.cfa": "RGGB"})
    >>> out = simulate_cfa(np.full((140, 140), 0.3), cam, pixel_m=0.098, methods=("bilinear",))
    >>> out.raw.shape, bool(np.allclose(out.rgb["bilinear"], 0.3, atol=1e-6))
    ((28, 28), True)
    """
    check_choice("units", units, CFA_UNITS)
    pattern = system.detector.cfa
    if pattern is None:
        raise ConfigError("system.detector.cfa = None: simulate_cfa needs a colour filter array (e.g. 'RGGB')")
    methods = tuple(methods)
    for m in methods:
        check_choice("method", m, DEMOSAIC_METHODS)
    px = pixel_m if pixel_m is not None else getattr(layout_or_scene, "pixel_m", None)
    if window is not None and px is None:
        raise ConfigError("pixel_m = None: a window needs the scene's pixel size")
    origin = _window_origin(window, float(px) if px is not None else math.nan, system)
    planes, systems = _form_planes(layout_or_scene, system, window=window, pixel_m=pixel_m, params=params, seed=seed)
    sensors, array = _sensors(systems)
    raw, offset, gain = _raw_in_units(planes, sensors, array, pattern, origin, units=units, noise=noise, seed=seed,
                                      params=params)  # fmt: skip
    out = CFAImages(raw, planes, {}, pattern, origin, units, bool(noise), offset, gain)
    bal = out.balanced()
    # the pattern as the image's own first pixel reads it (a window at an odd offset starts mid-cell)
    local = "".join(_letter(out.masks, r, c) for r, c in ((0, 0), (0, 1), (1, 0), (1, 1)))
    rgb = {m: demosaic(bal, local, method=m) for m in methods}
    return dataclasses.replace(out, rgb=rgb)


def _letter(masks: Mapping[str, np.ndarray], r: int, c: int) -> str:
    return next(colour[0].upper() for colour, m in masks.items() if m[r, c])
