"""Line-of-sight motion in a slanted edge: each line located, or the lines folded (used by
:mod:`satchain.measure.edge`).

A pushbroom camera forms each line at its own instant, so line-of-sight motion displaces whole lines: the edge
of a line sits at its own position.  Two MTFs follow, and :func:`align_lines` gives the per-line offsets of
both from the edge polynomial that the ESF is projected on:

* **aligned** (each line located): the lines' measured edge positions (:mod:`satchain.measure.edge._crossings`)
  smoothed by a penalised fit whose stiffness comes from the data -- a Whittaker smoother (second differences,
  whose null space is the straight line) with the penalty chosen by the unbiased risk estimate (Mallows' C_p)
  under the positions' own noise.  It is used only where the positions depart from the edge polynomial by more
  than their noise (a chi-square test at about 4 sigma) and the smoothed departure is over 0.03 px rms (less
  moves the MTF at Nyquist by < 0.005): a straight edge stays the polynomial, a wobbling one is followed.  The
  blur left is that about each line's position: the budget's per-row motion terms (:mod:`satchain.tf.pushbroom`).
* **as imaged** (ISO 12233's convention): one straight line (least squares through the positions); the lines'
  displacements about it are folded into the ESF.

``los_motion_rms_px`` is the rms departure of the aligned positions from that straight line (line-of-sight
motion, or the curvature of a curved edge).  The smoother is O(lines): a banded solve per trial penalty.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solveh_banded

from satchain.measure._common import median
from satchain.measure.edge._crossings import line_numbers
from satchain.measure.edge._locate import _Poly

__all__ = ["align_lines", "los_curves", "on_grid", "smooth_positions"]

_POS_FLOOR_PX = 2e-3  # noise-free positions are exact to about this (the line profile's spline error)
_CHI_SIGMAS = 4.0  # the positions depart from the polynomial by more than their noise at this many sigma
_MIN_DEPARTURE_PX = 0.03  # a smoothed departure from the polynomial below this (rms) moves the MTF by < 0.005
_LAMBDAS = 10.0 ** np.arange(-3.0, 12.01, 0.25)  # trial penalties (second differences, px^-4 per line)


def _penalty_bands(n: int) -> np.ndarray:
    """``D^T D`` of the second difference on ``n`` points in ``solveh_banded``'s upper form (3, n)."""
    ab = np.zeros((3, n))
    diag = np.full(n, 6.0)
    diag[[0, -1]] = 1.0
    diag[[1, -2]] = 5.0
    off1 = np.full(n - 1, -4.0)
    off1[[0, -1]] = -2.0
    ab[2], ab[1, 1:], ab[0, 2:] = diag, off1, 1.0
    return ab


def smooth_positions(pos: np.ndarray, sigma_px: float) -> tuple[np.ndarray, float]:
    """Whittaker smoothing of the positions (NaN: not measured, bridged) with the penalty that minimises the
    unbiased risk ``RSS / m + 2 sigma^2 tr(H) / m`` (``sigma_px`` the positions' noise); returns (smoothed
    positions at every line, the penalty).  ``tr(H)`` from the penalty's spectrum ``(2 - 2 cos(pi k / n))^2``
    (the discrete cosine basis: exact but for the ends)."""
    n = pos.size
    ok = np.isfinite(pos)
    w = ok.astype(float)
    y = np.where(ok, pos, 0.0)
    m = max(int(np.count_nonzero(ok)), 1)
    base = _penalty_bands(n)
    mu = (2.0 - 2.0 * np.cos(np.pi * np.arange(n) / n)) ** 2
    best: tuple[float, np.ndarray, float] | None = None
    for lam in _LAMBDAS:
        ab = base * lam
        ab[2] += w
        z = solveh_banded(ab, w * y, check_finite=False)
        rss = float(np.sum((y - z)[ok] ** 2))
        tr = float(np.sum(1.0 / (1.0 + lam * mu))) * m / n
        risk = rss / m + 2.0 * sigma_px**2 * tr / m
        if best is None or risk < best[0]:
            best = (risk, z, lam)
    assert best is not None  # _LAMBDAS is not empty: the first trial always sets it
    return best[1], float(best[2])


