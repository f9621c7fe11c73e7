"""The CTF a bar target's measurement gives on a pushbroom run's image, predicted at the image's own placement
(issue 29, item 12).

A group of three bars near 3 px per period is sampled by a handful of pixels: the CTF its measurement gives
(:func:`satchain.measure.bars.measure_bars`, a fit at the known period to the profile of a few rows) depends on
where the bars fall on the pixel grid by several hundredths, beyond what Coltman's CTF of the system MTF can say.
A slow line-of-sight motion moves whole rows and changes the blur of the few rows a group spans, and the run
(:class:`satchain.prediction.image_geometry.ImageGeometry`) knows where every row puts the ground and the path of each
row's window.  So the prediction is the measurement itself on a noise-free image of the target formed where the
image has it:

1. every image pixel ``(col, row)`` around the target sees the truth point :meth:`ImageGeometry.ground_m` (the
   mean map with the row's line-of-sight displacement);
2. its value is the target's rectangles (each group's dark plate on the scene's background, the bright bars on
   it) blurred by the system's transfer along the two pixel axes (``mtf_along``, the detector footprint
   included), a separable model: each rectangle is the product of the two axes' edge responses ``E(u) = 1/2 +
   int_0^fc M(f) sin(2 pi f u) / (pi f) df`` (``u`` the ground distance over the image's ground step, px).  The
   motion's blur in ``M`` is that of the target's own rows as their paths are
   (:func:`satchain.tf.pushbroom_roi.rows_blur_otf`), not the budget's expectation over the oscillations'
   phases: a slow ACT oscillation whose velocity opposes the Earth-rotation drift on those rows shortens the
   drift's smear (on the issue's run, 1 px at 60 Hz, the ACT transfer at 0.33 cy/px is 0.90 there against
   the budget's 0.80, and group 3 measures 0.398 against 0.377 so predicted, 0.334 with the budget's terms);
3. :func:`~satchain.measure.bars.measure_bars` measures that image with the groups, regions and levels the
   image's measurement used.

The rows' displacements over a group (an as-imaged transfer, averaging the rows' profiles) and the sampling
phase are both in it.  The separable blur leaves out the optics' non-separable part at the bars' corners, which
the regions (one bar width in from the bars' ends) keep away from.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

__all__ = ["predict_bar_ctf"]

#: Image pixels of context rendered around the groups' regions (the PSF's support).
_MARGIN_PX = 8
#: Frequency step (cy/px) of the edge-response integral; its highest frequency is the system's cutoff (<= 3).
_DF = 1.0 / 1024.0
#: The edge response is tabulated over +-_U_MAX_PX (0 and 1 beyond: a diffraction tail there is < 1e-3) at _DU_PX.
_U_MAX_PX, _DU_PX = 48.0, 1.0 / 64.0


def _edge_response(mtf: Callable[[np.ndarray], np.ndarray]) -> Callable[[np.ndarray], np.ndarray]:
    """The edge response ``E(u)`` (u in px) of the line spread whose transfer is ``mtf`` (cy/px)."""
    top = float(min(getattr(mtf, "cutoff", 3.0) or 3.0, 3.0))
    f = (np.arange(max(int(np.ceil(top / _DF)), 1)) + 0.5) * _DF
    w = np.asarray(mtf(f), float) * _DF / (np.pi * f)
    grid = np.arange(-_U_MAX_PX, _U_MAX_PX + 1e-9, _DU_PX)  # tabulated once, linear between (error < 1e-5)
    table = 0.5 + np.sin(2 * np.pi * np.outer(grid, f)) @ w

    def esf(u: np.ndarray) -> np.ndarray:
        return np.interp(np.asarray(u, float), grid, table, left=0.0, right=1.0)

    return esf


def _on_rows(mtf, terms, axis: str, rows: tuple[int, int]):
    """``mtf`` (the system's, cy/px of the image's ``axis``, with the budget's per-row motion terms) with those
    terms replaced by the blur the rows ``rows[0] .. rows[1] - 1`` have as their paths are
    (:func:`satchain.tf.pushbroom_roi.rows_blur_otf`); ``mtf`` itself without pushbroom terms."""
    if terms is None or rows[1] <= rows[0]:
        return mtf
    from satchain.tf.pushbroom_roi import per_row_otf, rows_blur_otf

    a = axis.lower()
    scale = 1.0 if a == "act" else float((terms.geometry() or {}).get("alt_scale", 1.0))  # image rows, det. px

    def on_rows(f):
        nu = np.asarray(f, float) / scale
        per = np.abs(per_row_otf(terms, nu, a))
        own = rows_blur_otf(terms, nu, a, first_line=rows[0], n_lines=rows[1] - rows[0])
        return np.where(per > 1e-3, np.asarray(mtf(f), float) * own / np.maximum(per, 1e-3), 0.0)

    on_rows.__dict__["cutoff"] = getattr(mtf, "cutoff", None)  # the band limit, as mtf's
    return on_rows


def _rect(gx, gy, box, steps, esf) -> np.ndarray:
    """The blurred unit rectangle ``box`` (m, ``[x0, y0, x1, y1]``) at the truth points ``(gx, gy)``."""
    x0, y0, x1, y1 = (float(v) for v in box)
    (sx, sy), (ex, ey) = steps, esf
    return (ex((gx - x0) / sx) - ex((gx - x1) / sx)) * (ey((gy - y0) / sy) - ey((gy - y1) / sy))


def target_model_image(geometry, record: Mapping[str, Any], rois, mtf_along, background: float):
    """A noise-free image (reflectance) of bar target ``record`` (its truth record) where ``geometry`` puts it,
    over the bounding box of ``rois`` plus :data:`_MARGIN_PX` (the scene's ``background`` elsewhere)."""
    r = np.asarray(rois, int)
    c0, r0 = max(int(r[:, 0].min()) - _MARGIN_PX, 0), max(int(r[:, 1].min()) - _MARGIN_PX, 0)
    c1, r1 = int(r[:, 2].max()) + _MARGIN_PX, min(int(r[:, 3].max()) + _MARGIN_PX, geometry.dx_px.size)
    image = np.full((r1, c1), float(background))
    cols, rows = np.meshgrid(np.arange(c0, c1, dtype=float), np.arange(r0, r1, dtype=float))
    gx, gy = geometry.ground_m(cols, rows)
    span = (max(int(r[:, 1].min()), 0), min(int(r[:, 3].max()), geometry.dx_px.size))
    esf = tuple(_edge_response(_on_rows(mtf_along[a], geometry.terms, a, span)) for a in ("ACT", "ALT"))
    dark, bright = float(record["dark"]), float(record["bright"])
    patch = np.full(gx.shape, float(background))
    for g in record["groups"]:
        patch += (dark - background) * _rect(gx, gy, g["bbox_m"], geometry.steps_m, esf)
        for bar in g["bars_m"]:
            patch += (bright - dark) * _rect(gx, gy, bar, geometry.steps_m, esf)
    image[r0:r1, c0:c1] = patch
    return image


def predict_bar_ctf(geometry, entry: Mapping[str, Any], mtf_along, background: float) -> np.ndarray | None:
    """The CTF of each group the bar measurement ``entry`` (a ``measure auto`` bar summary, its ``groups`` with
    their regions and periods) gives, measured the same way on :func:`target_model_image`; None when the
    geometry holds no truth record for it or the entry names no regions."""
    from satchain.measure.bars import measure_bars

    record = (getattr(geometry, "bars", None) or {}).get(entry.get("id"))
    groups = entry.get("groups") or []
    if record is None or not groups or any(g.get("roi_px") is None for g in groups):
        return None
    rois = [tuple(int(v) for v in g["roi_px"]) for g in groups]
    image = target_model_image(geometry, record, rois, mtf_along, background)
    levels = (float(record["dark"]), float(record["bright"])) if entry.get("levels_from") == "truth" else None
    r = measure_bars(
        image,
        periods_px=[float(g["period_px"]) for g in groups],
        group_rois=rois,
        direction=str(entry.get("direction", "ACT")).upper(),
        levels=levels,
        bars_per_group=int(record.get("n_bars", 3)),
    )
    return np.array([np.nan if v is None else float(v) for v in r.ctf], float)
