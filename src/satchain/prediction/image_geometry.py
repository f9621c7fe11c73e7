"""Where a pushbroom run's image puts the ground, row by row: the mean map plus each row's line-of-sight
displacement (issue 29, item 12).

:meth:`satchain.tf.pushbroom.PushbroomTerms.image_affine` is the image's *mean* geometry (the drifts of Earth
rotation and a line-rate error, a yaw). Oscillations, jitter and a line-of-sight log also move every image row
``i`` by its window mean ``(dx_i, dy_i)`` (detector pixels, ACT and ALT; :mod:`satchain.engine.timepath`): row
``i``, column ``j`` sees the ground point of the static image's pixel ``(j + sigma (i + N/2) + dx_i, i + eps (i +
N/2) + dy_i)``, that is the mean map's point of image pixel ``(j + dx_i - sigma dy_i / (1 + eps), i + dy_i / (1 +
eps))``. A slow oscillation thus bends a straight ground edge; :class:`ImageGeometry` predicts, for every line
an edge measurement uses, where the edge crosses it, and the angle the measurement's own fit of those positions
gives (a polynomial of the degree it chose, its slope at the lines' mean), so that the run compares the measured
angle with the angle the image should show (not with the straight edge of the mean map).

:func:`geometry_table` lists the motion inputs and the geometry they make (latitude, inclination, pass direction,
shear, along-track scale, TDI drift, rotation, each oscillation's row displacement) for results.json and the
report.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from affine import Affine

    from satchain.tf.pushbroom import PushbroomTerms

__all__ = ["ImageGeometry", "geometry_table", "run_geometry"]


@dataclass(frozen=True)
class ImageGeometry:
    """A run image's geometry: ``to_image`` (``affine.Affine``, truth metres -> image ``(col, row)``, pixel centres
    at integers: the mean map), ``drift_px`` the ``(sigma, eps)`` drifts per line it holds, ``dx_px`` / ``dy_px``
    each image row's line-of-sight displacement (ACT, ALT; the drifts left out) and ``edges`` the truth's edge
    lines by id, ``(point_m, direction_m)`` in truth metres."""

    to_image: Affine
    drift_px: tuple[float, float]
    dx_px: np.ndarray = field(repr=False)
    dy_px: np.ndarray = field(repr=False)
    edges: dict = field(default_factory=dict, repr=False)
    terms: PushbroomTerms | None = field(default=None, repr=False, compare=False)  # an edge as imaged
    bars: dict = field(default_factory=dict, repr=False)  # the truth's bar-target records by id (their CTF)
    background: float = 0.0  # the scene's background reflectance around the targets

    @property
    def steps_m(self) -> tuple[float, float]:
        """The ground metres along x of one column step and along y of one row step (what an axis-aligned
        measurement converts its pixels with; the ALT one carries the along-track scale)."""
        a, _, _, _, e, _ = tuple(~self.to_image)[:6]
        return abs(a), abs(e)

    @property
    def moves(self) -> bool:
        """Whether the rows are displaced besides the mean map (oscillations, jitter, a line-of-sight log)."""
        return bool(np.ptp(self.dx_px) > 1e-6 or np.ptp(self.dy_px) > 1e-6)  # (the drifts' rounding left out)

    def _row_offsets(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The image-pixel offsets ``(du, dv)`` of the mean map's point that rows ``rows`` (fractional: linear
        between rows) see."""
        n = np.arange(self.dx_px.size, dtype=float)
        dx, dy = np.interp(rows, n, self.dx_px), np.interp(rows, n, self.dy_px)
        sigma, eps = self.drift_px
        return dx - sigma * dy / (1.0 + eps), dy / (1.0 + eps)

    def ground_m(self, cols, rows) -> tuple[np.ndarray, np.ndarray]:
        """The truth's point (m) that image pixel ``(cols, rows)`` sees, row displacements included."""
        cols, rows = np.broadcast_arrays(np.asarray(cols, float), np.asarray(rows, float))
        du, dv = self._row_offsets(rows)
        a, b, c, d, e, f = tuple(~self.to_image)[:6]
        u, v = cols + du, rows + dv
        return a * u + b * v + c, d * u + e * v + f

    def edge_positions_px(self, edge_id: str, lines, axis: str) -> np.ndarray:
        """Where each image line crosses edge ``edge_id``: for ``axis = "ACT"`` (a near-vertical edge) the column
        at which each row of ``lines`` crosses it, for ``"ALT"`` the row at which each column does (full-image
        pixels, NaN where the line does not cross it inside the image)."""
        (px, py), (ux, uy) = self.edges[edge_id]
        lines = np.asarray(lines, float)
        n_rows, act = self.dx_px.size, str(axis).upper() == "ACT"
        a, b, c, d, e, f = tuple(~self.to_image)[:6]
        out = np.full(lines.shape, np.nan)
        for k, line in enumerate(lines):
            if act:  # along the row the map is affine in the column: one exact solution
                du, dv = self._row_offsets(np.array([line]))
                u0, v = du[0], line + dv[0]
                g0 = ux * (d * u0 + e * v + f - py) - uy * (a * u0 + b * v + c - px)
                slope = ux * d - uy * a
                out[k] = -g0 / slope if slope != 0 else np.nan
                continue
            rows = np.arange(n_rows, dtype=float)  # along the column: the zero crossing, linear between rows
            gx, gy = self.ground_m(np.full(n_rows, line), rows)
            g = ux * (gy - py) - uy * (gx - px)
            s = np.flatnonzero(np.sign(g[:-1]) * np.sign(g[1:]) <= 0)
            if s.size:
                i = int(s[0])
                out[k] = i + (g[i] / (g[i] - g[i + 1]) if g[i] != g[i + 1] else 0.0)
        return out

    def edge_angle_deg(self, edge_id: str, lines, measured_px, fit_degree: int, axis: str) -> float | None:
        """The angle (truth's convention) the edge measurement gives of edge ``edge_id`` on this image: its fit
        (a polynomial of ``fit_degree``, the slope at the mean line) of the positions this geometry predicts on
        the ``lines`` whose position it measured (``measured_px`` finite); None when fewer than 3 such lines."""
        if edge_id not in self.edges or lines is None or measured_px is None:
            return None
        lines = np.asarray(lines, float)
        ok = np.isfinite(np.asarray([np.nan if v is None else v for v in measured_px], float))
        pos = self.edge_positions_px(edge_id, lines[ok], axis)
        good = np.isfinite(pos)
        deg = int(min(max(int(fit_degree or 1), 1), 3))
        if np.count_nonzero(good) < max(3, deg + 2):
            return None
        x, y = lines[ok][good], pos[good]
        coef = np.polyfit(x - x.mean(), y, deg)
        slope = float(np.polyval(np.polyder(coef), 0.0))
        return math.degrees(math.atan(slope))  # act: from +y towards +x; alt: from +x towards +y (the same form)

    def displacement_transfer(self, rows, f_cy_per_px, axis: str) -> np.ndarray:
        """``|mean over rows of exp(2 pi i f d_i)|``: what averaging the ``rows`` (whose ``axis`` displacement is
        ``d_i``) along a pattern does to its component of ``f`` cycles per pixel (1 without displacement)."""
        rows = np.asarray(rows, int)
        d = (self.dx_px if str(axis).upper() == "ACT" else self.dy_px)[rows]
        f = np.atleast_1d(np.asarray(f_cy_per_px, float))
        return np.abs(np.mean(np.exp(2j * np.pi * np.outer(d - d.mean(), f)), axis=0))


