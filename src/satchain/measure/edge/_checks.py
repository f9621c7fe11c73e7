"""Slanted-edge target validation and quality flags (used by :mod:`satchain.measure.edge`).

Each check either refuses the region with a one-line :class:`~satchain.errors.InputError` (the target is not
one straight, unclipped edge) or returns quality flags ``(code, text)``: short machine-readable codes with a
human sentence.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.ndimage import correlate1d

from satchain.errors import InputError
from satchain.measure._clipping import find_clipping
from satchain.measure._common import median
from satchain.measure.edge._locate import _Poly
from satchain.measure.edge._numerics import _gauss_kernel_nd, window_mtf

__all__ = [
    "check_model",
    "check_saturation",
    "fit_plateaus",
    "check_single_edge",
    "critical_angle_flags",
    "curvature_bias_flag",
    "curvature_shift",
    "unfitted_curvature",
    "quantisation_step",
    "quantisation_flags",
    "CRITICAL_TILTS_DEG",
]

#: Tilts from the nearest axis, atan(1/n), where the rows' sub-pixel phases repeat after n rows.
CRITICAL_TILTS_DEG = (0.0, 45.0, 26.565, 18.435, 14.036)
_SAT_REFUSE_FRACTION = 0.01  # pixels at the saturation level above this fraction: refuse
_MODEL_MISS_FRACTION = 0.03  # pixels the edge model misses by > 1/4 step above this fraction: refuse
_FLAT_PLATEAU_TOL = 0.15  # a plateau departing from a straight line by this much of the step: a second edge
_QUANT_BIAS = 0.65  # worst MTF error (up to Nyquist) of an undithered quantised edge x its step count
_QUANT_DITHER = 0.45  # residual rms (in steps) from which noise dithers the quantisation (bias / 50)
_CURVE_F_STAT = 9.0  # higher-degree terms of the edge positions count when resolved (F > 9: ~3 sigma for one)


def check_saturation(data: np.ndarray, full_scale: float | None, valid=None, unique=None) -> list[tuple[str, str]]:
    """Refuse a clipped edge; flag a few pixels touching the full scale.

    Clipping is named only on evidence (:func:`satchain.measure._clipping.find_clipping`): pixels at the
    sensor's ``full_scale`` (refused above 1 % of the region, flagged below), or a plateau that shows
    saturation -- a flat run at an extreme while the noise is visible elsewhere, or, noise-free, a plateau
    reached with a kink on one side only (a profile cut flat).  A clipped plateau biases the ESF and the
    MTF (+0.045 at Nyquist for a 0.05-0.8 edge cut at 0.7): refused.  An edge's own smooth plateau, exactly
    constant in a noise-free render, is not clipping.  ``unique``: ``np.unique`` of the considered pixels, when
    known.
    """
    vals = data if valid is None else data[valid]
    lo, hi = float(vals.min()), float(vals.max())
    if hi == lo:
        raise InputError(f"image: the region is flat (every pixel = {lo:g}); no edge to measure")
    clip = find_clipping(data, full_scale=full_scale, valid=valid, unique=unique)
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
    """Level and slope of one plateau: ``a + b x + k / |x|``, the terms beyond the level taken only where
    resolved (|t| >= 3).

    A term enters on its own (forward selection: the more resolved one first, then the other beside it, kept
    where both stay resolved).  Over a plateau ``x`` and ``1 / |x|`` are nearly collinear: fitted together on
    noise their coefficients can both reach |t| = 3 while neither is resolved alone (|t| < 1), and the level,
    then an extrapolation, moved by 20 x its noise (1 DN on a 50 DN step at SNR 50: a contrast 2 % off).
    Least squares by the normal equations of the columns scaled to unit norm (well conditioned: the same
    solution as a QR/SVD least squares to rounding), one Gram matrix for every subset of the terms."""
    ax_s = np.abs(xs)
    cols = [np.ones_like(xs)]
    if xs.size >= 8 and np.ptp(xs) > 2.0:
        cols.append(xs)
        if xs.size >= 12 and ax_s.max() > 3 * ax_s.min():
            cols.append(1.0 / ax_s)
    m_all = np.stack(cols, axis=1)
    norm = np.sqrt(np.einsum("ij,ij->j", m_all, m_all))
    ms = m_all / norm
    gram, rhs = ms.T @ ms, ms.T @ es
    g_all, r_all, nrm = gram.tolist(), rhs.tolist(), norm.tolist()
    best = ([0], [r_all[0] / g_all[0][0]])  # the terms in the model (0: the level, 1: the slope, 2: k / |x|)
    if len(cols) > 1:
        fits = [_terms_fit(ms, es, g_all, r_all, [0, i]) for i in range(1, len(cols))]
        t, keep, coef = max(fits, key=lambda fit: fit[0])
        if t >= 3.0:
            best = (keep, coef)
            if len(cols) == 3:
                t, keep, coef = _terms_fit(ms, es, g_all, r_all, [0, 1, 2])
                best = (keep, coef) if t >= 3.0 else best
    keep, coef = best
    return coef[0] / nrm[0], coef[1] / nrm[1] if keep[1:2] == [1] else 0.0


def _terms_fit(ms, es, g_all, r_all, keep):
    """(the smallest |t| of the terms beyond the level, ``keep``, coefficients) of the least squares on the
    columns ``keep`` of ``ms`` (unit norm; ``g_all``, ``r_all``: their Gram matrix and ``ms.T @ es``)."""
    # (well conditioned: unit-norm columns; 2 x 2 or 3 x 3, inverted in plain floats)
    g_inv = _inv_small([[g_all[i][j] for j in keep] for i in keep])
    coef = [sum(g_inv[i][j] * r_all[k] for j, k in enumerate(keep)) for i in range(len(keep))]
    s2 = float(np.sum((es - ms[:, keep] @ np.array(coef)) ** 2)) / max(es.size - len(keep), 1)
    t = min(abs(coef[i]) / math.sqrt(max(g_inv[i][i] * s2, 1e-300)) for i in range(1, len(keep)))
    return t, keep, coef


def _inv_small(a: list) -> list:
    """The inverse of a symmetric positive definite 2 x 2 or 3 x 3 matrix (lists) by its cofactors."""
    if len(a) == 2:
        (p, q), (_, r) = a
        d = p * r - q * q
        return [[r / d, -q / d], [-q / d, p / d]]
    (a00, a01, a02), (_, a11, a12), (_, _, a22) = a
    c00, c01, c02 = a11 * a22 - a12 * a12, a02 * a12 - a01 * a22, a01 * a12 - a02 * a11
    c11, c12, c22 = a00 * a22 - a02 * a02, a01 * a02 - a00 * a12, a00 * a11 - a01 * a01
    d = a00 * c00 + a01 * c01 + a02 * c02
    return [[c00 / d, c01 / d, c02 / d], [c01 / d, c11 / d, c12 / d], [c02 / d, c12 / d, c22 / d]]


def check_single_edge(x, esf, counts, sigma, fits, lim) -> None:
    """Refuse when a side of the ESF is not a straight plateau (a stripe, a corner or a second edge)."""
    (a_lo, b_lo), (a_hi, b_hi) = fits
    step = a_hi - a_lo
    w = float(x[1] - x[0])
    s_bins = 1.0 / w  # 1 px smoothing
    es = correlate1d(esf, _gauss_kernel_nd(s_bins), mode="nearest")  # = gaussian_filter1d, without its overhead
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


def check_model(work, d_all, x, esf, model, sigma, valid=None) -> None:
    """Refuse when the fitted edge model misses many pixels of the whole region (a corner, another target).

    ``d_all`` are the distances of every pixel of ``work`` to the fitted edge (extended to every line),
    ``model = (a, b, c, e)`` the levels and gradients of ``a + b d + (c + e d) E(d)``.
    """
    a, b, c, e = model
    pred = a + b * d_all + (c + e * d_all) * np.interp(d_all, x, esf)
    miss = np.abs(work.ravel() - pred) > 0.25 * abs(c) + 5 * sigma
    if valid is not None:
        miss = miss[valid.ravel()]
    frac = np.count_nonzero(miss) / miss.size
    if frac > _MODEL_MISS_FRACTION:
        raise InputError(
            f"image: {100 * frac:.0f} % of the region's pixels differ from the fitted edge by more than a quarter "
            "of the step: the region holds more than one straight edge (a corner, a stripe, another target); "
            "give an ROI around one straight edge"
        )


def unfitted_curvature(lines, pos, coef, f, mtf):
    """Screen for an edge curvature that the fitted polynomial leaves in the edge positions.

    ``pos`` are the per-line edge positions (px along the line) at ``lines``, ``coef`` the polynomial used.
    Fits of each higher degree (up to 3) give the departure ``r`` of the edge from the fit used, along the
    normal.  Projecting along a wrong edge spreads the ESF by the distribution of ``r``, which multiplies the
    MTF by ``F(f) = |mean exp(2 pi i f r)|``: the measured ``mtf`` is about ``mtf / F - mtf`` below the edge's.
    Only extra terms resolved above the positions' noise (F statistic > 9) count.

    Returns ``(shift, f_at, spread_px, degree)`` for the largest estimated MTF shift up to Nyquist (``degree``
    the lowest higher degree that shows it, ``spread_px`` the range of ``r``), or None.
    """
    lines = np.asarray(lines, dtype=float)
    pos = np.asarray(pos, dtype=float)
    deg = len(coef) - 1
    n = lines.size
    tc = (lines - lines.mean()) / max(float(np.ptp(lines)), 1.0)
    used = np.polyval(coef, lines)
    rss_used = float(np.sum((pos - used) ** 2))
    band = (f > 0) & (f <= 0.5 + 1e-9)
    worst = None
    poly = _Poly(tc)
    for k in range(deg + 1, 4):
        dof = n - k - 1
        if dof < 4 or not np.any(band):
            break
        fit = poly.value(poly.fit(pos, k))  # np.polyfit's least squares (moments in a centred variable)
        rss = float(np.sum((pos - fit) ** 2))
        if not (rss_used - rss) / (k - deg) > _CURVE_F_STAT * max(rss / dof, 1e-30):
            continue
        r = (fit - used) / np.sqrt(1.0 + np.gradient(fit, lines) ** 2)  # along the local normal
        factor = np.abs(np.exp(2j * np.pi * np.outer(f[band], r - r.mean())).mean(axis=1))
        shift = mtf[band] * (1.0 / np.maximum(factor, 1e-3) - 1.0)
        i = int(np.argmax(shift))
        if worst is None or shift[i] > 1.25 * worst[0]:  # a higher degree must show clearly more
            worst = (float(shift[i]), float(f[band][i]), float(np.ptp(r)), k)
    return worst


def curvature_shift(d, r, x, esf, half_w: float, f):
    """Largest MTF shift up to Nyquist that edge departures ``r`` (px along the normal) cause: ``(shift, f)``.

    ``d`` are the samples' distances as projected on the fitted edge, ``r`` the departure of each sample's
    line from it (its true distance is ``d + r``), ``esf`` the ESF measured along the better edge (bins at
    ``x``).  Each bin of the projected ESF averages the true ESF over its samples' offsets, so it is
    ``esf + mean(esf(d + r) - esf(d))``; both go through the same LSF map (window ``half_w``) and their MTFs
    differ by the shift.  This is exact for the region (residuals that follow the rows' sub-pixel phases
    included, which a spread of the positions alone misses by up to 1.7 x at 2 deg tilt), and the noise of
    ``esf`` is common to both.
    """
    w = float(x[1] - x[0])
    kb = np.rint((d - x[0]) / w).astype(int)
    ok = (kb >= 0) & (kb < x.size)
    delta = np.interp(d[ok] + r[ok], x, esf) - np.interp(d[ok], x, esf)
    n = np.bincount(kb[ok], minlength=x.size)
    smeared = esf + np.bincount(kb[ok], weights=delta, minlength=x.size) / np.maximum(n, 1)
    band = (f > 0) & (f <= 0.5 + 1e-9)
    diff = np.abs(window_mtf(x, esf, half_w, f[band]) - window_mtf(x, smeared, half_w, f[band]))
    i = int(np.argmax(diff))
    return float(diff[i]), float(f[band][i])


def curvature_bias_flag(deg: int, shift: float, f_at: float, spread_px: float, k: int, *, forced: bool):
    """The ``curvature_bias`` flag: the MTF of a degree-``k`` fit differs by ``shift`` at ``f_at`` cy/px."""
    how = (
        "measure with fit_degree='auto' (or a higher degree)"
        if forced
        else f"the automatic choice kept degree {deg} (the curvature is below its evidence threshold); check with "
        f"fit_degree={k}"
    )
    return (
        "curvature_bias",
        f"edge curvature left by the degree-{deg} fit: the edge departs from it by up to {spread_px:.2f} px, "
        f"which spreads the ESF; a degree-{k} fit moves the MTF by {shift:.3f} (at {f_at:.2f} cy/px); {how}",
    )


def quantisation_step(data: np.ndarray, unique=None) -> float | None:
    """The step of the value lattice the region's pixels sit on (1 for most integer images), or None.

    None for continuous data (more distinct values than half the pixels, or values off any lattice).
    ``unique``: ``np.unique(data)`` when known.  Without it, continuous data are told apart first by
    :func:`distinct_lower_bound` (no sort)."""
    if unique is None and distinct_lower_bound(data) > 0.5 * np.size(data):
        return None
    u = np.unique(data) if unique is None else unique
    if u.size < 2 or u.size > 0.5 * data.size:
        return None
    q = float(np.min(np.diff(u)))
    if not q > 1e-7 * float(u[-1] - u[0]):  # float data that merely repeat a few values
        return None
    k = (u - u[0]) / q
    if not np.allclose(k, np.round(k), rtol=0.0, atol=1e-3):
        return None
    return q


_HASH_MUL, _HASH_SHIFT = np.uint64(0x9E3779B97F4A7C15), np.uint64(64 - 17)


def distinct_lower_bound(data) -> int:
    """A lower bound on the number of distinct values of ``data`` (finite floats), in O(n): the number of
    distinct 17-bit multiplicative hashes of their bit patterns (equal values hash alike; ``-0.0`` is made
    ``0.0`` first).  Continuous data of n << 2**17 values come close to n; ``np.unique(data).size`` is the
    exact count."""
    bits = (np.asarray(data, dtype=np.float64).ravel() + 0.0).view(np.uint64)
    seen = np.zeros(1 << 17, dtype=bool)
    seen[((bits * _HASH_MUL) >> _HASH_SHIFT).astype(np.intp)] = True
    return int(np.count_nonzero(seen))


def quantisation_flags(q: float, x: np.ndarray, esf: np.ndarray, resid: np.ndarray) -> list[tuple[str, str]]:
    """Flag (``quantisation``) an edge whose step spans few quantisation steps that the noise does not dither.

    Without noise each pixel is rounded to the lattice of step ``q`` and the binned ESF becomes a staircase
    that biases the MTF.  On exact Gaussian-PSF edges (benchmarks/bench_edge_audit.py) the largest error up
    to Nyquist is 0.3-0.65 / L for a step of L levels (100 -> 120 DN: 0.02-0.03, 10 % at Nyquist), so it
    exceeds 0.01 below about 65 levels.  Noise of >= 0.45 steps rms dithers the rounding and leaves it
    unbiased (the staircase's first harmonic falls by exp(-2 pi^2 s^2) < 1/50); the residual rms about
    the binned ESF (the robust sigma sees only the mode of rounded noise) measures it.
    """
    q4 = max(2, esf.size // 4)
    step = abs(float(median(esf[-q4:]) - median(esf[:q4])))
    levels = step / q
    keep = np.abs(resid) < max(0.1 * step, 2 * q)
    dither = float(np.sqrt(np.mean(resid[keep] ** 2))) / q if np.any(keep) else 0.0
    bias = _QUANT_BIAS / max(levels, 1e-9)
    if bias <= 0.01 or dither >= _QUANT_DITHER:
        return []
    return [
        (
            "quantisation",
            f"quantised values: the edge step is {levels:.0f} quantisation steps of {q:g} (one step = "
            f"{100 / max(levels, 1e-9):.1f} % of the contrast) and the noise ({dither:.2f} steps rms) is too small to "
            f"dither them; the MTF may be off by up to about {bias:.2f} (worst case; a larger contrast or noise "
            "of half a step avoids it)",
        )
    ]