def align_lines(pos: np.ndarray, sigma: np.ndarray, deg: int):
    """Per line (every line of the region) the edge positions for the aligned and the as-imaged ESF, the los
    motion (px rms) and whether it is significant.

    ``pos`` are the lines' measured edge positions (NaN: not measured), ``sigma`` their 1-sigma, ``deg`` the
    degree of the edge polynomial located.  Returns ``(aligned positions or None (the polynomial is kept),
    as-imaged positions or None (the polynomial is a straight line already and no motion was found),
    los_motion_rms_px, significant, noise_px)``; None throughout where fewer than 8 lines are measured.
    """
    ok = np.isfinite(pos)
    m = int(np.count_nonzero(ok))
    if m < max(8, deg + 6):
        return None, None, float("nan"), False, float("nan")
    fits = _Poly(np.arange(pos.size, dtype=float), max(deg, 1))
    w = ok.astype(float)
    y = np.where(ok, pos, 0.0)
    s_ok = ok & np.isfinite(sigma)
    s2 = float(median(sigma[s_ok] ** 2)) if s_ok.any() else 0.0
    noise = float(np.sqrt(s2 + _POS_FLOOR_PX**2))
    line = fits.value(fits.fit(y, 1, w))
    poly = line if deg == 1 else fits.value(fits.fit(y, deg, w))
    dof = m - deg - 1
    chi2 = float(np.sum((pos[ok] - poly[ok]) ** 2)) / noise**2
    smooth = smooth_positions(pos, noise)[0] if chi2 > dof + _CHI_SIGMAS * np.sqrt(2.0 * dof) else None
    if smooth is None or np.sqrt(np.mean((smooth[ok] - poly[ok]) ** 2)) < _MIN_DEPARTURE_PX:
        los = float(np.sqrt(np.mean((poly[ok] - line[ok]) ** 2)))
        return None, (None if deg == 1 else line), los, False, noise
    los = float(np.sqrt(np.mean((smooth[ok] - line[ok]) ** 2)))
    return smooth, line, los, True, noise


def los_curves(lines, where, own, moved, flags):
    """The line-of-sight motion in the lines' edge positions (:func:`align_lines`): ``(aligned curve or None
    (the located polynomial's is kept), as-imaged (f, mtf, sigma) or None (the same as the aligned), los motion
    px rms, the aligned per-line offsets from ``own`` or None)``, flag ``line_of_sight_motion`` where the
    positions depart from the polynomial beyond their noise.  ``own`` is the located edge polynomial, ``moved``:
    :func:`satchain.measure.edge._moved_curve` of per-line offsets from it (None: the ESF is projected on a
    given line, kept)."""
    transposed, roi = where
    pos = lines[1] - line_numbers(1, not transposed, roi)[0]
    at_aligned, at_imaged, los, significant, noise = align_lines(pos, lines[2], len(own) - 1)
    base = np.polyval(own, np.arange(pos.size, dtype=float))
    shift = None if moved is None or at_aligned is None else at_aligned - base
    aligned = None if shift is None else moved(shift)
    imaged = None if moved is None or at_imaged is None else moved(at_imaged - base)
    if significant:
        how = (
            "the ESF is projected on the given edge line, the lines' displacements folded in"
            if moved is None
            else "the MTF is measured with each line located (mtf_aligned; the headline mtf unless fit_degree is "
            "forced); the edge as imaged, the lines' displacements folded into the ESF (ISO 12233), is mtf_as_imaged"
        )
        flags.append(
            (
                "line_of_sight_motion",
                f"the lines' edge positions depart from one straight edge by {los:.3f} px rms, beyond their noise "
                f"({noise:.3f} px; line-of-sight motion, or a wavy edge): {how}",
            )
        )
    return aligned, (None if imaged is None else imaged[2]), los, (None if aligned is None else shift)


def on_grid(f_ref, curve):
    """A curve ``(f, mtf, sigma)`` on the frequencies ``f_ref`` (NaN beyond its own band)."""
    f, mtf, sig = curve
    out = [np.interp(f_ref, f, y, right=np.nan) for y in (mtf, sig)]
    return out[0], out[1]
