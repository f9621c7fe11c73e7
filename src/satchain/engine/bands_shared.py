"""What the bands of one :func:`~satchain.engine.bands.simulate_bands` call share, so that forming every band costs
little more than its own image chain (benchmarks/bench_bands.py): the ground rendered once per distinct grey
layout; the engine's stage 1 (decimation) and the coarse frame's transform once per pixel grid, made for the grid's
widest optical band (:func:`group_decimation`, :func:`shared_coarse`, :func:`shared_spectrum`), so that each band of
the grid only multiplies its own OTF, folds and adds its noise; and each band's OTF over the fewest spectral
quadrature nodes that keep its MTF within :data:`OTF_TOLERANCE` of the system's own. Nothing outlives the call: the
store is a dict the call owns.

Examples
--------
>>> from satchain.scene.layout import Scene
>>> store, scene = {}, Scene(4.0, 4.0, background=0.3)
>>> shared_render(store, scene, 0.5, 2**20) is shared_render(store, scene, 0.5, 2**20)
True
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from satchain.config.system import ImagingSystem

__all__ = [
    "GROUP_STOPBAND_RATIO",
    "OTF_NODES_TRIED",
    "OTF_TOLERANCE",
    "band_otf",
    "band_params",
    "group_decimation",
    "shared_coarse",
    "shared_render",
    "shared_spectrum",
]


#: The simulation's OTF of a band with a response: the fewest quadrature nodes (of these) whose diffraction MTF is
#: within :data:`OTF_TOLERANCE` of the system's own (:data:`~satchain.config.sections_light.RESPONSE_NODES` nodes)
#: at every frequency up to the optics' cutoff (:func:`band_otf`).
OTF_NODES_TRIED = (3, 4, 5, 7)
#: Largest change of a band's diffraction MTF that :func:`band_otf`'s fewer nodes may make (absolute).
OTF_TOLERANCE = 1e-3
#: The smallest stop-band / pass-band ratio of a pixel grid's shared stage 1 (:func:`group_decimation`; the engine's
#: own default is :attr:`~satchain.engine.simulate.SimParams.stopband_ratio`, 1.8): a narrower transition, so that
#: the grid's widest band decimates as much as the others (ankarasat3-pms' blue band on the paper scene's 0.07 m
#: ground: by 2, not 1). The low-pass kernel's support grows as 1 / (f_stop - f_pass)
#: (:data:`~satchain.engine.spectral.LOWPASS_SUPPORT`), so the tiles' margins widen and the image is unchanged
#: within 1e-6 of the scene's range (tests/engine/test_bands_speed.py) -- except next to the ground's edge, where the
#: engine continues the coarse grid by its border rule and a different D changes the image at the engine's accuracy
#: there (6e-6 measured on a yaw-steered scene 10 MS pixels wide: tests/engine/test_stage1_sharing.py).
GROUP_STOPBAND_RATIO = 1.25


def _diffraction_mtf(otf, f: np.ndarray) -> np.ndarray:
    """|diffraction OTF| along x, y and the diagonal at radial frequencies ``f`` (cy/mm), stacked."""
    others = tuple(n for n in otf.component_names if n != "diffraction")
    d = f / math.sqrt(2.0)
    return np.abs(np.stack([otf(f, 0 * f, exclude=others), otf(0 * f, f, exclude=others), otf(d, d, exclude=others)]))


def band_otf(s: ImagingSystem, band) -> Any:
    """The :class:`~satchain.tf.budget.SystemOTF` the simulation uses for band system ``s`` (from
    :meth:`~satchain.config.system.ImagingSystem.for_band`) of ``[[bands]]`` entry ``band``: for a band with a
    spectral response, its diffraction over the fewest nodes of :data:`OTF_NODES_TRIED` (the same centroid
    quadrature, :func:`~satchain.config.response.response_quadrature`) whose MTF differs from that over the system's
    nodes by less than :data:`OTF_TOLERANCE` at every frequency up to the optics' cutoff (along x, y and the
    diagonal); every other component unchanged. Else (no response, or no fewer nodes that close) ``s``'s own OTF.
    Either with its diffraction interpolated on a radial table on whole spectra (``radial_table``: within 2e-8 of
    the closed form, :class:`~satchain.tf.optics.DiffractionOTF`).

    Examples
    --------
    >>> from satchain import load_preset
    >>> ms = load_preset("ankarasat3-pms")
    >>> i = ms.band_index("red")
    >>> s = ms.for_band(i)
    >>> len(s.optics.wavelengths_m), len(band_otf(s, ms.bands[i]).system.optics.wavelengths_m)
    (11, 3)
    """
    from satchain.config.response import response_quadrature
    from satchain.tf.budget import SystemOTF

    full = SystemOTF(s, radial_table=True)  # whole spectra: the closed form on a radial table (within 2e-8)
    curve = band.spectral_response
    n_full = len(s.optics.wavelengths_m)
    if curve is None or "diffraction" not in full.component_names:
        return full
    f = np.linspace(0.0, full.cutoff_cy_per_mm, 257)
    ref = _diffraction_mtf(full, f)
    for n in (k for k in OTF_NODES_TRIED if k < n_full):
        lam, w = response_quadrature(curve, n)
        lighter = SystemOTF(s.replace({"optics.wavelengths_m": tuple(float(x) for x in lam),
                                       "optics.wavelength_weights": tuple(float(x) for x in w / w.sum())}),
                            radial_table=True)  # fmt: skip
        if float(np.max(np.abs(_diffraction_mtf(lighter, f) - ref))) < OTF_TOLERANCE:
            return lighter
    return full


def band_params(params: Any, system: ImagingSystem, s: ImagingSystem) -> Any:
    """``params`` for band system ``s`` of ``system``: ``far_margin_px`` (the coarse frame's extension beyond the
    ground truth, in output pixels) kept at the same ground distance as the system's own pixels give it, so a band
    with pixels ``r`` times the system's gets ``ceil(far_margin_px / r)`` of them (the optics' PSF tails, which the
    margin holds, are the same on the ground for every band; the pixel footprint is integrated exactly). An MS band at
    4x the pitch: 32 of its pixels for the default 128; its image changes by < 1e-4 of the scene's range
    (tests/engine/test_bands_speed.py; 2.5e-5 measured on the paper scene). Bands no coarser: ``params`` itself.

    Examples
    --------
    >>> from satchain import load_preset
    >>> from satchain.engine.simulate import SimParams
    >>> ms = load_preset("ankarasat3-pms")
    >>> band_params(SimParams(), ms, ms.for_band(ms.band_index("red"))).far_margin_px
    32
    """
    r = min(s.gsd_alt_m / system.gsd_alt_m, s.gsd_act_m / system.gsd_act_m)
    if r <= 1.0:
        return params
    return dataclasses.replace(params, far_margin_px=max(1, int(math.ceil(params.far_margin_px / r - 1e-9))))


def group_decimation(bands: dict[int, tuple[Any, float]], stopband_ratio: float) -> dict[int, tuple[float, float]]:
    """Stage 1 of each band, given as ``index -> (pixel grid, optics cutoff in cycles per input pixel)``: ``index ->
    (pass band, stopband ratio)`` for :class:`~satchain.engine.simulate.SimParams` (``pass_cy_per_px``,
    ``stopband_ratio``). A band that shares its grid with others decimates with the grid's widest cutoff as its pass
    band and ``min(stopband_ratio, GROUP_STOPBAND_RATIO)``, so every band of the grid gets the same coarse grid (one
    stage 1 and one frame transform: :func:`shared_coarse`, :func:`shared_spectrum`) -- when that decimates no less
    than its own cutoff and ``stopband_ratio`` would (so it is never slower); else, and a band alone on its grid,
    ``(0.0, stopband_ratio)``: the engine's own plan, exactly.

    Examples
    --------
    >>> g = group_decimation({0: ("pan", 0.133), 1: ("ms", 0.188), 2: ("ms", 0.112)}, 1.8)
    >>> g[0], g[1], g[2]
    ((0.0, 1.8), (0.188, 1.25), (0.188, 1.25))
    """
    from satchain.engine.simulate import decimation_factor

    widest: dict[Any, float] = {}
    count: dict[Any, int] = {}
    for grid, f in bands.values():
        widest[grid] = max(widest.get(grid, 0.0), float(f))
        count[grid] = count.get(grid, 0) + 1
    ratio = min(float(stopband_ratio), GROUP_STOPBAND_RATIO)
    out: dict[int, tuple[float, float]] = {}
    for i, (grid, f) in bands.items():
        joins = count[grid] > 1 and decimation_factor(widest[grid], ratio) >= decimation_factor(f, stopband_ratio)
        out[i] = (widest[grid], ratio) if joins else (0.0, float(stopband_ratio))
    return out


def shared_spectrum(reuse: dict, sim: Any, coarse: np.ndarray) -> Any:
    """The band of ``sim``'s coarse frame's transform (:meth:`~satchain.engine.simulate.Simulator.frame_spectrum`)
    over its whole stage-1 pass band, or the call's latest one when it transformed the same coarse grid (the
    object :func:`shared_coarse` returned) into the same frame (extension, shape, border; under yaw steering the
    same turn about the same pivot) over a band reaching ``sim``'s optical cutoff: ``sim`` takes its own band out of
    it (:meth:`~satchain.engine.simulate.Simulator.own_band`), the very values its own transform gives. The latest
    one only is held."""
    p = sim.params
    key: tuple = (sim.D, sim.frame_ext, sim.frame_shape, p.border, p.border_value, sim.yaw_deg)
    if sim.yaw_deg:  # the turned frame depends on the pivot: the grid's size, pitch and phase
        key += (sim.output_shape, sim.k, tuple(p.phase_px))
    held = reuse.get("spectrum")
    if held is not None and held[0] is coarse and held[1] == key and held[2] >= sim.f_cut:
        return held[3]
    spec = sim.frame_spectrum(coarse, f_band=sim.f_pass)
    reuse["spectrum"] = (coarse, key, sim.f_pass, spec)
    return spec


def shared_coarse(reuse: dict, sim: Any, src_scene, source) -> np.ndarray:
    """The engine's stage 1 (:meth:`~satchain.engine.simulate.Simulator.decimate`) of ``source`` (the ground truth
    of ``src_scene``) for ``sim``, or the call's latest one when it decimated the same ground object onto the same
    coarse grid (decimation factor, coarse extension, stop frequency, border) with a pass band reaching at least
    ``sim``'s optical cutoff: the low-pass is exactly 1 up to its pass frequency and ``sim``'s OTF 0 beyond its
    cutoff, so the image changes only by rounding and the kernel's tails (< 1e-6 of the scene's range:
    tests/engine/test_bands_speed.py). At D = 1 the coarse grid is the ground itself. The latest one only is
    held."""
    p = sim.params
    key = (sim.D, sim.n_coarse, sim.coarse_ext, sim.f_stop if sim.D > 1 else None, p.border, p.border_value)
    held = reuse.get("coarse")
    if held is not None and held[0] is src_scene and held[1] == key and (sim.D == 1 or held[2] >= sim.f_cut):
        return held[3]
    coarse = sim.decimate(source)
    reuse["coarse"] = (src_scene, key, sim.f_pass, coarse)
    reuse.pop("spectrum", None)  # its coarse grid is no longer held
    return coarse


class _RenderOnce:
    """``scene`` rendered whole once at ``pixel_m`` (on the first read); windows inside it are copies of that
    render (a renderer's pixel does not depend on the window: tests/engine/test_bands_speed.py), others rendered."""

    def __init__(self, scene, pixel_m: float):
        self.scene, self.pixel_m = scene, pixel_m
        self.bounded = bool(getattr(scene, "bounded", False))  # no ground beyond its extent (a cube)
        self.full: np.ndarray | None = None

    def shape_px(self, pixel_m: float | None = None) -> tuple[int, int]:
        return self.scene.shape_px(pixel_m)

    def render(self, window, *, pixel_m: float | None = None) -> np.ndarray:
        r0, c0, h, w = (int(v) for v in window)
        ny, nx = (int(v) for v in self.scene.shape_px(self.pixel_m))
        if pixel_m != self.pixel_m or r0 < 0 or c0 < 0 or r0 + h > ny or c0 + w > nx:
            return self.scene.render(tuple(window), pixel_m=pixel_m)
        if self.full is None:
            self.full = np.asarray(self.scene.render((0, 0, ny, nx), pixel_m=self.pixel_m))
        return self.full[r0 : r0 + h, c0 : c0 + w].copy()


def _same_layout(a, b) -> bool:
    if a is b:
        return True
    try:
        return type(a) is type(b) and bool(a == b)
    except (TypeError, ValueError):  # fields that do not compare (arrays): not known equal
        return False


def shared_render(reuse: dict, scene, pixel_m: float, max_bytes: float):
    """``scene`` behind the call's latest whole render when the grey layouts are equal (a new one otherwise; the
    previous one dropped), or ``scene`` itself when its whole render would exceed ``max_bytes`` (8 B a pixel)."""
    ny, nx = (int(v) for v in scene.shape_px(pixel_m))
    if 8.0 * ny * nx > max_bytes:
        return scene
    held = reuse.get("ground")
    if held is None or held.pixel_m != pixel_m or not _same_layout(held.scene, scene):
        held = reuse["ground"] = _RenderOnce(scene, pixel_m)
    return held
