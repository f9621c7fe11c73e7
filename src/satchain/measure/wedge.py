"""Hyperbolic-wedge resolution: the reference paper's contrast scan ("Hyperbolic Wedge Resolution Analysis").

The wedge's stripes narrow along its axis.  At each position along the axis the contrast across the stripes,
``(max - min) / (max + min)`` of the profile across them (optionally averaged over a few neighbouring
positions), is recorded; a linear search from the wide end finds the first position where the contrast
falls to ``threshold`` (15 % by default: the paper's Rayleigh-criterion contrast).  The resolvable *line
width* there is the stripe width (half a period, a "line"); the corresponding frequency is
``1 / (2 line width)`` cycles (line pairs) per px, since bright and dark stripes are equally wide.

Geometry is explicit: ``line_width_px`` gives the stripe width at each position along the axis (the scene
module's truth JSON records it), so the function works on any wedge, hyperbolic or linear.

Validation and uncertainty (issue 10).  The pixel noise is estimated from the second differences between
neighbouring profiles (the stripes change slowly along the axis); a region whose wide end has no contrast
above the noise (a constant image, no wedge) or already below the threshold is refused.  The contrast at
each position carries a 1-sigma from the noise, and the resolved position a 1-sigma from the contrast
scatter at the crossing over the local slope of the curve (converted to line width and metres).  ``flags``
report clipping, low contrast-to-noise, a noise floor near the threshold, and a contrast that climbs back
above the threshold after the crossing (spurious resolution / aliasing).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from satchain._validate import check_choice, check_range
from satchain.errors import InputError
from satchain.measure._clipping import resolve_full_scale
from satchain.measure._common import ResultMixin, clipping_flag, crop_roi, first_crossing, robust_sigma
from satchain.units import cy_per_px_to_cy_per_m_ground

__all__ = ["WedgeResult", "measure_wedge"]


@dataclass(frozen=True)
class WedgeResult(ResultMixin):
    """Contrast curve along the wedge and the resolvable line width where it falls to ``threshold``.

    ``position_px`` are positions along the wedge axis (columns for an ``ALT`` wedge, rows for ``ACT``) in the
    region, ordered from the widest stripes; ``line_width_px`` the stripe width there; ``contrast`` the curve.
    The ``resolved_*`` fields are None when the contrast never falls to the threshold; ``*_std`` are 1-sigma
    (noise); ``noise_std`` the pixel noise estimated; ``flags`` quality warnings.
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
    contrast_std: np.ndarray | None = None
    resolved_position_px_std: float | None = None
    resolved_line_width_px_std: float | None = None
    resolved_line_width_m_std: float | None = None
    noise_std: float = 0.0
    flags: tuple = ()


