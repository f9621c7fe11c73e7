"""Noise-free images of a truth record's targets formed with a predicted system (what predictions measure).

A prediction that is "the same measurement on a noise-free image formed with the predicted system" (the
wedge's 15 % crossing, :mod:`satchain.prediction.wedge`; the Siemens star's MTF, :mod:`satchain.prediction.star`)
needs that image. :class:`TargetImageModel` forms it for one target of a truth record:

1. the target is rebuilt from its truth record (:func:`item_from_truth`) and rendered alone on the scene's
   background at a fine pixel ``gsd_m / d`` over a window aligned with the image's pixel grid (the engine's
   geometry contract: pixel ``[i, j]`` covers ``[j, j + 1) GSD``), :data:`MARGIN_PX` output pixels of background
   around it;
2. its spectrum is multiplied by the system's OTF (cy/px, the detector footprint included) and, when the fine
   pixel is coarser than the truth's own (``d < D = round(gsd_m / truth_pixel_m)``, to save time), by the ratio
   of the two pixels' area-average transfer functions, so that it is the image of the truth rendered at its own
   pixel, as the engine forms it;
3. it is sampled at the detector's pixel centres (any sub-pixel placement of the grid), noise free.

:func:`scene_model_image` puts several targets' images on one canvas (each target alone with its PSF; light
from targets farther apart than :data:`MARGIN_PX` pixels is left out).

Examples
--------
>>> from satchain.scene import Scene, SlantedEdge
>>> truth = Scene(40.0, 40.0, (SlantedEdge("e", center_m=(20.0, 20.0), size_m=20.0),), pixel_m=0.05).truth()
>>> box = lambda fx, fy: np.sinc(fx) * np.sinc(fy)  # the detector footprint alone
>>> m = TargetImageModel(box, item_from_truth(truth["items"][0]), gsd_m=0.5, truth_pixel_m=0.05, background=0.2)
>>> img = m.image()
>>> img.shape, round(float(img.min()), 3), round(float(img.max()), 3)
((72, 72), 0.05, 0.8)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import numpy as np

from satchain.errors import InputError
from satchain.scene.targets import HyperbolicWedge, SiemensStar, SlantedEdge

__all__ = ["MARGIN_PX", "TargetImageModel", "item_from_truth", "scene_model_image"]

#: Output pixels of background around a target in its model window (the PSF's support).
MARGIN_PX = 16

OTF2D = Callable[[np.ndarray, np.ndarray], np.ndarray]


def _edge_from_truth(rec: Mapping[str, Any]):
    from satchain.scene import SlantedEdge

    measures = str(rec["measures"]).lower()
    a = math.radians(float(rec["angle_deg"]))
    normal = (math.cos(a), -math.sin(a)) if measures == "act" else (-math.sin(a), math.cos(a))
    nx, ny = (float(v) for v in rec["normal_to_bright"])
    side = "positive" if nx * normal[0] + ny * normal[1] > 0 else "negative"
    cx, cy = (float(v) for v in rec["edge_point_m"])
    return SlantedEdge(
        str(rec["id"]),
        center_m=(cx, cy),
        size_m=float(rec["size_m"]),
        angle_deg=float(rec["angle_deg"]),
        measures=measures,
        bright=float(rec["bright"]),
        dark=float(rec["dark"]),
        bright_side=side,
    )


def _star_from_truth(rec: Mapping[str, Any]):
    from satchain.scene import SiemensStar

    cx, cy = (float(v) for v in rec["center_m"])
    return SiemensStar(
        str(rec["id"]),
        center_m=(cx, cy),
        radius_m=float(rec["radius_m"]),
        cycles=int(rec["cycles"]),
        inner_radius_m=float(rec["inner_radius_m"]),
        mean=float(rec["mean"]),
        amplitude=float(rec["amplitude"]),
    )


def _wedge_from_truth(rec: Mapping[str, Any]):
    from satchain.scene import HyperbolicWedge

    w0 = float(rec["line_width_start_m"])
    lox, loy = (float(v) for v in rec["local_origin_m"])
    return HyperbolicWedge(
        str(rec["id"]),
        origin_m=(lox - w0, loy - w0),
        orientation=str(rec["orientation"]),
        length_m=float(rec["length_m"]),
        line_width_start_m=w0,
        line_width_end_m=float(rec["line_width_end_m"]),
        n_stripes=int(rec["n_stripes"]),
        bright=float(rec["bright"]),
        dark=float(rec["dark"]),
    )


#: Truth-record kind -> the function that rebuilds its scene item (one entry per target kind).
FROM_TRUTH = {
    SlantedEdge.kind: _edge_from_truth,
    SiemensStar.kind: _star_from_truth,
    HyperbolicWedge.kind: _wedge_from_truth,
}


def item_from_truth(record: Mapping[str, Any]):
    """The scene item (:mod:`satchain.scene`) a truth record describes, rebuilt from its parameters.

    Raises
    ------
    InputError
        A kind without a model (:data:`FROM_TRUTH`) or an incomplete record (naming the missing key).
    """
    kind = record.get("kind")
    if kind not in FROM_TRUTH:
        raise InputError(f"truth item kind = {kind!r}: no model image for it; allowed: {', '.join(FROM_TRUTH)}")
    try:
        return FROM_TRUTH[kind](record)
    except KeyError as exc:
        raise InputError(f"truth item {record.get('id')!r} ({kind}): missing key {exc}") from None
    except (TypeError, ValueError) as exc:
        raise InputError(f"truth item {record.get('id')!r} ({kind}): {exc}") from None


def _box(f: np.ndarray, width: float) -> np.ndarray:
    """Transfer function of an area average over ``width`` (in the unit of 1 / f)."""
    return np.sinc(f * width)


class TargetImageModel:
    """One target rendered once at the fine pixel ``gsd_m / d`` and its spectrum filtered by the OTF once (only
    inside the OTF's ``cutoff``, cy/px, when it has one); :meth:`image` then samples it for any placement.

    ``d = round(gsd_m / truth_pixel_m)`` (the truth's own pixel, as the engine renders it), or ``max_oversample``
    when that is smaller: the fine pixel's area average is then replaced by the truth pixel's in the spectrum
    (exact for the average; the fine sampling's aliasing, from the target's outline only when ``d`` leaves the
    OTF's band well below the fine Nyquist, is not).
    """

    def __init__(
        self,
        otf2d: OTF2D,
        item: Any,
        *,
        gsd_m: float,
        truth_pixel_m: float,
        background: float,
        max_oversample: int | None = None,
    ):
        d_truth = max(1, int(round(gsd_m / truth_pixel_m)))
        d = d_truth if max_oversample is None else max(1, min(d_truth, int(max_oversample)))
        bx0, by0, bx1, by1 = (float(v) for v in item.bbox_m())
        m = MARGIN_PX * gsd_m
        c0, r0 = math.floor((bx0 - m) / gsd_m), math.floor((by0 - m) / gsd_m)  # output px, on the image's grid
        nc, nr = math.ceil((bx1 + m) / gsd_m) - c0, math.ceil((by1 + m) / gsd_m) - r0
        fine = np.full((nr * d, nc * d), float(background))
        item.paint(fine, (r0 * d, c0 * d, nr * d, nc * d), gsd_m / d)
        spec = np.fft.fft2(fine - background)  # the window's border is background: periodic without a seam
        fmax = float(getattr(otf2d, "cutoff", np.inf))
        fy, fx = np.fft.fftfreq(nr * d) * d, np.fft.fftfreq(nc * d) * d  # cy per output px
        self.iy, self.ix = np.nonzero(np.abs(fy) <= fmax)[0], np.nonzero(np.abs(fx) <= fmax)[0]
        self.fy, self.fx = fy[self.iy][:, None], fx[self.ix][None, :]
        tf = np.asarray(otf2d(self.fx, self.fy))
        if d != d_truth:  # the truth pixel's area average instead of the fine pixel's
            p_t, p_f = truth_pixel_m / gsd_m, 1.0 / d  # in output px
            tf = tf * (_box(self.fx, p_t) * _box(self.fy, p_t)) / (_box(self.fx, p_f) * _box(self.fy, p_f))
        self.band = spec[np.ix_(self.iy, self.ix)] * tf
        self.d, self.shape, self.background = d, (nr, nc), float(background)
        self.origin_px = (c0, r0)
        self.origin_m = (c0 * gsd_m, r0 * gsd_m)

    def image(self, shift_px: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
        """Point samples at the output pixel centres (fine index ``j d + d/2 - 1/2 + shift d``): a phase ramp,
        the band folded modulo the output size (the aliasing of sampling every d-th fine sample), an inverse
        DFT of the output size."""
        d, (nr, nc) = self.d, self.shape
        sx, sy = d / 2 - 0.5 + shift_px[0] * d, d / 2 - 0.5 + shift_px[1] * d
        g = self.band * np.exp(2j * np.pi * (self.fx * sx + self.fy * sy) / d)
        folded = np.zeros((nr, nc), dtype=complex)
        np.add.at(folded, (self.iy[:, None] % nr, self.ix[None, :] % nc), g)
        return np.fft.ifft2(folded).real / (d * d) + self.background


def scene_model_image(
    otf2d: OTF2D,
    records: Iterable[Mapping[str, Any]],
    *,
    gsd_m: float,
    truth_pixel_m: float,
    background: float,
    max_oversample: int | None = None,
) -> tuple[np.ndarray, tuple[float, float], dict[str, TargetImageModel]]:
    """Several targets' noise-free images on one canvas covering them all (each formed alone, see the module
    docstring; they add as departures from the background). Returns the canvas, the scene point (m) of its
    top-left corner and the per-target models by id."""
    models = {
        str(rec["id"]): TargetImageModel(
            otf2d, item_from_truth(rec), gsd_m=gsd_m, truth_pixel_m=truth_pixel_m, background=background,
            max_oversample=max_oversample,
        )
        for rec in records
    }  # fmt: skip
    if not models:
        raise InputError("records: no target to form an image of")
    c0 = min(m.origin_px[0] for m in models.values())
    r0 = min(m.origin_px[1] for m in models.values())
    c1 = max(m.origin_px[0] + m.shape[1] for m in models.values())
    r1 = max(m.origin_px[1] + m.shape[0] for m in models.values())
    canvas = np.full((r1 - r0, c1 - c0), float(background))
    for m in models.values():
        (c, r), (h, w) = m.origin_px, m.shape
        canvas[r - r0 : r - r0 + h, c - c0 : c - c0 + w] += m.image() - m.background
    return canvas, (c0 * gsd_m, r0 * gsd_m), models
