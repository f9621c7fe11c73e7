"""Where each band of a banded system samples the ground (:func:`satchain.engine.bands.simulate_bands`): its
static ``registration_offset_px`` carried onto the ground through the image's map, less the ground's motion under
the Earth's rotation and a line-rate error by the band's own time (with or without yaw steering); and the window of
the ground truth it reads there (continued by the border rule beyond a ground truth that has no more ground).
Private to the bands' engine; the budget predicts the same offsets
(:func:`satchain.prediction.budget.band_budgets`).

Examples
--------
>>> from satchain import load_preset
>>> s = load_preset("ankarasat3-pms")
>>> _offset_on_ground_px(s.for_band(1), (0.3, -0.2))  # no drift, no yaw: the offset itself
(0.3, -0.2)
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from satchain.config.system import ImagingSystem
from satchain.engine.params import SimParams
from satchain.engine.sources import SceneSource
from satchain.engine.tiling import Window
from satchain.errors import ConfigError

__all__: list[str] = []


def _drift_lead_px(system: ImagingSystem, index: int, s: ImagingSystem) -> tuple[float, float]:
    """(ALT, ACT) band px the ground under band ``index`` (system ``s``) has moved beyond the nominal line rate under
    the Earth's rotation and ``motion.line_rate_error`` (their drift ``(eps, sigma)`` px a line, the pushbroom
    geometry's: :mod:`satchain.engine.timepath`) when its row 0 starts, from the system's row 0
    start: ``n = [offset g / pitch + (g_b (1 - N_b) - g (1 - N)) / 2] / g_b`` of its lines later (``offset_alt_mm``
    places centre lines, crossed mid-TDI window; ``g``, ``N``: GSD ALT, TDI stages; ``_b``: the band's). On nominal
    grids the TDI terms cancel: the budget's ``earth_rotation`` plus its ``line_rate``. (0, 0) without either.

    With yaw steering the detector is turned by ``gamma`` so that its columns follow the ground's motion: the drift
    is ``(0, eps')`` in the detector's frame (``eps' = |(x, y)| / g - 1``, the relative speed per line over the GSD),
    so the lead is ``(eps' n, 0)`` there -- no ACT part. The engine shifts the band's ground window before it turns
    the ground (:mod:`satchain.engine.yaw`: image pixel ``q`` sees ground ``P + M (q - P)``), so the lead is
    returned on the ground's axes, ``M (0, eps' n)`` in ``(x, y)``: ``(eps' n cos gamma, eps' n sin gamma)``
    (ALT, ACT), which the turned image shows as ``(eps' n, 0)``."""
    if not (system.orbit.earth_rotation or system.motion.line_rate_error):
        return (0.0, 0.0)
    from satchain.tf.pushbroom import PushbroomTerms

    terms = PushbroomTerms(s)
    earth = terms.earth or {}
    sigma, eps = terms.drift_px if terms.drift_px is not None else (0.0, 0.0)
    g, n_st, g_b, n_b = system.gsd_alt_m, system.detector.tdi_stages, s.gsd_alt_m, s.detector.tdi_stages
    lead_m = system.bands[index].offset_alt_mm * 1e-3 * g / system.detector.pitch_y_m
    n = (lead_m + (g_b * (1 - n_b) - g * (1 - n_st)) / 2.0) / g_b
    if system.orbit.yaw_steering:  # sigma = 0 in the detector's frame; the lead on the ground's axes
        gamma = math.radians(float(earth.get("rotation_deg", 0.0)))
        return (float(eps) * n * math.cos(gamma), float(eps) * n * math.sin(gamma))
    return (float(eps) * n, float(sigma) * n)


def _ground_shift_px(system: ImagingSystem, index: int, s: ImagingSystem, offset: tuple[float, float]) -> tuple:
    """(ALT, ACT) band px by which band ``index`` (system ``s``) samples the ground displaced: its
    ``registration_offset_px`` carried onto the ground (:func:`_offset_on_ground_px`, so that the image shows it as
    given) less the drift's lead (:func:`_drift_lead_px`, already on the ground's axes)."""
    earth = _drift_lead_px(system, index, s)
    a, c = _offset_on_ground_px(s, offset)
    return (a - earth[0], c - earth[1])


def _offset_on_ground_px(s: ImagingSystem, offset: tuple[float, float]) -> tuple[float, float]:
    """The ground displacement (ALT, ACT; band px, the ground's axes) that moves band ``s``'s image content by
    ``offset = (a, c)`` of its pixels: the linear part of the image's map onto the ground
    (:meth:`satchain.tf.pushbroom.PushbroomTerms.image_affine`, which the engine forms) applied to the offset.
    Row ``i``, column ``j`` see the ground at ``x = j + sigma i``, ``y = (1 + eps) i`` (px; ``(sigma, eps)`` the
    drift a line: Earth rotation and ``motion.line_rate_error``), turned about a pivot that moves with the grid by
    ``M = [[cos g, sin g], [-sin g, cos g]]`` (``g`` the yaw, steered; :mod:`satchain.engine.yaw`), so a ground
    shift ``d`` moves the content by ``D^-1 M^-1 d`` and the offset needs ``d = M D (c, a)``, in metres
    (``x``: ACT, ``y``: ALT; ``G_x``, ``G_y`` the GSDs)::

        x = G_x (c + sigma a),   y = G_y (1 + eps) a
        ACT = (x cos g + y sin g) / G_x,   ALT = (-x sin g + y cos g) / G_y

    Unsteered, ``sigma`` shears an ALT offset across track (-0.05 px a line at 40 deg: 0.3 px ALT showed 0.015
    px ACT) and ``1 + eps`` scales it (0.3 showed 0.297); steered, ``g`` turns it (-2.9 deg: the same 0.015 px).
    Without either the offset is the displacement itself (the identity, exactly)."""
    from satchain.tf.pushbroom import PushbroomTerms

    terms = PushbroomTerms(s)
    sigma, eps = terms.drift_px if terms.drift_px is not None else (0.0, 0.0)
    g = math.radians(float(terms.earth.get("rotation_deg", 0.0))) if terms.earth is not None else 0.0
    a, c = (float(v) for v in offset)
    if not (sigma or eps or g) or not (a or c):
        return (a, c)
    x_m, y_m = s.gsd_act_m * (c + sigma * a), s.gsd_alt_m * (1.0 + eps) * a
    cos_g, sin_g = math.cos(g), math.sin(g)
    return ((y_m * cos_g - x_m * sin_g) / s.gsd_alt_m, (x_m * cos_g + y_m * sin_g) / s.gsd_act_m)


class _ShiftedScene:
    """``scene`` seen from ``start`` (scene pixels at ``pixel_m``), ``shape`` pixels: renders windows of it. A
    ground truth with no ground beyond its extent (``bounded``: a reflectance cube) is continued there by the
    engine's border rule (``params.border``, as beyond any ground truth's edge)."""

    def __init__(self, scene, start: tuple[int, int], shape: tuple[int, int], pixel_m: float,
                 params: SimParams = SimParams()):  # noqa: B008  # fmt: skip
        self.scene, self.start, self.shape, self.pixel_m, self.params = scene, start, shape, pixel_m, params
        self.grid: tuple[tuple[float, float], tuple[int, int]] | None = None  # set by _band_source

    def shape_px(self, pixel_m: float | None = None) -> tuple[int, int]:
        return self.shape

    def render(self, window, *, pixel_m: float | None = None) -> np.ndarray:
        r0, c0, h, w = (int(v) for v in window)
        r0, c0 = r0 + self.start[0], c0 + self.start[1]
        ny, nx = (int(v) for v in self.scene.shape_px(self.pixel_m))
        if getattr(self.scene, "bounded", False) and not (r0 >= 0 and c0 >= 0 and r0 + h <= ny and c0 + w <= nx):
            from satchain.engine.sources import BorderedWindow

            p = self.params
            src = SceneSource(self.scene, pixel_m=self.pixel_m)
            return np.asarray(BorderedWindow(src, Window(r0, c0, h, w), rule=p.border, value=p.border_value))
        return self.scene.render((r0, c0, h, w), pixel_m=self.pixel_m)


def _band_source(scene, window: Window, pixel_m: float, s: ImagingSystem, offset_px,
                 params: SimParams = SimParams()) -> tuple[Any, tuple, tuple]:  # noqa: B008  # fmt: skip
    """The ground truth band ``s`` samples (a scene, or a window of it), the detector grid's phase on it (scene
    pixels) and the output shape: the grid starts at the window's corner moved by ``-offset_px`` band pixels."""
    start, phase, shape, n_out = [], [], [], []
    for ax, (lo, n, g) in enumerate(((window.row0, window.height, s.gsd_alt_m), (window.col0, window.width,
                                                                                  s.gsd_act_m))):  # fmt: skip
        k = g / pixel_m
        m = int(math.floor(n / k + 1e-9))
        if m < 1:
            raise ConfigError(f"window = {tuple(window)!r} at pixel_m = {pixel_m!r}: smaller than one pixel of "
                              f"band {s.name!r} ({g:.4g} m)")  # fmt: skip
        o = lo - float(offset_px[ax]) * k
        o_int = int(math.floor(o + 1e-9))
        f = max(o - o_int, 0.0)
        start.append(o_int)
        phase.append(f)
        shape.append(max(n, int(math.ceil(f + m * k - 1e-9))))
        n_out.append(m)
    if tuple(start) == (0, 0) and tuple(shape) == tuple(scene.shape_px(pixel_m)):
        return scene, (phase[0], phase[1]), (n_out[0], n_out[1])  # the scene itself: today's path exactly
    view = _ShiftedScene(scene, (start[0], start[1]), (shape[0], shape[1]), pixel_m, params)
    view.grid = ((start[0] + phase[0], start[1] + phase[1]), (n_out[0], n_out[1]))  # its grid's corner, pixels
    return view, (phase[0], phase[1]), (n_out[0], n_out[1])


def _warn_beyond(scene, view, pixel_m: float, s: ImagingSystem, name: str, params: SimParams) -> None:
    """Warn when band ``name``'s displaced grid (``view``, a :class:`_ShiftedScene`) reaches a whole pixel or more
    beyond a bounded ground truth (a cube): those pixels see the cube continued by the border rule, not ground."""
    import warnings

    from satchain.errors import SatchainWarning

    if not getattr(scene, "bounded", False) or not isinstance(view, _ShiftedScene) or view.grid is None:
        return
    full = scene.shape_px(pixel_m)
    (corner, n_out) = view.grid
    beyond = max(max(-corner[ax] * pixel_m / g, corner[ax] * pixel_m / g + n_out[ax] - int(full[ax]) * pixel_m / g)
                 for ax, g in enumerate((s.gsd_alt_m, s.gsd_act_m)))  # fmt: skip
    if beyond >= 1.0:
        warnings.warn(f"band {name!r}: its grid, displaced over its delay (the Earth's rotation, a line-rate error) "
                      f"or by its registration offset, reaches {beyond:.1f} of its pixels beyond the ground truth; "
                      f"there it sees the ground truth continued by border = {params.border!r}",
                      SatchainWarning, stacklevel=4)  # fmt: skip
