"""A Bayer colour camera's edge measured and predicted side by side: each raw colour plane's MTF on its own
sampling grid, the demosaiced luminance's MTF50 and the false colour at a neutral edge, per demosaicing method.

:func:`measure_cfa` measures a :class:`satchain.engine.cfa_sim.CFAImages` (measurement only: slanted edges with
:func:`satchain.measure.edge.measure_edge`, chroma with :func:`satchain.engine.cfa.false_colour_amplitude`);
given the system it adds the predictions of :func:`predict_cfa` (:mod:`satchain.tf.cfa` on each colour's
:class:`satchain.tf.budget.SystemOTF`). It lives here, above both the engine and measure/, because it joins them.

The colour planes are measured on the photosites of their own colour only:

``red``, ``blue``
    every other row and column of the raw mosaic (a 2 px grid): frequencies per plane pixel / 2 = cy/px of the
    full array; the plane's own Nyquist is 0.25 cy/px.
``green``
    the quincunx turned onto its own square grid of pitch sqrt(2) px (plane[i, j] = the photosite at row
    ``r0 + i - j``, column ``c0 + i + j``: every green photosite of the region, none interpolated), measured by the
    slanted-edge method there (the edge, 5 deg from a column, is 40 deg from the turned grid's rows); frequencies
    per plane pixel / sqrt(2) = cy/px. Its grid's Nyquist is 1/(2 sqrt 2) = 0.354 cy/px (along the grid's axes);
    the quincunx's own first Brillouin zone reaches 1/(2p) along the array's axes (0.459 cy/px along a 5 deg
    normal), read from the same oversampled curve.

Each reading is the MTF along the edge normal, as the prediction (``plane_mtf`` at the normal's direction).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from satchain.config.sections_cfa import CFA_COLOURS, colour_system
from satchain.engine.cfa import REC709_LUMA, false_colour_amplitude, luminance
from satchain.errors import InputError
from satchain.tf.cfa import grid_nyquist_cy_per_px, nyquist_cy_per_px, plane_mtf
from satchain.units import MM_PER_M

__all__ = ["CFAMeasurement", "MethodFigures", "PlaneFigures", "measure_cfa", "predict_cfa"]

_PLANE_PX = {"red": 2.0, "blue": 2.0, "green": math.sqrt(2.0)}  # a plane pixel in photosites of the array
_SAMPLING = {
    "red": "every other row and column (2 px grid)",
    "blue": "every other row and column (2 px grid)",
    "green": "quincunx turned onto its sqrt(2) px grid",
}


@dataclass(frozen=True)
class PlaneFigures:
    """One colour plane's edge: the MTF at its grid's Nyquist ``f_grid_cy_per_px`` and at its Brillouin zone's
    Nyquist along the edge normal ``f_zone_cy_per_px`` (cy/px of the full array), and its MTF50 (cy/px),
    measured and (with a system) predicted; ``edge`` the plane's :class:`~satchain.measure.edge.EdgeResult`
    (its frequencies per plane pixel)."""

    colour: str
    sampling: str
    f_grid_cy_per_px: float
    f_zone_cy_per_px: float
    measured_at_grid_nyquist: float
    measured_at_zone_nyquist: float
    measured_mtf50_cy_per_px: float | None
    predicted_at_grid_nyquist: float | None = None
    predicted_at_zone_nyquist: float | None = None
    predicted_mtf50_cy_per_px: float | None = None
    edge: Any = field(default=None, repr=False)


@dataclass(frozen=True)
class MethodFigures:
    """One demosaicing method at the edge: the luminance's MTF50 (cy/px), the false colour ``peak`` and ``rms``
    near the edge and ``flat_peak`` in the flat regions away from it (fractions of the edge step)."""

    method: str
    mtf50_cy_per_px: float | None
    false_colour_peak: float
    false_colour_rms: float
    flat_peak: float


@dataclass(frozen=True)
class CFAMeasurement:
    """What :func:`measure_cfa` returns: ``planes`` (colour -> :class:`PlaneFigures`), ``methods`` (method ->
    :class:`MethodFigures`, plus ``"true"``: the three colour planes themselves, the optics' own colour fringe
    that a perfect interpolation would show), ``luminance_mtf50_predicted`` (cy/px: the BT.709 weighted sum of
    the colours' OTFs, a perfect interpolation; None without a system) and ``normal_deg`` (the edge normal's
    direction from +x towards +y)."""

    pattern: str
    planes: Mapping[str, PlaneFigures]
    methods: Mapping[str, MethodFigures]
    normal_deg: float
    luminance_mtf50_predicted: float | None = None

    def plane_rows(self) -> list[dict[str, Any]]:
        """The planes as table rows (dicts of plain numbers)."""
        keys = ("colour", "sampling", "f_grid_cy_per_px", "measured_at_grid_nyquist", "predicted_at_grid_nyquist",
                "f_zone_cy_per_px", "measured_at_zone_nyquist", "predicted_at_zone_nyquist",
                "measured_mtf50_cy_per_px", "predicted_mtf50_cy_per_px")  # fmt: skip
        return [{k: getattr(p, k) for k in keys} for p in self.planes.values()]

    def method_rows(self) -> list[dict[str, Any]]:
        """The methods side by side as table rows."""
        return [
            {"method": m.method, "luminance_mtf50_cy_per_px": m.mtf50_cy_per_px,
             "luminance_mtf50_predicted": self.luminance_mtf50_predicted, "false_colour_peak": m.false_colour_peak,
             "false_colour_rms": m.false_colour_rms, "flat_false_colour_peak": m.flat_peak}
            for m in self.methods.values()
        ]  # fmt: skip


def _sub(images, roi) -> tuple[np.ndarray, dict[str, np.ndarray], tuple[int, int, int, int]]:
    raw = np.asarray(images.raw, dtype=float)
    x0, y0, x1, y1 = (0, 0, raw.shape[1], raw.shape[0]) if roi is None else (int(v) for v in roi)
    if not (0 <= x0 < x1 <= raw.shape[1] and 0 <= y0 < y1 <= raw.shape[0]) or min(x1 - x0, y1 - y0) < 24:
        raise InputError(f"roi = {roi!r}: must be (x0, y0, x1, y1) inside the {raw.shape} image, >= 24 px a side")
    masks = {c: m[y0:y1, x0:x1] for c, m in images.masks.items()}
    return images.balanced()[y0:y1, x0:x1], masks, (x0, y0, x1, y1)


def colour_plane(sub: np.ndarray, masks: Mapping[str, np.ndarray], colour: str) -> np.ndarray:
    """``colour``'s photosites of a region on the plane's own grid (see the module's description).

    Examples
    --------
    >>> from satchain.engine.cfa import cfa_masks
    >>> m = cfa_masks((6, 6), "RGGB")
    >>> colour_plane(np.arange(36.0).reshape(6, 6), m, "blue").tolist()[0]
    [7.0, 9.0, 11.0]
    """
    m = masks[colour]
    if colour != "green":
        r, c = (int(v) for v in np.argwhere(m[:2, :2])[0])
        return sub[r::2, c::2]
    h, w = sub.shape
    n = (min(h, w) - 1) // 2
    c0 = 0 if m[n - 1, 0] else 1  # the first column so that (n - 1, c0) is a green photosite
    i, j = np.mgrid[0:n, 0:n]
    rows, cols = n - 1 + i - j, c0 + i + j
    return sub[rows, cols]


def _at(edge, f_cy_per_px: float, plane_px: float) -> float:
    return float(np.interp(f_cy_per_px * plane_px, edge.f_cy_per_px, edge.mtf))


def predict_cfa(system, *, normal_deg: float) -> dict[str, Any]:
    """The predicted figures along an edge normal at ``normal_deg`` (from +x towards +y): per colour
    ``{"grid": MTF at its grid's Nyquist, "zone": at its zone's Nyquist along the normal, "mtf50": cy/px}`` (the
    colour's system OTF, :func:`satchain.tf.cfa.plane_mtf`), and ``"luminance_mtf50"`` (cy/px; the MTF50 of the
    BT.709 weighted sum of the colours' OTFs: a perfect interpolation of a neutral edge). Pure prediction."""
    from satchain.tf.budget import SystemOTF

    pattern, det = system.detector.cfa, system.detector
    f = np.linspace(0.0, 1.0, 4001)
    out: dict[str, Any] = {}
    total = np.zeros(f.shape, dtype=complex)
    a = math.radians(normal_deg)
    fx, fy = f * math.cos(a) / (det.pitch_x_m * MM_PER_M), f * math.sin(a) / (det.pitch_y_m * MM_PER_M)
    for colour, w in zip(CFA_COLOURS, REC709_LUMA, strict=True):
        otf = SystemOTF(colour_system(system, colour))
        fg, fz = grid_nyquist_cy_per_px(colour), nyquist_cy_per_px(pattern, colour, direction_deg=normal_deg)
        at = plane_mtf(otf, [fg, fz], pitch_x_m=det.pitch_x_m, pitch_y_m=det.pitch_y_m, direction_deg=normal_deg)
        h = np.asarray(otf(fx, fy))
        out[colour] = {"grid": float(at[0]), "zone": float(at[1]), "mtf50": _mtf50(f, np.abs(h))}
        total += w * h
    out["luminance_mtf50"] = _mtf50(f, np.abs(total))
    return out


def _mtf50(f: np.ndarray, mtf: np.ndarray) -> float | None:
    """Where ``mtf`` first falls through 0.5 (linear between samples); None if it never does."""
    below = np.nonzero(mtf < 0.5)[0]
    return None if below.size == 0 else _crossing(f, mtf, int(below[0]))


def _crossing(f: np.ndarray, mtf: np.ndarray, k: int) -> float:
    """Where ``mtf`` falls through 0.5 between samples ``k - 1`` and ``k`` (linear)."""
    a, b = float(mtf[k - 1]), float(mtf[k])
    return float(f[k - 1] + (f[k] - f[k - 1]) * (a - 0.5) / (a - b))


def measure_cfa(
    images,
    roi: tuple[int, int, int, int] | None = None,
    *,
    system=None,
    fit_degree: int | str = 1,
    edge_band_px: float = 4.0,
    flat_margin_px: float = 8.0,
) -> CFAMeasurement:
    """Measure a colour camera's neutral slanted edge: each raw colour plane's MTF on its own grid, and per
    demosaicing method the luminance's MTF50 and the false colour across the edge.

    Parameters
    ----------
    images : CFAImages
        From :func:`satchain.engine.cfa_sim.simulate_cfa` (the raw mosaic is measured white-balanced).
    roi : (x0, y0, x1, y1), optional
        Half-open region of the image holding one edge (>= 24 px a side); the whole image by default.
    system : ImagingSystem, optional
        Adds the predictions (:func:`predict_cfa`) next to the measurements.
    fit_degree : 1, 2, 3 or "auto"
        Passed to :func:`~satchain.measure.edge.measure_edge` for the colour planes. Default 1 (ISO 12233's
        straight fit): on planes sampled this coarsely the edge positions of some phases wobble with the
        aliasing, which "auto" can read as line-of-sight motion.
    edge_band_px, flat_margin_px : float
        The false colour is measured within ``edge_band_px`` of the edge (px along the normal) and, as
        ``flat_peak``, beyond ``flat_margin_px`` of it.
    """
    from satchain.measure.edge import measure_edge

    sub, masks, (x0, y0, x1, y1) = _sub(images, roi)
    planes, edges = {}, {}
    for colour in CFA_COLOURS:
        edges[colour] = measure_edge(colour_plane(sub, masks, colour), fit_degree=fit_degree)
    normal = -float(edges["red"].angle_deg)  # the edge line's angle from y; its normal from +x towards +y
    pred = predict_cfa(system, normal_deg=normal) if system is not None else {}
    for colour in CFA_COLOURS:
        e, px = edges[colour], _PLANE_PX[colour]
        fg, fz = grid_nyquist_cy_per_px(colour), nyquist_cy_per_px(images.pattern, colour, direction_deg=normal)
        p = pred.get(colour, {})
        m50 = None if e.mtf50_cy_per_px is None else e.mtf50_cy_per_px / px
        planes[colour] = PlaneFigures(colour, _SAMPLING[colour], fg, fz, _at(e, fg, px), _at(e, fz, px), m50,
                                      p.get("grid"), p.get("zone"), p.get("mtf50"), e)  # fmt: skip
    red_at = tuple(int(v) for v in np.argwhere(masks["red"][:2, :2])[0])
    near, flat = _edge_bands(edges["red"], red_at, sub.shape, (edge_band_px, flat_margin_px))
    rgbs = {"true": images.true_rgb, **images.rgb}
    methods = {}
    for method, rgb in rgbs.items():
        rgb = np.asarray(rgb)[y0:y1, x0:x1]
        lum = measure_edge(luminance(rgb)[4:-4, 4:-4], fit_degree=fit_degree)
        fc = false_colour_amplitude(rgb, valid=near)
        fl = false_colour_amplitude(rgb, valid=flat, step=fc.step)
        methods[method] = MethodFigures(method, lum.mtf50_cy_per_px, fc.peak, fc.rms, fl.peak)
    return CFAMeasurement(images.pattern, planes, methods, normal, pred.get("luminance_mtf50"))


def _edge_bands(red_edge, red_at, shape: tuple[int, int], widths: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Pixels of the region within ``widths[0]`` px of the edge the red plane located, and beyond ``widths[1]``
    (4 px from the region's border left out: the demosaicing's own border)."""
    x_pl, y_pl = red_edge.edge_point_xy  # on the red plane's grid: pixel (i, j) is the region's (2 i + r, 2 j + c)
    t = math.radians(float(red_edge.angle_deg))
    y, x = np.mgrid[0 : shape[0], 0 : shape[1]].astype(float)
    d = np.abs((x - 2 * x_pl - red_at[1]) * math.cos(t) - (y - 2 * y_pl - red_at[0]) * math.sin(t))
    inner = np.zeros(shape, dtype=bool)
    inner[4:-4, 4:-4] = True
    return inner & (d < widths[0]), inner & (d > widths[1])