def run_geometry(system, truth: dict, simulator, shape: tuple[int, int]) -> ImageGeometry | None:
    """The :class:`ImageGeometry` of a run's image of ``shape`` simulated by ``simulator`` (its time path gives
    the rows' displacements), truth metres from ``truth``'s origin; None for a static system."""
    from affine import Affine

    from satchain.measure.auto import truth_origin_m
    from satchain.scene.targets import BarTarget, SlantedEdge
    from satchain.tf.pushbroom import PushbroomTerms, window_means

    terms = PushbroomTerms(system)
    if not terms.active:
        return None
    ox, oy = truth_origin_m(truth)
    to_image = terms.image_affine((shape[0], shape[1])) @ Affine.translation(-ox, -oy)
    drift = terms.drift_px if terms.drift_px is not None else (0.0, 0.0)
    n = int(shape[0])
    tp = getattr(simulator, "time_path", None)
    dx = dy = np.zeros(n)
    if tp is not None:
        k, m = tp.window_samples, tp.samples_per_line
        dy, dx = (window_means(d[: (n - 1) * m + k], m, k) for d in (tp.dy, tp.dx))
        mid = np.arange(n) + tp.stages / 2.0  # each row's window-mean time, in lines: the drifts' part
        dx, dy = dx - tp.drift_px[0] * mid, dy - tp.drift_px[1] * mid
    edges = {}
    for it in truth.get("items", []):
        if it.get("kind") == SlantedEdge.kind and "edge_point_m" in it and "edge_direction" in it:
            edges[str(it["id"])] = (tuple(map(float, it["edge_point_m"])), tuple(map(float, it["edge_direction"])))
    bars = {str(it["id"]): it for it in truth.get("items", []) if it.get("kind") == BarTarget.kind and "groups" in it}
    drift = (float(drift[0]), float(drift[1]))
    return ImageGeometry(
        to_image, drift, np.asarray(dx), np.asarray(dy), edges, terms, bars, float(truth.get("background", 0.0))
    )