def measure_wedge(
    image,
    *,
    line_width_px,
    direction: str = "ALT",
    roi=None,
    threshold: float = 0.15,
    average_px: int = 1,
    pixel_m: float | None = None,
    full_scale: float | None = None,
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
    full_scale : float, optional
        The sensor's full scale in the image's units; integer images default to their dtype maximum.  The
        wedge is flagged ``clipping`` only on evidence: pixels at the full scale, or a flat run at its top
        (bottom) that shows saturation (:func:`satchain.measure.find_clipping`).

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
    full_scale = resolve_full_scale(image, full_scale)
    data = crop_roi(image, roi, min_size=4)
    work = data if direction == "ALT" else data.T  # profiles are columns of `work`
    pos = np.arange(work.shape[1], dtype=float)
    lw = np.asarray(line_width_px(pos) if callable(line_width_px) else line_width_px, dtype=float)
    if lw.shape != pos.shape or not np.all(np.isfinite(lw)) or np.any(lw <= 0):
        raise InputError(
            f"line_width_px: need {pos.size} finite positive widths (one per position along the wedge), "
            f"got shape {lw.shape}"
        )
    # second differences along the axis: a stripe pattern that shifts linearly from profile to profile cancels
    noise = float(robust_sigma(np.diff(work, n=2, axis=1)) / np.sqrt(6)) if work.shape[1] > 2 else 0.0
    flags = [f for f in [clipping_flag(work, full_scale=full_scale, noise_std=noise)] if f]
    if avg > 1:
        kernel = np.ones(avg) / avg
        work = np.apply_along_axis(lambda r: np.convolve(r, kernel, mode="same"), 1, work)
    hi, lo = work.max(axis=0), work.min(axis=0)
    if np.any(hi + lo <= 0):
        raise InputError("image: contrast needs positive levels (max + min > 0) in every profile")
    contrast = (hi - lo) / (hi + lo)
    s_eff = noise / np.sqrt(avg)
    c_std = s_eff * np.sqrt(2 * (1 + contrast**2)) / (hi + lo)
    order = np.argsort(-lw, kind="stable")  # from the widest stripes
    pos, lw, contrast, c_std = pos[order], lw[order], contrast[order], c_std[order]
    c_noise = 2 * s_eff * np.sqrt(2 * np.log(max(work.shape[0], 2))) / float(np.median(hi + lo))
    _check_wide_end(contrast, c_std, c_noise, thr, flags)
    idx = np.arange(pos.size, dtype=float)
    p_res = first_crossing(idx, contrast, thr)
    res_pos = res_lw = res_f = None
    sd_pos = sd_lw = None
    if p_res is not None:
        res_pos = float(np.interp(p_res, idx, pos))
        res_lw = float(np.interp(p_res, idx, lw))
        res_f = 1.0 / (2.0 * res_lw)
        sd_idx = _crossing_std(idx, contrast, c_std, p_res)
        step = np.gradient(pos), np.gradient(lw)
        sd_pos = float(sd_idx * abs(np.interp(p_res, idx, step[0])))
        sd_lw = float(sd_idx * abs(np.interp(p_res, idx, step[1])))
        after = contrast[int(np.ceil(p_res)) + 2 :]
        if after.size and np.max(after - 2 * c_std[int(np.ceil(p_res)) + 2 :]) > thr:
            flags.append("the contrast climbs back above the threshold after the crossing (spurious resolution)")
    else:
        flags.append("the contrast never falls to the threshold in this region")
    if c_noise > 0.5 * thr:
        flags.append(f"noise floor: pure noise alone gives a contrast of ~{c_noise:.3f} (threshold {thr:g})")
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
        contrast_std=c_std,
        resolved_position_px_std=sd_pos,
        resolved_line_width_px_std=sd_lw,
        resolved_line_width_m_std=None if (pixel_m is None or sd_lw is None) else sd_lw * pixel_m,
        noise_std=noise,
        flags=tuple(flags),
    )


def _check_wide_end(contrast, c_std, c_noise: float, thr: float, flags: list) -> None:
    """Refuse a region without a wedge (no contrast above the noise at the wide end) or one whose wide end is
    already below the threshold; flag a low contrast-to-noise."""
    wide = float(np.median(contrast[: min(5, contrast.size)]))
    sd = float(np.median(c_std[: min(5, contrast.size)]))
    if not (wide > 3 * c_noise and wide > 5 * sd and wide > 0):
        raise InputError(
            f"image: no wedge: the contrast at the wide end ({wide:.3g}) is not above the noise "
            f"(noise contrast ~{c_noise:.2g}); a constant or stripe-free region"
        )
    if wide <= thr:
        raise InputError(
            f"threshold = {thr:g}: the contrast at the wide end is already {wide:.3g}; no resolution to find "
            "(a blurred or wrongly framed wedge)"
        )
    if sd > 0 and wide / sd < 10:
        flags.append(f"low contrast-to-noise: wide-end contrast / its 1-sigma = {wide / sd:.1f} < 10")


def _crossing_std(idx, contrast, c_std, p_res: float) -> float:
    """1-sigma (in positions) of the threshold crossing: contrast scatter over the local slope (+-5 positions)."""
    sel = np.abs(idx - p_res) <= 5
    if np.count_nonzero(sel) < 3:
        return float("nan")
    slope, icpt = np.polyfit(idx[sel], contrast[sel], 1)
    resid = contrast[sel] - (slope * idx[sel] + icpt)
    dof = max(np.count_nonzero(sel) - 2, 1)
    sc = max(float(np.interp(p_res, idx, c_std)), float(np.sqrt(np.sum(resid**2) / dof)))
    return float(sc / abs(slope)) if slope != 0 else float("inf")
