"""Slanted-edge target validation and quality flags (used by :mod:`satchain.measure.edge`).

Each check either refuses the region with a one-line :class:`~satchain.errors.InputError` (the target is not
one straight, unclipped edge) or returns quality flags ``(code, text)``: short machine-readable codes with a
human sentence.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d

from satchain.errors import InputError
from satchain.measure._clipping import find_clipping

__all__ = [
    "check_model",
    "check_saturation",
    "fit_plateaus",
    "check_single_edge",
    "critical_angle_flags",
    "CRITICAL_TILTS_DEG",
]

#: Tilts from the nearest axis, atan(1/n), where the rows' sub-pixel phases repeat after n rows.
CRITICAL_TILTS_DEG = (0.0, 45.0, 26.565, 18.435, 14.036)
_SAT_REFUSE_FRACTION = 0.01  # pixels at the saturation level above this fraction: refuse
_MODEL_MISS_FRACTION = 0.03  # pixels the edge model misses by > 1/4 step above this fraction: refuse
_FLAT_PLATEAU_TOL = 0.15  # a plateau departing from a straight line by this much of the step: a second edge


def check_saturation(data: np.ndarray, full_scale: float | None) -> list[tuple[str, str]]:
    """Refuse a clipped edge; flag a few pixels touching the full scale.

    Clipping is named only on evidence (:func:`satchain.measure._clipping.find_clipping`): pixels at the
    sensor's ``full_scale`` (refused above 1 % of the region, flagged below), or a plateau that shows
    saturation -- a flat run at an extreme while the noise is visible elsewhere, or, noise-free, a plateau
    reached with a kink on one side only (a profile cut flat).  A clipped plateau biases the ESF and the
    MTF (+0.045 at Nyquist for a 0.05-0.8 edge cut at 0.7): refused.  An edge's own smooth plateau, exactly
    constant in a noise-free render, is not clipping.
    """
    lo, hi = float(data.min()), float(data.max())
    if hi == lo:
        raise InputError(f"image: the region is flat (every pixel = {lo:g}); no edge to measure")
    clip = find_clipping(data, full_scale=full_scale)
    if clip is None:
        return []
    if clip.evidence == "full_scale":
        if clip.fraction > _SAT_REFUSE_FRACTION:
            raise InputError(
                f"image: {clip.n_pixels} pixel(s) ({100 * clip.fraction:.1f} %) at or above the saturation level "
                f"(full scale) {clip.level:g}; the edge is clipped"
            )
        return [("clipping", f"{clip.n_pixels} pixel(s) touch the full scale {clip.level:g} (not refused: < 1 %)")]
    raise InputError(f"image: the edge is clipped (saturated): {clip.message.removeprefix('clipping: ')}")


def fit_plateaus(x: np.ndarray, esf: np.ndarray, lim: float):
    """Fits ``a + b x (+ k / |x|)`` of the dark (x < -lim) and bright (x > lim) sides of the binned ESF.

    ``a`` is the plateau level, ``b`` its slope (illumination gradient); the ``k`` term absorbs the slow
    1/|x| approach of diffraction tails so that it is not taken for a gradient.
    Returns ((a_lo, b_lo), (a_hi, b_hi)); refuses an edge at the border of the region.
    """
    fits = []
    for side in (x < 0, x > 0):
        ax = np.abs(x[side])
        if ax.size < 4:
            raise InputError("image: the edge lies at the border of the region; centre it in the ROI")
        if ax.max() < lim:  # a ramp, or an edge whose transition fills the region: no plateau to fit
            raise InputError(
                f"image: no plateau: the transition (2 x its 10-90 % rise = {lim:.1f} px) reaches the region's "
                f"border ({ax.max():.1f} px from the edge); not an edge, or the region is too small for its blur"
            )
        use = min(lim, 0.5 * ax.max())
        sel = ax >= use
        xs, es = x[side][sel], esf[side][sel]
        a, b = _plateau_line(xs, es)
        fits.append((float(a), float(b)))
    return fits[0], fits[1]


def _plateau_line(xs: np.ndarray, es: np.ndarray):
    """Level and slope of one plateau: ``a + b x + k / |x|``, dropping the terms not resolved (|t| < 3)."""
    ax_s = np.abs(xs)
    cols = [np.ones_like(xs)]
    if xs.size >= 8 and np.ptp(xs) > 2.0:
        cols.append(xs)
        if xs.size >= 12 and ax_s.max() > 3 * ax_s.min():
            cols.append(1.0 / ax_s)
    while True:
        m = np.stack(cols, axis=1)
        coef, *_ = np.linalg.lstsq(m, es, rcond=None)
        if len(cols) == 1:
            return float(coef[0]), 0.0
        dof = max(xs.size - len(cols), 1)
        s2 = float(np.sum((es - m @ coef) ** 2)) / dof
        se = np.sqrt(np.maximum(np.diag(np.linalg.pinv(m.T @ m)) * s2, 1e-300))
        t = np.abs(coef[1:]) / se[1:]
        if np.all(t >= 3.0):
            return float(coef[0]), float(coef[1]) if len(cols) > 1 and cols[1] is xs else 0.0
        cols.pop(1 + int(np.argmin(t)))


def check_single_edge(x, esf, counts, sigma, fits, lim) -> None:
    """Refuse when a side of the ESF is not a straight plateau (a stripe, a corner or a second edge)."""
    (a_lo, b_lo), (a_hi, b_hi) = fits
    step = a_hi - a_lo
    w = float(x[1] - x[0])
    s_bins = 1.0 / w  # 1 px smoothing
    es = gaussian_filter1d(esf, s_bins, mode="nearest")
    noise = sigma / np.sqrt(np.maximum(counts, 1) * 2 * np.sqrt(np.pi) * s_bins)
    for side, (a, b), name in ((x < -lim, (a_lo, b_lo), "dark"), (x > lim, (a_hi, b_hi), "bright")):
        if not np.any(side):
            continue
        dev = np.abs(es[side] - (a + b * x[side])) - 6 * noise[side]
        k = int(np.argmax(dev))
        if dev[k] > _FLAT_PLATEAU_TOL * abs(step):
            raise InputError(
                f"image: the {name} side of the edge is not flat ({abs(x[side][k]):.0f} px from the edge it departs "
                f"from its plateau by {dev[k] + 6 * noise[side][k]:.3g} while the step is {abs(step):.3g}): the region "
                "holds more than one edge (a stripe, a corner or another edge); give an ROI around one straight edge"
            )


def critical_angle_flags(slope: float, n_lines: int, mode: str, width: float) -> list[tuple[str, str]]:
    """Flags on tilts near atan(1/n) (phases repeat; measured on the natural lattice) and near an axis."""
    tilt = float(np.degrees(np.arctan(abs(slope))))
    out = []
    for a in CRITICAL_TILTS_DEG:
        if abs(tilt - a) < 1.0:
            out.append(
                (
                    "angle_near_critical",
                    f"near-critical angle: edge tilt {tilt:.2f} deg is within 1 deg of {a:g} deg, where the "
                    f"sub-pixel phases repeat; the ESF is sampled on a {width:.3f} px lattice ({mode} bins), with "
                    "less phase diversity and more noise; a tilt of about 3-10 deg is best",
                )
            )
    if n_lines * abs(slope) < 1.0:
        out.append(
            (
                "phases_incomplete",
                f"edge shifts only {n_lines * abs(slope):.2f} px over {n_lines} lines: phases incomplete",
            )
        )
    return out


def check_model(work, d_all, x, esf, model, sigma) -> None:
    """Refuse when the fitted edge model misses many pixels of the whole region (a corner, another target).

    ``d_all`` are the distances of every pixel of ``work`` to the fitted edge (extended to every line),
    ``model = (a, b, c, e)`` the levels and gradients of ``a + b d + (c + e d) E(d)``.
    """
    a, b, c, e = model
    pred = a + b * d_all + (c + e * d_all) * np.interp(d_all, x, esf)
    miss = np.abs(work.ravel() - pred) > 0.25 * abs(c) + 5 * sigma
    frac = np.count_nonzero(miss) / miss.size
    if frac > _MODEL_MISS_FRACTION:
        raise InputError(
            f"image: {100 * frac:.0f} % of the region's pixels differ from the fitted edge by more than a quarter "
            "of the step: the region holds more than one straight edge (a corner, a stripe, another target); "
            "give an ROI around one straight edge"
        )
