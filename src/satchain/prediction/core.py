"""Predicted figures of merit, evaluated the way each measurement sees them (the prediction half of a run).

Everything here is prediction: the system OTF (``satchain.tf``), Coltman's CTF (:mod:`satchain.tf.ctf`), the
wedge resolution and the Siemens star's MTF measured on their noise-free predicted images
(:mod:`satchain.prediction.wedge`, :mod:`satchain.prediction.star`) and GIQE 5 (:mod:`satchain.prediction.quality`).
:func:`predict` evaluates them once per run for the targets of a truth record and returns a frozen
:class:`Predictions`; :func:`satchain.comparison.compare` then puts measurements beside them without needing
the system.

Frequencies are in cycles per pixel (cy/px) along a direction ``(ux, uy)`` of the image plane: x = ACT
(columns), y = ALT (rows). Square detector pixels are assumed for the cy/mm <-> cy/px conversion
(``satchain run`` refuses other systems).

Examples
--------
>>> gauss = lambda fx, fy: np.exp(-(fx**2) - 4 * fy**2)  # a 2-D MTF in cy/px, worse along y (ALT)
>>> p = predict_from_mtf(gauss, {"items": []}, gsd_m=1.0)
>>> round(float(p.mtf_along["ACT"](0.5)), 6), round(float(p.mtf_along["ALT"](0.5)), 6)
(0.778801, 0.367879)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from satchain._argcheck import checked
from satchain.errors import InputError
from satchain.prediction.star import StarPrediction, predict_stars
from satchain.prediction.wedge import PLACEMENTS_PX, WEDGE_AXES, WedgePrediction, predict_wedge
from satchain.scene.targets import HyperbolicWedge, SlantedEdge

if TYPE_CHECKING:
    from satchain.prediction.image_geometry import ImageGeometry
    from satchain.scene.truth import Truth

__all__ = [
    "DIRECTIONS",
    "NYQUIST_CY_PER_PX",
    "WEDGE_AXES",
    "AxisMTF",
    "EdgePrediction",
    "Predictions",
    "StarPrediction",
    "WedgePrediction",
    "predict",
    "predict_from_mtf",
    "system_mtf_cy_per_px",
]

#: Unit directions ``(ux, uy)`` (x = ACT, y = ALT) of the measured axes.
DIRECTIONS: dict[str, tuple[float, float]] = {
    "ACT": (1.0, 0.0),
    "ALT": (0.0, 1.0),
    "D45": (math.sqrt(0.5), math.sqrt(0.5)),
    "D135": (math.sqrt(0.5), -math.sqrt(0.5)),
}
#: The Nyquist frequency of a sampled image along any axis of its pixel grid, cy/px.
NYQUIST_CY_PER_PX = 0.5

MTF2D = Callable[[np.ndarray, np.ndarray], np.ndarray]


class AxisMTF:
    """A 2-D MTF (a callable of ``(fx, fy)`` in cy/px) along the unit direction ``(ux, uy)``, as a callable of
    cy/px along that direction (the magnitude of a complex OTF is taken). ``cutoff`` (cy/px) is copied from
    ``mtf2d.cutoff`` when it has one, which makes Coltman's series a finite sum.

    Examples
    --------
    >>> m = AxisMTF(lambda fx, fy: 1.0 - np.hypot(fx, 2 * fy), (0.0, 1.0))
    >>> float(m(0.25))
    0.5
    """

    def __init__(self, mtf2d: MTF2D, direction: tuple[float, float]):
        n = math.hypot(*direction)
        if not n > 0:
            raise InputError(f"direction = {direction!r}: must be a non-zero (ux, uy) vector")
        self._mtf2d = mtf2d
        self.ux, self.uy = float(direction[0]) / n, float(direction[1]) / n
        cutoff = getattr(mtf2d, "cutoff", None)
        if cutoff is not None:
            self.cutoff = float(cutoff)

    def __call__(self, f_cy_per_px) -> np.ndarray:
        f = np.asarray(f_cy_per_px, dtype=float)
        return np.abs(np.asarray(self._mtf2d(f * self.ux, f * self.uy)))


class _SystemOTF:
    """A SystemOTF as a callable of cy/px, complex (the phase kept: a smear's sinc changes sign), with the
    components named in ``exclude`` left out: what forms the predicted wedge image."""

    def __init__(self, otf: Any, exclude: tuple[str, ...] = ()):
        self._mtf = _SystemMTF(otf, exclude)
        self.cutoff = self._mtf.cutoff

    def __call__(self, fx_cy_per_px, fy_cy_per_px) -> np.ndarray:
        m = self._mtf
        return m._otf(*m.detector_cy_per_mm(fx_cy_per_px, fy_cy_per_px), exclude=m._exclude)  # image axes


class _SystemMTF:
    """A SystemOTF as a callable of cy/px (square pixels of pitch sqrt(px py)), with its cutoff in cy/px;
    the components named in ``exclude`` are left out.  Frequencies are on the **image's** axes: where pushbroom
    terms space the image rows ``alt_scale`` detector pixels apart on the ground (a line-rate error ``e``:
    ``1 + e``; Earth rotation; :meth:`~satchain.tf.pushbroom.PushbroomTerms.geometry`), ``fy`` cycles per image
    row are ``fy / alt_scale`` cycles per detector pixel (the budget's own tables stay on the detector's axis). A
    shear ``sigma`` (Earth rotation: row ``i`` sees the ground ``sigma i`` px across) tilts the image's axes on the
    detector too: image row ``i``, column ``j`` sees the blurred focal plane at detector ``(j + sigma i, alt_scale
    i)``, so the image's wave vector ``(fx, fy)`` is the detector's ``(fx, (fy - sigma fx) / alt_scale)`` (a star's
    diagonals see it at first order: ``-+ sigma`` on the ALT part, 6.6 % at the equator)."""

    def __init__(self, otf: Any, exclude: tuple[str, ...] = ()):
        from satchain import units

        d = otf.system.detector
        self._otf = otf
        self._exclude = tuple(exclude)
        self.pitch_m = math.sqrt(d.pitch_x_m * d.pitch_y_m)
        self._to_mm = float(units.cy_per_px_to_cy_per_mm(1.0, pitch_m=self.pitch_m))
        self.cutoff = float(units.cy_per_mm_to_cy_per_px(otf.cutoff_cy_per_mm, pitch_m=self.pitch_m))
        pb = getattr(otf, "pushbroom", None)
        geo = pb.geometry() if pb is not None and pb.active else None
        self.alt_scale = 1.0 if geo is None else float(geo["alt_scale"])  # image rows apart, in detector px
        self.shear = 0.0 if geo is None else float(geo["shear_act_px_per_line"])  # ACT px per image row

    def detector_cy_per_mm(self, fx_cy_per_px, fy_cy_per_px) -> tuple[np.ndarray, np.ndarray]:
        """The detector's frequencies (cy/mm) of the image's wave vector ``(fx, fy)`` (cy per image px)."""
        fx, fy = np.asarray(fx_cy_per_px), np.asarray(fy_cy_per_px)
        fy_det = (fy - self.shear * fx) / self.alt_scale if self.shear else fy / self.alt_scale
        return fx * self._to_mm, fy_det * self._to_mm

    def __call__(self, fx_cy_per_px, fy_cy_per_px) -> np.ndarray:
        return np.abs(self._otf(*self.detector_cy_per_mm(fx_cy_per_px, fy_cy_per_px), exclude=self._exclude))


#: Components whose PSF is far wider than any target's measurement region (the aerosol adjacency spreads a
#: fraction ``s`` of the light over ``aerosol_psf_scale_m``, 200 m by default). A local measurement (edge, star,
#: bars, wedge) normalises by the levels it sees around the target, which already hold that scattered light,
#: so the plateau ``1 - s`` the component puts on every image frequency is invisible to it; predicting it
#: would put the prediction ``1 - s`` below any correct measurement. Left out of the local predictions.
WIDE_COMPONENTS = ("aerosol",)


def system_mtf_cy_per_px(otf: Any, *, local: bool = False) -> MTF2D:
    """The system MTF of a :class:`~satchain.tf.budget.SystemOTF` as a callable of ``(fx, fy)`` in cy/px.

    ``local=True``: as a measurement on a target far smaller than the aerosol adjacency scale sees it
    (:data:`WIDE_COMPONENTS` left out)."""
    names = getattr(otf, "component_names", ())
    return _SystemMTF(otf, tuple(c for c in WIDE_COMPONENTS if c in names) if local else ())


@dataclass(frozen=True)
class EdgePrediction:
    """A slanted edge's prediction: the system MTF along its normal (the e-SFR's axis).

    ``normal`` is the unit vector ``(nx, ny)`` towards the bright side (x = ACT, y = ALT); ``mtf_at_nyquist``
    the MTF at 0.5 cy/px along it; ``mtf`` the MTF along it as a callable of cy/px.
    """

    id: str
    normal: tuple[float, float]
    mtf_at_nyquist: float
    mtf: Callable[[Any], np.ndarray] = field(repr=False, compare=False)


@dataclass(frozen=True)
class Predictions:
    """Everything :func:`satchain.comparison.compare` needs from the prediction side (no system object).

    Attributes
    ----------
    mtf_along : mapping
        ``"ACT" | "ALT" | "D45" | "D135"`` -> MTF along that axis, a callable of cy/px.
    edges : mapping
        Truth id -> :class:`EdgePrediction` for every slanted edge of the truth record.
    wedges : mapping
        Wedge id -> :class:`~satchain.prediction.wedge.WedgePrediction` for every wedge of the truth record: its
        resolution measured on its noise-free predicted image (never clamped to the GSD), the spread over
        sub-pixel placements and the predicted contrast scan.
    stars : mapping
        Star id -> :class:`~satchain.prediction.star.StarPrediction` for every Siemens star of the truth record: its
        MTF per direction measured on its noise-free predicted image (the same calibration, annuli and input
        modulation as the measured star); empty when made without a truth star (the system MTF is compared).
    giqe5, rer, snr : float
        Predicted NIIRS (GIQE 5), its RER (GIQE 5 combination of the axes) and contrast SNR.
    gsd_los_m, elevation_deg : float
        Line-of-sight GSD (m) and elevation (degrees) with which a measured RER and SNR give a measured NIIRS.
    wedge_threshold : float
        Contrast at which a wedge stops resolving.
    warnings : tuple of str
        Predicted problems (saturated targets).
    geometry : satchain.prediction.image_geometry.ImageGeometry, optional
        A pushbroom image's geometry row by row (its mean map and each row's line-of-sight displacement): the
        edges' angles are predicted through it, as the edge measurement fits the positions it predicts.
    """

    mtf_along: Mapping[str, Callable[[Any], np.ndarray]] = field(repr=False)
    edges: Mapping[str, EdgePrediction]
    wedges: Mapping[str, WedgePrediction]
    giqe5: float = float("nan")
    rer: float = float("nan")
    snr: float = float("nan")
    gsd_los_m: float = float("nan")
    elevation_deg: float = 90.0
    wedge_threshold: float = 0.15
    warnings: tuple[str, ...] = ()
    mtf2d: MTF2D | None = field(default=None, repr=False, compare=False)
    stars: Mapping[str, StarPrediction] = field(default_factory=dict)
    geometry: ImageGeometry | None = field(default=None, repr=False, compare=False)

    def edge(self, edge_id: str, direction: str) -> EdgePrediction:
        """The prediction of edge ``edge_id``; an edge the truth does not list gets its axis ``direction``."""
        if edge_id in self.edges:
            return self.edges[edge_id]
        m = self.mtf_along[direction.upper()]
        return EdgePrediction(edge_id, DIRECTIONS[direction.upper()], float(m(NYQUIST_CY_PER_PX)), m)


def predict_from_mtf(
    mtf2d: MTF2D,
    truth: Mapping[str, Any],
    *,
    gsd_m: float,
    wedge_threshold: float = 0.15,
    quality: Mapping[str, float] | None = None,
    gsd_los_m: float | None = None,
    elevation_deg: float = 90.0,
    warnings: tuple[str, ...] = (),
    otf2d: MTF2D | None = None,
    noise_sigma: Callable[[np.ndarray], np.ndarray] | None = None,
    image_grid_m: tuple | None = None,
) -> Predictions:
    """Predictions from a 2-D MTF in cy/px (square ground pixels of ``gsd_m`` metres; ``image_grid_m = ((step_x,
    step_y), (x0, y0))``: the image's ground steps along its columns and rows and its pixel (0, 0)'s corner when
    its geometry scales them, e.g. a pushbroom image's along-track scale: a wedge is then predicted on that grid,
    its OTF on the image's axes).

    ``quality`` holds the predicted ``giqe5``, ``rer_giqe5`` and ``snr`` (as
    :func:`satchain.prediction.quality.predict_quality` gives them); without it the NIIRS figures are NaN.
    ``otf2d`` is the complex OTF (cy/px) that forms the predicted wedge images (default ``mtf2d``, exact when the
    OTF is real and non-negative); the wedges are rendered at the truth's ``pixel_m`` on its ``background``
    (:func:`satchain.prediction.wedge.predict_wedge`); ``noise_sigma`` (per-pixel noise in reflectance as a
    function of reflectance, :func:`sensor_noise_reflectance`) gives their crossings' 1-sigma from noise. The
    stars' measured MTF is predicted on their noise-free predicted images formed with ``otf2d`` too
    (:func:`satchain.prediction.star.predict_stars`).
    """
    along = {d: AxisMTF(mtf2d, u) for d, u in DIRECTIONS.items()}
    edges = {}
    for it in truth.get("items", []):
        if it.get("kind") != SlantedEdge.kind:
            continue
        nx, ny = (float(v) for v in it["normal_to_bright"])
        m = AxisMTF(mtf2d, (nx, ny))
        edges[str(it["id"])] = EdgePrediction(str(it["id"]), (m.ux, m.uy), float(m(NYQUIST_CY_PER_PX)), m)
    otf = mtf2d if otf2d is None else otf2d
    wedges = _predict_wedges(otf, truth, gsd_m, wedge_threshold, noise_sigma, image_grid_m)
    q = quality or {}
    return Predictions(
        mtf_along=along,
        edges=edges,
        wedges=wedges,
        giqe5=float(q.get("giqe5", float("nan"))),
        rer=float(q.get("rer_giqe5", float("nan"))),
        snr=float(q.get("snr", float("nan"))),
        gsd_los_m=float(gsd_m if gsd_los_m is None else gsd_los_m),
        elevation_deg=float(elevation_deg),
        wedge_threshold=float(wedge_threshold),
        warnings=tuple(warnings),
        mtf2d=mtf2d,
        stars=predict_stars(otf, truth, gsd_m=gsd_m),
    )


def sensor_noise_reflectance(sensor: Any) -> Callable[[np.ndarray], np.ndarray] | None:
    """The per-pixel noise of ``sensor`` (a SensorModel) in reflectance units, as a function of reflectance:
    shot noise of signal, path radiance and dark charge, read noise, PRNU, DSNU and (finite full well)
    quantisation; None without a sensor."""
    if sensor is None:
        return None

    def sigma(refl: np.ndarray) -> np.ndarray:
        e = sensor.offset_e + sensor.dark_e + np.clip(refl, 0, None) * sensor.electrons_per_unit
        q = (sensor.full_well_e / 2 ** int(sensor.bit_depth)) ** 2 / 12 if np.isfinite(sensor.full_well_e) else 0.0
        var = e + sensor.read_noise_e**2 + (sensor.prnu * e) ** 2 + sensor.dsnu_e**2 + q
        return np.sqrt(var) / sensor.electrons_per_unit

    return sigma


class _OnImageAxis:
    """An OTF of the image's cy/px (its columns and rows) on a render grid whose square pixels are ``(sx, sy)``
    image pixels (a wedge predicted on the ground step across its stripes): ``f`` cycles per render pixel are
    ``f / s`` per image pixel."""

    def __init__(self, otf2d: MTF2D, sx: float, sy: float):
        self._otf, self._s = otf2d, (float(sx), float(sy))
        cutoff = getattr(otf2d, "cutoff", None)
        if cutoff is not None:
            self.cutoff = float(cutoff) * max(self._s)

    def __call__(self, fx, fy) -> np.ndarray:
        return self._otf(np.asarray(fx) / self._s[0], np.asarray(fy) / self._s[1])


def _predict_wedges(otf2d: MTF2D, truth: Mapping[str, Any], gsd_m: float, threshold: float,
                    noise: Callable | None = None, grid_m: tuple | None = None) -> dict:  # fmt: skip
    """Wedge id -> WedgePrediction (resolution None, with the reason, when the predicted image has no wedge
    the scan can measure); with ``grid_m`` (:func:`predict_from_mtf`) each on the image's grid: square pixels
    of its ground step across the stripes, placed as the image's rows and columns, the OTF on its axes."""
    out = {}
    truth_px = float(truth.get("pixel_m") or gsd_m / 10.0)
    background = float(truth.get("background", 0.2))
    for it in truth.get("items", []):
        if it.get("kind") != HyperbolicWedge.kind:
            continue
        axis = WEDGE_AXES[str(it["orientation"]).lower()]
        otf: MTF2D = otf2d
        step_m = gsd_m
        own: tuple[float, ...] = (0.0, 0.0)
        if grid_m is not None and (step := {"ACT": grid_m[0][0], "ALT": grid_m[0][1]}.get(axis)) is not None:
            otf = _OnImageAxis(otf2d, step / grid_m[0][0], step / grid_m[0][1])
            step_m, own = step, tuple(float(np.mod(c / step, 1.0)) for c in grid_m[1])
        try:
            out[str(it["id"])] = predict_wedge(
                otf,
                it,
                gsd_m=step_m,
                placements_px=tuple(
                    (float(np.mod(a + own[0], 1.0)), float(np.mod(b + own[1], 1.0))) for a, b in PLACEMENTS_PX
                ),
                truth_pixel_m=truth_px,
                background=background,
                threshold=threshold,
                noise_sigma=noise,
            )
        except InputError as exc:
            out[str(it["id"])] = WedgePrediction(str(it["id"]), axis, None, gsd_m, threshold=threshold, reason=str(exc))
    return out


def saturation_warnings(sensor: Any, truth: Mapping[str, Any]) -> tuple[str, ...]:
    """Targets whose brightest reflectance reaches the full well (they will be clipped): say so."""
    if sensor is None or not np.isfinite(sensor.full_well_e):
        return ()
    out = []
    for it in truth.get("items", []):
        top = it.get("bright", it.get("mean", 0.0) + it.get("amplitude", 0.0))
        e = sensor.offset_e + sensor.dark_e + top * sensor.electrons_per_unit
        if e >= sensor.full_well_e:
            out.append(
                f"{it['id']}: reflectance {top:g} gives {e:.0f} e- >= full well {sensor.full_well_e:.0f} e- "
                f"(saturated; fewer TDI stages or a shorter integration would keep it measurable)"
            )
    return tuple(out)


@checked
def predict(
    system: Any,
    truth: Mapping[str, Any] | Truth,
    *,
    otf: Any = None,
    quality: Mapping[str, float] | None = None,
    sensor: Any = None,
    wedge_threshold: float = 0.15,
    image_grid_m: tuple | None = None,
) -> Predictions:
    """Predict every figure a run compares, for the targets of ``truth`` (``image_grid_m``: see
    :func:`predict_from_mtf`).

    Parameters
    ----------
    system : ImagingSystem
        With square ground pixels (``gsd_act_m == gsd_alt_m``).
    truth : mapping or Truth
        The scene's truth record (``Scene.truth()``, a ``*.truth.json``'s content, or a
        :class:`satchain.scene.truth.Truth`).
    otf : SystemOTF, optional
        The system OTF (built from ``system`` when not given).
    quality : mapping, optional
        :func:`satchain.prediction.quality.predict_quality` ``.to_dict()``, or some of its figures (``giqe5``,
        ``rer_giqe5``, ``snr`` are used): the others are computed, and without ``giqe5`` the NIIRS is that of
        the RER and SNR used (:func:`satchain.prediction.quality.complete_quality`); an unknown key is refused.
    sensor : SensorModel, optional
        For saturation warnings, and the image noise that gives the wedge crossings their 1-sigma.
    wedge_threshold : float
        Contrast at which a wedge stops resolving (the paper's 0.15).
    """
    from satchain.prediction.quality import complete_quality
    from satchain.tf.budget import SystemOTF

    truth = truth.to_dict() if hasattr(truth, "to_dict") else truth  # a satchain.scene.truth.Truth
    otf = SystemOTF(system) if otf is None else otf
    quality = complete_quality(system, quality, otf=otf)
    names = getattr(otf, "component_names", ())
    return predict_from_mtf(
        system_mtf_cy_per_px(otf, local=True),
        dict(truth),
        gsd_m=system.gsd_m,
        wedge_threshold=wedge_threshold,
        quality=quality,
        gsd_los_m=system.gsd_los_m,
        elevation_deg=system.orbit.elevation_deg,
        warnings=saturation_warnings(sensor, truth),
        otf2d=_SystemOTF(otf, tuple(c for c in WIDE_COMPONENTS if c in names)),
        noise_sigma=sensor_noise_reflectance(sensor),
        image_grid_m=image_grid_m,
    )