def geometry_table(system) -> list[dict]:
    """The motion inputs and the image geometry they make, as rows ``{"quantity", "value", "unit"}`` (empty for
    a static system): what results.json's ``image_geometry`` and the report's table show."""
    from satchain.tf.pushbroom import PushbroomTerms

    terms = PushbroomTerms(system)
    g = terms.geometry()
    if g is None:
        return []
    orb, mot = system.orbit, system.motion
    rows = [("line time", g["line_time_s"] * 1e6, "us"), ("TDI stages", g["tdi_stages"], "")]
    if orb.earth_rotation:
        e = g["earth_rotation"]
        rows += [("latitude", orb.latitude_deg, "deg"), ("inclination", orb.inclination_deg, "deg"),
                 ("pass direction", orb.pass_direction, ""), ("yaw steering", bool(orb.yaw_steering), ""),
                 ("track heading", e["track_heading_deg"], "deg east of north")]  # fmt: skip
    rows += [
        ("line-rate error", mot.line_rate_error, ""),
        ("shear (ACT per line)", g["shear_act_px_per_line"], "px"),
        ("shear angle", g["shear_deg"], "deg"),
        ("along-track scale", g["alt_scale"], "ALT ground step / GSD"),
        ("image ground step ACT (the GSD)", system.gsd_act_m, "m"),
        ("image ground step ALT (GSD x along-track scale)", system.gsd_alt_m * g["alt_scale"], "m"),
        ("image rotation (yaw)", g["rotation_deg"], "deg"),
        ("TDI drift over the window, ACT", g["tdi_drift_px"]["act"], "px"),
        ("TDI drift over the window, ALT", g["tdi_drift_px"]["alt"], "px"),
    ]
    for k, (osc, o) in enumerate(zip(mot.oscillation, g.get("oscillations", []), strict=False), start=1):
        rows += [
            (f"oscillation {k}", f"{osc.axis.upper()} {osc.amplitude_px:g} px at {osc.frequency_hz:g} Hz, "
                                 f"phase {osc.phase_deg:g} deg", ""),
            (f"oscillation {k}: cycles per TDI window", o["cycles_per_window"], ""),
            (f"oscillation {k}: row displacement amplitude", o["line_displacement_amplitude_px"], "px"),
        ]  # fmt: skip
    for axis, p in (g.get("jitter_psd") or {}).items():
        text = f"{p['sigma_px']:.4g} ({p['sigma_blur_px']:.4g}, {p['line_displacement_rms_px']:.4g})"
        rows.append((f"jitter PSD {axis.upper()}: sigma (blur, row displacement rms)", text, "px"))
    for axis in ("act", "alt"):
        rows.append((f"row displacement rms, {axis.upper()}", g["line_displacement_rms_px"][axis], "px"))
    return [{"quantity": q, "value": v, "unit": u} for q, v, u in rows]
