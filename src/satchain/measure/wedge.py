"""Hyperbolic-wedge resolution: the reference paper's contrast scan ("Hyperbolic Wedge Resolution Analysis").

The wedge's stripes narrow along its axis.  At each position along the axis the contrast across the stripes,
``(max - min) / (max + min)`` of the profile across them (optionally averaged over a few neighbouring
positions), is recorded; a linear search from the wide end finds the first position where the contrast
falls to ``threshold`` (15 % by default: the paper's Rayleigh-criterion contrast).  The resolvable *line
width* there is the stripe width (half a period, a "line"); the corresponding frequency is
``1 / (2 line width)`` cycles (line pairs) per px, since bright and dark stripes are equally wide.

Geometry is explicit: ``line_width_px`` gives the stripe width at each position along the axis (the scene
module's truth JSON records it), so the function works on any wedge, hyperbolic or linear.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from satchain._validate import check_choice, check_range
from satchain.errors import InputError
from satchain.measure._common import ResultMixin, crop_roi, first_crossing
from satchain.units import cy_per_px_to_cy_per_m_ground

__all__ = ["WedgeResult", "measure_wedge"]


@dataclass(frozen=True)
class WedgeResult(ResultMixin):
    """Contrast curve along the wedge and the resolvable line width where it falls to ``threshold``.

    ``position_px`` are positions along the wedge axis (columns for an ``ALT`` wedge, rows for ``ACT``) in the
    region, ordered from the widest stripes; ``line_width_px`` the stripe width there; ``contrast`` the curve.
    The ``resolved_*`` fields are None when the contrast never falls to the threshold.
    """

    position_px: np.ndarray
    line_width_px: np.ndarray
    contrast: np.ndarray
    threshold: float
    direction: str
    resolved_position_px: float | None
    resolved_line_width_px: float | None
    resolved_f_cy_per_px: float | None
    resolved_line_width_m: float | None = None
    resolved_f_cy_per_m_ground: float | None = None


def measure_wedge(
    image,
    *,
    line_width_px,
    direction: str = "ALT",
    roi=None,
    threshold: float = 0.15,
    average_px: int = 1,
    pixel_m: float | None = None,
) -> WedgeResult:
    """Contrast scan along a hyperbolic (or any) wedge; resolvable line width at ``threshold`` contrast.

    Parameters
    ----------
    image : array_like, 2-D
    line_width_px : callable or array_like
        Stripe width (px) at each position along the wedge axis: a function of the position (px, in the
        region's coordinates) or an array with one value per position.
    direction : {"ALT", "ACT"}
        Direction *across* the stripes, i.e. the resolution measured.  ``ALT``: stripes run along x, the
        profile is a column, the axis is x (the paper's wedge); ``ACT``: the transpose.
    roi : (x0, y0, x1, y1), optional
        Region holding the stripes only (no surround).
    threshold : float
        Contrast in (0, 1) where the stripes count as no longer resolved.
    average_px : int
        Number of neighbouring profiles averaged at each position (noise reduction).
    pixel_m : float, optional
        Ground sample distance: adds the line width in metres and the frequency in cy/m on the ground.

    Examples
    --------
    >>> y, x = np.mgrid[0:40, 0:100]
    >>> lw = 6.0 - 0.05 * x  # stripes from 6 px down to 1 px wide
    >>> img = 100 + 80 * np.sign(np.sin(np.pi * y / lw)) * np.clip((x - 50) / -40, 0, 1)
    >>> r = measure_wedge(img, line_width_px=lambda p: 6.0 - 0.05 * p)
    >>> round(r.resolved_position_px, 1), round(r.resolved_line_width_px, 3)
    (42.5, 3.875)
    """
    check_choice("direction", direction, ("ALT", "ACT"))
    thr = check_range("threshold", threshold, 0.0, 1.0, lo_open=True, hi_open=True)
    avg = int(check_range("average_px", average_px, 1, 1000))
    data = crop_roi(image, roi, min_size=4)
    work = data if direction == "ALT" else data.T  # profiles are columns of `work`
    pos = np.arange(work.shape[1], dtype=float)
    lw = np.asarray(line_width_px(pos) if callable(line_width_px) else line_width_px, dtype=float)
    if lw.shape != pos.shape or not np.all(np.isfinite(lw)) or np.any(lw <= 0):
        raise InputError(
            f"line_width_px: need {pos.size} finite positive widths (one per position along the wedge), "
            f"got shape {lw.shape}"
        )
    if avg > 1:
        kernel = np.ones(avg) / avg
        work = np.apply_along_axis(lambda r: np.convolve(r, kernel, mode="same"), 1, work)
    hi, lo = work.max(axis=0), work.min(axis=0)
    if np.any(hi + lo <= 0):
        raise InputError("image: contrast needs positive levels (max + min > 0) in every profile")
    contrast = (hi - lo) / (hi + lo)
    order = np.argsort(-lw, kind="stable")  # from the widest stripes
    pos, lw, contrast = pos[order], lw[order], contrast[order]
    p_res = first_crossing(np.arange(pos.size, dtype=float), contrast, thr)
    res_pos = res_lw = res_f = None
    if p_res is not None:
        idx = np.arange(pos.size, dtype=float)
        res_pos = float(np.interp(p_res, idx, pos))
        res_lw = float(np.interp(p_res, idx, lw))
        res_f = 1.0 / (2.0 * res_lw)
    return WedgeResult(
        position_px=pos,
        line_width_px=lw,
        contrast=contrast,
        threshold=thr,
        direction=direction,
        resolved_position_px=res_pos,
        resolved_line_width_px=res_lw,
        resolved_f_cy_per_px=res_f,
        resolved_line_width_m=None if (pixel_m is None or res_lw is None) else res_lw * pixel_m,
        resolved_f_cy_per_m_ground=(
            None if (pixel_m is None or res_f is None) else float(cy_per_px_to_cy_per_m_ground(res_f, gsd_m=pixel_m))
        ),
    )
