"""Staggered arrays combined onto the half-pitch grid (SPOT-5's supermode; the model: :mod:`satchain.tf.staggered`).

Array A samples the focal-plane image (already through the optics and the ``p``-wide pixel aperture) at
``(i p, j p)``, array B at ``((i + 1/2) p, (j + 1/2) p)``. :func:`staggered_samples` takes both from an image
formed on the ``p / 2`` grid (A: the even rows and columns, B: the odd ones); :func:`combine_staggered` puts them
back on the ``p / 2`` grid (A at even-even, B at odd-odd) and fills each other point with the mean of its lattice
neighbours (up, down, left, right: the ``quincunx_bilinear`` combination, transfer function
:func:`satchain.tf.staggered.combination_otf`); at the border, of those that exist.

:func:`simulate_staggered` forms both arrays' images of a layout through the engine (two simulations of the same
scene, array B's ground window shifted by half a GSD along and across track, each with its own noise) and
combines them: a system's ``[detector] layout = "staggered"`` imaged as flown.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from satchain.engine.tiling import Window
from satchain.errors import ConfigError

__all__ = ["StaggeredImages", "combine_staggered", "simulate_staggered", "staggered_samples"]


def staggered_samples(image_half_pitch) -> tuple[np.ndarray, np.ndarray]:
    """The two arrays' samples ``(A, B)`` from an image on the ``p / 2`` grid: ``A = image[0::2, 0::2]``,
    ``B = image[1::2, 1::2]`` (B cropped to A's shape when the image has an odd size).

    Examples
    --------
    >>> a, b = staggered_samples(np.arange(16.0).reshape(4, 4))
    >>> a.tolist(), b.tolist()
    ([[0.0, 2.0], [8.0, 10.0]], [[5.0, 7.0], [13.0, 15.0]])
    """
    img = np.asarray(image_half_pitch)
    if img.ndim != 2 or min(img.shape) < 2:
        raise ValueError(f"image_half_pitch: shape {img.shape}: must be a 2-D image of at least 2 x 2")
    ny, nx = img.shape[0] // 2, img.shape[1] // 2
    return img[0 : 2 * ny : 2, 0 : 2 * nx : 2].copy(), img[1 : 2 * ny : 2, 1 : 2 * nx : 2].copy()


def combine_staggered(a, b, *, method: str = "quincunx_bilinear") -> np.ndarray:
    """The two arrays combined on the ``p / 2`` grid (shape ``2 x`` theirs, float64): A at even rows and columns,
    B at odd ones, every other point the mean of its up, down, left and right neighbours (those inside).

    Examples
    --------
    >>> combine_staggered(np.full((2, 2), 3.0), np.full((2, 2), 3.0)).tolist()[0]
    [3.0, 3.0, 3.0, 3.0]
    """
    from satchain.tf.staggered import COMBINATIONS

    if method not in COMBINATIONS:
        raise ValueError(f"method = {method!r}: must be one of {', '.join(COMBINATIONS)}")
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.ndim != 2 or a.shape != b.shape:
        raise ValueError(f"a, b: shapes {a.shape} and {b.shape}: must be the same 2-D shape")
    ny, nx = a.shape
    out = np.zeros((2 * ny, 2 * nx))
    known = np.zeros(out.shape, bool)
    out[0::2, 0::2], out[1::2, 1::2] = a, b
    known[0::2, 0::2] = known[1::2, 1::2] = True
    total = np.zeros(out.shape)
    count = np.zeros(out.shape)
    for dy, dx in ((1, 0), (-1, 0), (0, 1), (0, -1)):  # the four lattice neighbours at p / 2
        src = (slice(max(dy, 0), out.shape[0] + min(dy, 0)), slice(max(dx, 0), out.shape[1] + min(dx, 0)))
        dst = (slice(max(-dy, 0), out.shape[0] + min(-dy, 0)), slice(max(-dx, 0), out.shape[1] + min(-dx, 0)))
        total[dst] += np.where(known[src], out[src], 0.0)
        count[dst] += known[src]
    fill = ~known
    out[fill] = total[fill] / count[fill]
    return out


@dataclass(frozen=True)
class StaggeredImages:
    """What :func:`simulate_staggered` returns: ``a`` and ``b`` (each array's image on its own grid of the GSD, in
    ``units``), ``combined`` (both on the grid of half the GSD, :func:`combine_staggered`), ``transform`` (the
    combined grid's affine map from (column, row) to the scene's ground metres, x across track, y along track
    down the image: pixel size GSD / 2, its pixel (0, 0) centred on array A's pixel (0, 0)), ``combination`` (the
    method used, :data:`satchain.tf.staggered.COMBINATIONS`), ``units``, ``window`` (array A's window, in its
    pixels from the scene's origin) and ``gsd_m`` ((ACT, ALT) GSD of one array, m)."""

    a: np.ndarray
    b: np.ndarray
    combined: np.ndarray
    transform: Any
    combination: str
    units: str
    window: Window
    gsd_m: tuple[float, float]

    @property
    def combined_gsd_m(self) -> tuple[float, float]:
        """(ACT, ALT) pixel of the combined grid on the ground, m: half of one array's."""
        return (self.gsd_m[0] / 2, self.gsd_m[1] / 2)


class _GroundWindow:
    """A layout rendered over a window whose origin is ``origin_px`` scene pixels (rows, cols; any integers) from
    the scene's origin, at ``pixel_m``: the engine's ground truth of one array."""

    def __init__(self, scene, *, pixel_m: float, origin_px: tuple[int, int], shape_px: tuple[int, int]):
        self.scene, self.pixel_m, self.origin_px, self.shape_px = scene, float(pixel_m), origin_px, shape_px

    def read(self, window) -> np.ndarray:
        r0, c0, h, w = (int(v) for v in window)
        win = (self.origin_px[0] + r0, self.origin_px[1] + c0, h, w)
        return np.asarray(self.scene.render(win, pixel_m=self.pixel_m), dtype=np.float64)


def _as_layout(layout_or_scene):
    """A :class:`satchain.scene.Scene` from itself, a layout file or a layout mapping."""
    import os

    from satchain.scene.layout import Scene, layout_from_dict, load_layout

    if isinstance(layout_or_scene, Scene):
        return layout_or_scene
    if isinstance(layout_or_scene, (str, os.PathLike)):
        return load_layout(layout_or_scene)
    if isinstance(layout_or_scene, dict):
        return layout_from_dict(layout_or_scene)
    raise ConfigError(
        f"layout_or_scene = {type(layout_or_scene).__name__}: must be a layout (satchain.scene.Scene, a layout "
        "file or its mapping): a layout renders at any ground window, which the half-GSD shift needs"
    )


def _check_staggered(system) -> None:
    if system.detector.layout != "staggered":
        raise ConfigError(
            f"detector.layout = {system.detector.layout!r}: simulate_staggered needs a system with "
            "[detector] layout = 'staggered' (two arrays half a pixel apart); use satchain.simulate for one array"
        )
    if system.bands:
        raise ConfigError(
            f"system has {len(system.bands)} [[bands]]: simulate_staggered forms one band; pass system.for_band(i)"
        )


def _array_plan(window: Window, gsd_m: tuple[float, float], pixel_m: float, shift: float, context: int):
    """Array ``shift`` (0: A, 1/2: B, in GSD)'s ground window: the scene pixel of its origin (rows, cols), the
    sub-scene-pixel remainder as the detector grid's phase (input px), and its shape (input px)."""
    origin, phase, shape = [], [], []
    for start, n, g in ((window.row0, window.height, gsd_m[1]), (window.col0, window.width, gsd_m[0])):
        at = (start + shift - context) * g / pixel_m  # the window's first edge, scene pixels
        whole = math.floor(at + 1e-9)
        origin.append(whole)
        phase.append(max(at - whole, 0.0) if abs(at - round(at)) > 1e-9 else 0.0)
        shape.append(math.ceil((n + 2 * context) * g / pixel_m - 1e-9) + 1)  # + 1: room for the phase
    return (origin[0], origin[1]), (phase[0], phase[1]), (shape[0], shape[1])


def _seed_of(seed: int, array_index: int) -> int:
    """The noise seed of array ``array_index`` (0: A, 1: B): independent draws (and fixed patterns) per array."""
    return int(np.random.SeedSequence([int(seed), int(array_index)]).generate_state(1, dtype=np.uint32)[0])


def simulate_staggered(
    layout_or_scene,
    system,
    *,
    window=None,
    pixel_m: float | None = None,
    seed: int = 0,
    noise: bool = False,
    units: str = "reflectance",
    method: str = "quincunx_bilinear",
    context_px: int = 32,
    params=None,
) -> StaggeredImages:
    """Both arrays of a staggered layout imaging ``layout_or_scene``, and their combination on the half-GSD grid.

    Array A's pixel ``(i, j)`` covers the ground ``[(col0 + j) g_x, (col0 + j + 1) g_x) x [(row0 + i) g_y, ...)``
    (``g`` the GSD); array B's window is A's moved by ``(+g_x / 2, +g_y / 2)`` on the ground -- the window's
    origin shifted, the layout rendered there (no resampling) -- and each is one simulation through the engine
    (:class:`~satchain.engine.simulate.Simulator`: optics, the p-wide pixel, motion, TDI; one platform motion,
    ``seed``), with its own noise (seeded from ``(seed, array index)``: its own shot, read and fixed-pattern
    draws). Then :func:`combine_staggered`. ``context_px`` array pixels of the layout around the window are
    imaged too (then cut off), so both arrays see the same ground beyond the window's edge.

    Parameters
    ----------
    layout_or_scene : Scene, path or mapping
        The layout (rendered at any window; a raster scene cannot be moved by half a GSD without resampling).
    system : ImagingSystem
        Its ``[detector] layout = "staggered"`` (square pixels); one band.
    window : (row0, col0, height, width), optional
        Array A's window in its own pixels from the scene's origin; default the whole pixels the scene holds.
    pixel_m : float, optional
        The layout's rendering pixel on the ground (m); default the largest one not above the scene's own that
        divides half the ACT GSD exactly (a remainder along ALT is the detector grid's phase, exact as well).
    seed, noise, units : as :func:`satchain.simulate`; ``units`` other than reflectance, or noise, use the
        system's sensor (:func:`~satchain.engine.sensor.sensor_from_system`).
    method : str
        The combination (:data:`satchain.tf.staggered.COMBINATIONS`).
    params : SimParams, optional
        The engine's knobs (its ``phase_px`` is set here).

    Examples
    --------
    >>> from satchain import load_preset
    >>> from satchain.scene import Scene
    >>> s = load_preset("ankarasat3").replace({"detector.layout": "staggered"})
    >>> r = simulate_staggered(Scene(12.0, 12.0, background=0.3), s, window=(2, 2, 16, 16))
    >>> r.a.shape, r.combined.shape, round(r.transform.a, 3), bool(np.allclose(r.combined, 0.3, atol=1e-6))
    ((16, 16), (32, 32), 0.245, True)
    """
    from affine import Affine

    from satchain._validate import check_choice
    from satchain.engine.sensor import OUTPUT_UNITS, sensor_from_system
    from satchain.tf.staggered import COMBINATIONS

    check_choice("units", units, OUTPUT_UNITS)
    check_choice("method", method, COMBINATIONS)
    _check_staggered(system)
    if isinstance(context_px, bool) or int(context_px) != context_px or not 0 <= context_px <= 1024:
        raise ConfigError(f"context_px = {context_px!r}: must be an integer in [0, 1024]")
    scene = _as_layout(layout_or_scene)
    gsd = (float(system.gsd_act_m), float(system.gsd_alt_m))
    win, pixel_m = _window_and_pixel(scene, gsd, window, pixel_m)
    sensor = sensor_from_system(system) if (noise or units != "reflectance") else None
    a, b = (
        _one_array(scene, system, win, gsd, pixel_m, shift=s, context=int(context_px), params=params,
                   sensor=sensor, units=units, noise=noise, seed=seed, index=i)
        for i, s in enumerate((0.0, 0.5))
    )  # fmt: skip
    x0, y0 = win.col0 * gsd[0], win.row0 * gsd[1]
    transform = Affine(gsd[0] / 2, 0.0, x0 + gsd[0] / 4, 0.0, gsd[1] / 2, y0 + gsd[1] / 4)
    return StaggeredImages(a, b, combine_staggered(a, b, method=method), transform, method, units, win, gsd)


def _window_and_pixel(scene, gsd_m: tuple[float, float], window, pixel_m: float | None) -> tuple[Window, float]:
    """Array A's window (default: the whole GSD pixels the scene holds) and the layout's rendering pixel (default:
    the largest one not above the scene's own that divides half the ACT GSD exactly)."""
    from satchain._validate import check_positive
    from satchain.scene.shapes import check_window

    if pixel_m is None:
        pixel_m = gsd_m[0] / (2 * math.ceil(gsd_m[0] / (2 * scene.pixel_m) - 1e-9))
    pixel_m = check_positive("pixel_m", pixel_m)
    if window is None:
        rows = max(1, math.floor(scene.height_m / gsd_m[1] + 1e-9))
        window = (0, 0, rows, max(1, math.floor(scene.width_m / gsd_m[0] + 1e-9)))
    return Window(*check_window(window)), pixel_m


def _one_array(scene, system, win: Window, gsd_m, pixel_m: float, *, shift: float, context: int, params, sensor,
               units: str, noise: bool, seed: int, index: int) -> np.ndarray:  # fmt: skip
    """One array's image of ``win`` (its ground window ``shift`` GSD from A's), ``context`` pixels cut off."""
    from satchain.engine.memory import check_simulation_memory
    from satchain.engine.simulate import SimParams, Simulator

    origin, phase, shape = _array_plan(win, gsd_m, pixel_m, shift, context)
    src = _GroundWindow(scene, pixel_m=pixel_m, origin_px=origin, shape_px=shape)
    base = SimParams() if params is None else params
    sim = Simulator(system, input_pixel_m=pixel_m, input_shape=shape, params=replace(base, phase_px=phase),
                    motion_seed=seed)  # one platform motion for both arrays  # fmt: skip
    check_simulation_memory(sim)
    img = sim.run(src, sensor=sensor, units=units, noise=noise, seed=_seed_of(seed, index))
    out = np.asarray(img[context : context + win.height, context : context + win.width], dtype=np.float64)
    if out.shape != (win.height, win.width):
        raise ConfigError(f"window = {tuple(win)!r}: the simulation gave {out.shape} pixels")
    return out
