"""Where each band of a banded system samples the ground (:func:`satchain.engine.bands.simulate_bands`): its
static ``registration_offset_px`` carried onto the ground through the image's map, less the ground's motion under
the Earth's rotation by the band's own time (with or without yaw steering). Private to the bands' engine; the
budget predicts the same offsets (:func:`satchain.prediction.budget.band_budgets`).

Examples
--------
>>> from satchain import load_preset
>>> s = load_preset("ankarasat3-pms")
>>> _offset_on_ground_px(s.for_band(1), (0.3, -0.2))  # no drift, no yaw: the offset itself
(0.3, -0.2)
"""

from __future__ import annotations

import math

from satchain.config.system import ImagingSystem

__all__: list[str] = []


def _earth_lead_px(system: ImagingSystem, index: int, s: ImagingSystem) -> tuple[float, float]:
    """(ALT, ACT) band px the ground under band ``index`` (system ``s``) has moved under the Earth's rotation (drift
    ``(eps, sigma)`` px a line: :mod:`satchain.engine.timepath`) when its row 0 starts, from the system's row 0
    start: ``n = [offset g / pitch + (g_b (1 - N_b) - g (1 - N)) / 2] / g_b`` of its lines later (``offset_alt_mm``
    places centre lines, crossed mid-TDI window; ``g``, ``N``: GSD ALT, TDI stages; ``_b``: the band's). On nominal
    grids the TDI terms cancel: the budget's ``earth_rotation``. (0, 0) without it.

    With yaw steering the detector is turned by ``gamma`` so that its columns follow the ground's motion: the drift
    is ``(0, eps')`` in the detector's frame (``eps' = |(x, y)| / g - 1``, the relative speed per line over the GSD),
    so the lead is ``(eps' n, 0)`` there -- no ACT part. The engine shifts the band's ground window before it turns
    the ground (:mod:`satchain.engine.yaw`: image pixel ``q`` sees ground ``P + M (q - P)``), so the lead is
    returned on the ground's axes, ``M (0, eps' n)`` in ``(x, y)``: ``(eps' n cos gamma, eps' n sin gamma)``
    (ALT, ACT), which the turned image shows as ``(eps' n, 0)``."""
    if not system.orbit.earth_rotation:
        return (0.0, 0.0)
    from satchain.tf.pushbroom import PushbroomTerms

    earth = PushbroomTerms(s).earth or {"tdi_drift_px_per_stage": (0.0, 0.0)}
    sigma, eps = earth["tdi_drift_px_per_stage"]
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
    given) less the Earth's lead (:func:`_earth_lead_px`, already on the ground's axes)."""
    earth = _earth_lead_px(system, index, s)
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
