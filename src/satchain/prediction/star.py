"""The predicted Siemens-star MTF, measured the way the image's star is (issue 18).

The star's measured MTF is not the system MTF: the estimator (:func:`satchain.measure.star.measure_star` as
:func:`satchain.measure.auto.measure_auto` calls it) fits annuli of a sampled image, takes the star's input
modulation from the truth (``amplitude / mean``) on an image calibrated to reflectance by a straight line
through the uniform areas of the scene (the edges' plateaus and the background), and all of that shifts the
curve by up to ~0.02 from the system MTF (the outer radii most: the PSF's tails carry light across the star's
rim and pull the edges' plateaus off their reflectances, so the fitted calibration has an offset). Comparing the
measured curve with the system MTF therefore fails on that bias, not on the camera.

So the prediction is made by the measurement itself, as for the wedge (:mod:`satchain.prediction.wedge`):

1. the star and the scene's calibration sources (its slanted edges) are formed noise free with the predicted
   system, each alone on the background, at the image's own pixel grid and placement
   (:func:`satchain.prediction.target_image.scene_model_image`);
2. that canvas goes through :func:`~satchain.measure.auto.measure_auto`: the same calibration, centre search,
   annuli and input modulation as the measured star.

The system MTF along each direction is kept beside it (``mtf_model``): ``mtf - mtf_model`` is the estimator's
systematic, reported, no longer part of the check. Prediction calls measure's estimator; measure never
imports any of this (ARCHITECTURE: measurement stays independent of the transfer functions).

Examples
--------
>>> from satchain.scene import Scene, SiemensStar
>>> truth = Scene(60.0, 60.0, (SiemensStar("s", center_m=(30.0, 30.0), radius_m=20.0),), pixel_m=0.1).truth()
>>> gauss = lambda fx, fy: np.exp(-3.0 * (fx**2 + fy**2)) * np.sinc(fx) * np.sinc(fy)
>>> (p,) = predict_stars(gauss, truth, gsd_m=0.5).values()
>>> m = float(p.mtf_at("ACT", 0.3))  # the system MTF there: exp(-0.27) sinc(0.3) = 0.655
>>> p.reason is None, p.input_modulation_from, round(m, 2)
(True, 'truth', 0.65)
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from satchain.errors import InputError
from satchain.prediction.target_image import item_from_truth, scene_model_image
from satchain.scene.targets import SiemensStar, SlantedEdge

__all__ = ["CALIBRATION_KINDS", "MAX_OVERSAMPLE", "StarPrediction", "predict_stars"]

#: Truth kinds formed beside the stars because the measurement's radiometric calibration reads their levels.
CALIBRATION_KINDS = (SlantedEdge.kind,)
#: The model's fine pixel is ``gsd / min(D, MAX_OVERSAMPLE)``: the star's sine has no frequency above
#: ``cycles / (2 pi inner_radius)`` and the OTF none above its cutoff (< 1 cy/px), so the 4x fine sampling aliases
#: only the outlines into the band; the measured curves agree with the truth pixel's (D = 14) to 1e-5.
MAX_OVERSAMPLE = 4
#: The largest canvas (output px) that holds the stars and the calibration sources; beyond it the stars are formed
#: with the background alone as calibration (noted in ``calibration_note``).
MAX_CANVAS_PX = 4_000_000

OTF2D = Callable[[np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class StarPrediction:
    """A star's predicted measured MTF: ``mtf[direction]`` (``ACT``, ``ALT``, ``D45``, ``D135``) at
    ``f_cy_per_px``, measured on its noise-free predicted image; ``input_modulation_from`` and ``calibration``
    (offset, gain of the reflectance calibration the measurement fitted on that image) say how; ``reason``
    why there is none (``mtf`` then empty)."""

    id: str
    f_cy_per_px: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, compare=False)
    mtf: Mapping[str, np.ndarray] = field(default_factory=dict, repr=False, compare=False)
    input_modulation_from: str | None = None
    calibration: Mapping[str, Any] = field(default_factory=dict, repr=False, compare=False)
    calibration_note: str | None = None
    reason: str | None = None

    def mtf_at(self, direction: str, f_cy_per_px) -> np.ndarray:
        """The predicted measured MTF along ``direction`` at ``f_cy_per_px`` (NaN outside the predicted radii)."""
        f = np.asarray(f_cy_per_px, dtype=float)
        curve = self.mtf.get(direction)
        if curve is None or self.f_cy_per_px.size < 2:
            return np.full(f.shape, np.nan)
        return np.interp(f, self.f_cy_per_px, curve, left=np.nan, right=np.nan)


def _rebuildable(record: Mapping[str, Any]) -> bool:
    try:
        item_from_truth(record)
    except InputError:
        return False
    return True


def _groups(truth: Mapping[str, Any], stars: list[Mapping[str, Any]], gsd_m: float) -> list[tuple[list, str | None]]:
    """The canvases to form: the stars with the calibration sources when their union fits
    :data:`MAX_CANVAS_PX`, else each star alone on the background (with the note that says so)."""
    cal = [it for it in truth.get("items", []) if it.get("kind") in CALIBRATION_KINDS and _rebuildable(it)]
    boxes = np.array([it["bbox_m"] for it in stars + cal], dtype=float)
    w = (boxes[:, 2].max() - boxes[:, 0].min()) / gsd_m
    h = (boxes[:, 3].max() - boxes[:, 1].min()) / gsd_m
    if w * h <= MAX_CANVAS_PX:
        return [(stars + cal, None)]
    note = f"the stars and edges span {w:.0f} x {h:.0f} px: each star calibrated on the background alone"
    return [([st], note) for st in stars]


def _predict_group(otf2d, records, note, truth, gsd_m, max_oversample) -> dict[str, StarPrediction]:
    """The stars of ``records`` measured on one canvas of ``records``' noise-free images."""
    from satchain.measure.auto import MEASURERS, measure_auto

    background = float(truth.get("background", 0.2))
    truth_px = float(truth.get("pixel_m") or gsd_m / 10.0)
    ids = [str(it["id"]) for it in records if it.get("kind") == SiemensStar.kind]
    try:
        canvas, origin, _ = scene_model_image(
            otf2d, records, gsd_m=gsd_m, truth_pixel_m=truth_px, background=background, max_oversample=max_oversample
        )
        res = measure_auto(canvas, {"items": list(records), "background": background}, pixel_m=gsd_m,
                           origin_m=origin, ids=ids)  # fmt: skip
    except InputError as exc:
        return {i: StarPrediction(i, reason=f"the predicted image cannot be formed or measured: {exc}") for i in ids}
    cal = {k: res.calibration.get(k) for k in ("offset", "gain", "fitted", "note")}
    found = {str(s["id"]): s for s in res.to_dict().get(MEASURERS[SiemensStar.kind].key, [])}
    why = {str(s["id"]): str(s.get("reason")) for s in res.skipped}
    out = {}
    for i in ids:
        s = found.get(i)
        if s is None:
            out[i] = StarPrediction(i, reason=f"its noise-free predicted image cannot be measured: {why.get(i)}")
            continue
        out[i] = StarPrediction(
            i,
            f_cy_per_px=np.asarray(s["f_cy_per_px"], dtype=float),
            mtf={d: np.asarray(v, dtype=float) for d, v in s["mtf"].items()},
            input_modulation_from=s.get("input_modulation_from"),
            calibration=cal,
            calibration_note=note,
        )
    return out


def predict_stars(
    otf2d: OTF2D,
    truth: Mapping[str, Any],
    *,
    gsd_m: float,
    max_oversample: int = MAX_OVERSAMPLE,
) -> dict[str, StarPrediction]:
    """Predict every star's measured MTF by measuring the noise-free predicted image (module docstring).

    Parameters
    ----------
    otf2d : callable
        The system OTF ``otf2d(fx, fy)`` in cy/px (x = ACT, y = ALT), detector footprint included; an attribute
        ``cutoff`` (cy/px) limits where it is evaluated.
    truth : mapping
        The scene's truth record (``items``, ``background``, ``pixel_m``).
    gsd_m : float
        The image's ground pixel (m).
    max_oversample : int
        The model's fine pixels per output pixel at most (see :data:`MAX_OVERSAMPLE`).

    Returns
    -------
    dict
        Star id -> :class:`StarPrediction` (with ``reason`` when the predicted image cannot be measured).
    """
    stars = [it for it in truth.get("items", []) if it.get("kind") == SiemensStar.kind]
    out: dict[str, StarPrediction] = {}
    if stars:
        for records, note in _groups(truth, stars, gsd_m):
            out.update(_predict_group(otf2d, records, note, truth, gsd_m, max_oversample))
    return out
