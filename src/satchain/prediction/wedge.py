"""The predicted hyperbolic-wedge resolution, formed and measured the way the image's wedge is (issue 18).

A wedge's 15 % contrast crossing is not Coltman's CTF of an infinite square wave: the wedge has five dark
lines on a bright plate (a finite pattern), its contrast is ``(max - min) / (max + min)`` of *sampled* profiles
(the samples rarely fall on the peaks, and near one GSD the line pairs alias onto the sampling null), and its
reflectances 0.8 / 0.05 give a modulation of 0.88, not 1. So the prediction is made by the measurement itself:

1. the wedge of the truth record is rendered alone (on its scene background) at a fine pixel
   ``gsd_m / D`` (``D = round(gsd_m / truth pixel)``, the truth's own pixel size) over a window aligned with
   the image's pixel grid (the engine's geometry contract: pixel ``[i, j]`` covers ``[j, j + 1) GSD``);
2. the system's complex OTF (all components, the detector footprint included, the wide aerosol adjacency
   left out as for every local prediction) is applied by FFT, and the result is sampled at the detector's
   pixel centres, noise free;
3. that image goes through :func:`satchain.measure.auto.measure_auto` -- the very same region, contrast scan
   and 15 % crossing as the measured wedge.

The prediction is never clamped to the GSD. Its uncertainty is the spread over sub-pixel placements of the
pixel grid (the wedge moved by fractions of a pixel along and across its lines): the prediction for a wedge
whose placement on the grid is not known better than a pixel. Prediction calls measure's estimator; measure
never imports any of this (ARCHITECTURE: measurement stays independent of the transfer functions).

Examples
--------
>>> from satchain.scene import HyperbolicWedge, Scene
>>> truth = Scene(80.0, 30.0, (HyperbolicWedge("w", origin_m=(5.0, 5.0)),), pixel_m=0.05).truth()
>>> gauss = lambda fx, fy: np.exp(-8.0 * (fx**2 + fy**2))  # a 2-D OTF in cy/px
>>> p = predict_wedge(gauss, truth["items"][0], gsd_m=0.5, truth_pixel_m=0.05, background=0.2)
>>> p.axis, 0.45 < p.resolution_m < 1.0, len(p.resolutions_by_placement_m)
('ALT', True, 4)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from satchain.errors import InputError
from satchain.prediction.target_image import MARGIN_PX, TargetImageModel, item_from_truth

__all__ = ["MARGIN_PX", "PLACEMENTS_PX", "WedgePrediction", "predict_wedge", "wedge_model_image"]

#: The axis across a wedge's stripes for each wedge orientation of the scene.
WEDGE_AXES = {"horizontal": "ALT", "vertical": "ACT", "diagonal": "D135"}
#: Sub-pixel placements ``(dx, dy)`` (output px) of the pixel grid over which the prediction's spread is taken;
#: the first is the image's own placement (the predicted value).
PLACEMENTS_PX = ((0.0, 0.0), (0.25, 0.5), (0.5, 0.25), (0.75, 0.75))
#: Noisy copies of the predicted image re-measured for the crossing's 1-sigma from noise.
N_NOISE = 16

OTF2D = Callable[[np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class WedgePrediction:
    """A wedge's predicted resolvable line width (ground m), measured on its noise-free predicted image.

    ``resolution_m`` is at the image's own placement on the pixel grid (None when the predicted contrast never
    falls to the threshold); ``resolution_m_std`` the 1-sigma spread over the sub-pixel placements
    :data:`PLACEMENTS_PX` (``resolutions_by_placement_m``; None where a placement has no crossing: counted in the
    spread as the widest line when its wide end is already unresolved, as the narrowest when it never falls);
    ``position_m`` / ``line_width_m`` / ``contrast`` the predicted contrast scan (positions along the wedge from
    its wide end); ``gsd_m`` the GSD; ``reason`` why there is no prediction, when there is none.
    ``resolution_noise_m_std``: the 1-sigma that the image noise gives a measured crossing, from re-measuring the
    predicted image with the sensor's noise added :data:`N_NOISE` times (a parametric bootstrap); None without
    a noise model.
    """

    id: str
    axis: str
    resolution_m: float | None
    gsd_m: float
    resolution_m_std: float | None = None
    resolutions_by_placement_m: tuple = ()
    threshold: float = 0.15
    position_m: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, compare=False)
    line_width_m: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, compare=False)
    contrast: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, compare=False)
    reason: str | None = None
    resolution_noise_m_std: float | None = None

    def contrast_at(self, position_m) -> np.ndarray:
        """The predicted contrast at positions along the wedge (m from its wide end); NaN outside the scan."""
        x = np.asarray(position_m, dtype=float)
        if self.position_m.size < 2:
            return np.full(x.shape, np.nan)
        return np.interp(x, self.position_m, self.contrast, left=np.nan, right=np.nan)


class _WedgeModel(TargetImageModel):
    """A truth record's wedge rendered once at the truth's pixel, its spectrum filtered by the OTF once;
    :meth:`image` then samples it for any placement (:class:`satchain.prediction.target_image.TargetImageModel`)."""

    def __init__(self, otf2d: OTF2D, item: Mapping[str, Any], gsd_m: float, truth_pixel_m: float, background: float):
        super().__init__(otf2d, item_from_truth(item), gsd_m=gsd_m, truth_pixel_m=truth_pixel_m, background=background)


def wedge_model_image(
    otf2d: OTF2D,
    item: Mapping[str, Any],
    *,
    gsd_m: float,
    truth_pixel_m: float,
    background: float,
    shift_px: tuple[float, float] = (0.0, 0.0),
) -> tuple[np.ndarray, tuple[float, float]]:
    """The noise-free image (reflectance, one value per detector pixel) of a truth record's wedge alone.

    ``otf2d(fx, fy)`` is the system OTF in cy/px (x = ACT, y = ALT; complex or real; the detector footprint
    included; an attribute ``cutoff`` in cy/px, when it has one, limits where it is evaluated); ``shift_px``
    moves the pixel grid by a fraction of a pixel. Returns the image and the scene point (m) of its top-left
    corner (pixel ``[i, j]`` is centred at ``origin + (j + 1/2, i + 1/2) gsd_m``).
    """
    model = _WedgeModel(otf2d, item, gsd_m, truth_pixel_m, background)
    return model.image(shift_px), model.origin_m


def _measure_model(image, item, origin_m, gsd_m, threshold):
    from satchain.measure.auto import measure_auto
    from satchain.scene.targets import HyperbolicWedge

    res = measure_auto(image, {"items": [dict(item)]}, pixel_m=gsd_m, origin_m=origin_m, wedge_threshold=threshold)
    found = [it.summary for it in res.by_kind(HyperbolicWedge.kind)]
    if not found:
        reason = "; ".join(str(s.get("reason")) for s in res.skipped) or "no result"
        raise InputError(f"wedge {item['id']!r}: its predicted image cannot be measured ({reason})")
    return found[0]


def _noise_std(image, item, origin_m, gsd_m, threshold, noise_sigma, first) -> float | None:
    """1-sigma of the crossing (m) over :data:`N_NOISE` noisy copies of ``image`` (fixed seed: reproducible)."""
    rng = np.random.default_rng(20260101)
    sigma = np.asarray(noise_sigma(image), dtype=float)
    out = []
    for _ in range(N_NOISE):
        try:
            r = _measure_model(image + sigma * rng.standard_normal(image.shape), item, origin_m, gsd_m, threshold)
        except InputError:
            continue
        out.append(r.get("resolution_m"))
    vals = [float(v) for v in out if v is not None and math.isfinite(v)]
    if first is None or len(vals) < N_NOISE // 2:
        return None
    return float(np.std(vals, ddof=1))


def predict_wedge(
    otf2d: OTF2D,
    item: Mapping[str, Any],
    *,
    gsd_m: float,
    truth_pixel_m: float,
    background: float,
    threshold: float = 0.15,
    placements_px: tuple[tuple[float, float], ...] = PLACEMENTS_PX,
    noise_sigma: Callable[[np.ndarray], np.ndarray] | None = None,
) -> WedgePrediction:
    """Predict a wedge's resolvable line width by measuring its noise-free predicted image (module docstring).

    Parameters
    ----------
    otf2d : callable
        The system OTF ``otf2d(fx, fy)`` in cy/px (x = ACT, y = ALT), detector footprint included.
    item : mapping
        The wedge's truth record (``kind = "hyperbolic_wedge"``, as :meth:`satchain.scene.Scene.truth` gives).
    gsd_m, truth_pixel_m : float
        The image's ground pixel and the truth's render pixel (m).
    background : float
        The scene's background reflectance around the wedge's plate.
    threshold : float
        Contrast at which the stripes stop being resolved.
    placements_px : tuple of (dx, dy)
        Sub-pixel placements of the pixel grid; the first is the image's own (the predicted value), all of them
        give the spread ``resolution_m_std``.
    noise_sigma : callable, optional
        The image noise, 1-sigma per pixel in reflectance as a function of the noise-free reflectance: gives
        ``resolution_noise_m_std``.
    """
    runs: list[dict[str, Any]] = []
    res: list[float | None] = []
    spread: list[float] = []
    w0, w1 = float(item["line_width_start_m"]), float(item["line_width_end_m"])
    model = _WedgeModel(otf2d, item, gsd_m, truth_pixel_m, background)
    ox, oy = model.origin_m
    for k, (dx, dy) in enumerate(placements_px):
        try:
            origin = (ox + dx * gsd_m, oy + dy * gsd_m)
            runs.append(_measure_model(model.image((dx, dy)), item, origin, gsd_m, threshold))
        except InputError:
            if k == 0:  # the image's own placement: no prediction
                raise
            res.append(None)  # its wide end is already unresolved: counted as the widest line in the spread
            spread.append(w0)
            continue
        r = runs[-1].get("resolution_m")
        res.append(None if r is None or not math.isfinite(r) else float(r))
        spread.append(w1 if res[-1] is None else res[-1])  # no crossing: resolved to the narrow end
    spread = spread if res[0] is not None else []
    first = runs[0]
    sd_noise = None
    if noise_sigma is not None:
        sd_noise = _noise_std(
            model.image(placements_px[0]),
            item,
            (ox + placements_px[0][0] * gsd_m, oy + placements_px[0][1] * gsd_m),
            gsd_m,
            threshold,
            noise_sigma,
            res[0],
        )
    return WedgePrediction(
        id=str(item["id"]),
        axis=WEDGE_AXES[str(item["orientation"]).lower()],
        resolution_m=None if res[0] is None else float(res[0]),
        gsd_m=float(gsd_m),
        resolution_m_std=float(np.std(spread, ddof=1)) if len(spread) > 1 else None,
        resolutions_by_placement_m=tuple(res),
        threshold=float(threshold),
        position_m=np.asarray(first["position_m_along_wedge"], dtype=float),
        line_width_m=np.asarray(first["line_width_m"], dtype=float),
        contrast=np.asarray(first["contrast"], dtype=float),
        resolution_noise_m_std=sd_noise,
    )
