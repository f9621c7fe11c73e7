"""Where each image line crosses an edge (used by :mod:`satchain.measure.edge` and :mod:`satchain.measure.jitter`).

A pushbroom camera forms each line at its own instant, so line-of-sight motion shifts whole lines: the position
of a long straight edge line by line records the motion (a cal/val method).  The position of line ``i`` is
found by fitting the edge's own profile to that line (a matched filter, the maximum-likelihood estimator for
white noise):

1. A first position per line: the centroid of the ``[-1/2, 0, 1/2]`` derivative in a window around the
   derivative's peak, searched near the edge fitted over the region.
2. The edge's line profile, ``T(u)`` with ``u = column - position``, estimated from all lines at once: a
   least-squares cubic B-spline (knots every 0.5 px, wider where the phases leave a gap) through every pixel
   near the edge, placed by its line's position (the lines' sub-pixel phases sample ``T`` finely, as in the
   slanted-edge method).
3. Each line fitted alone: ``v_k = a_i + c_i T(k - x_i)`` over ``2 (W + 2) + 1`` pixels around the edge
   (Gauss-Newton in ``a_i, c_i, x_i``), then steps 2-3 twice more from the fitted positions, the last fit over
   ``2 W + 1`` pixels.  ``x_i`` is reported relative to the 50 % crossing of ``T`` between its plateaus: the
   edge's centre for a symmetric blur.

Every pixel's value is a function of its distance to the edge only, whatever the sub-pixel phase, so the fit
has no phase-dependent bias beyond the spline's error (a few 1e-4 px; a 50 % crossing interpolated between two
pixels is biased by up to ~0.05 px with the phase, which a tilted edge turns into a false periodic wobble).
Its noise is the Cramer-Rao bound ``sigma_x^2 = sigma^2 / sum_k (c T'(k - x))^2`` (about half the derivative
centroid's variance): the 1-sigma per line comes from that, with ``sigma`` the pixel noise pooled over every
line's residuals (weighted as the position sees them).  A line is not measured (NaN) where its window leaves
the region or touches an excluded or clipped pixel, and where its fit fails or departs from the other lines
(contrast off by 30 %, residuals above 3x the typical line's).
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import BSpline, PPoly
from scipy.linalg.lapack import dpbsv

from satchain.errors import InputError
from satchain.measure._common import median as _median
from satchain.measure._common import robust_sigma

__all__ = ["edge_line_fields", "line_numbers", "line_positions", "rough_line"]

_KNOT_PX = 0.5  # template knot spacing (finer knots let noise trade the profile for a phase-locked bias)
_MAX_GAP_PX = 0.75  # largest gap in the lines' sub-pixel phases the template can bridge
_CONTRAST_TOL = 0.3  # a line whose step differs more from the median step is not measured
# Gauss-Newton stops when every line's step, or the steps still to come, are below this (px; relative for the
# levels): :func:`_converged`
_TOL_STEP = 1e-5
_SORT_PHASES = 4096  # up to this many lines the phase gap comes from sorting them, above from 64 bins
_RMS_TOL = 3.0  # ... nor one whose residual rms exceeds this x the median line's (plus 0.5 % of the step)


def edge_line_fields(work, coef, valid, clip, transposed: bool, roi):
    """(lines, positions, 1-sigma) in full-image pixel coordinates: ``lines`` are the image rows crossing an
    ACT edge (columns for an ALT one), ``positions`` the x (y) where each crosses it, NaN where not measured.

    ``work`` is the oriented region (rows cross the edge, rising along +x), ``coef`` the edge fitted over it,
    ``valid`` its mask (or None), ``clip = (full_scale or None, sign)`` marks the clipped pixels
    (``work * sign >= full_scale``), ``roi`` the region's offset in the image.
    """
    full_scale, sign = clip
    usable = None if full_scale is None else (work * sign) < full_scale
    if valid is not None:
        usable = valid if usable is None else usable & valid
    pos, sig = line_positions(work, coef, usable)
    lines = line_numbers(work.shape[0], transposed, roi)
    return lines, pos + (line_numbers(1, not transposed, roi)[0]), sig


def rough_line(work: np.ndarray, usable=None) -> np.ndarray:
    """A straight line ``x = coef[0] y + coef[1]`` through the lines' derivative peaks (least squares, then once
    more without the peaks off it by more than 5 robust sigma + 3 px): only where to search for the edge, for
    an edge that wobbles too much for :func:`satchain.measure.edge._locate.locate_edge`'s robust fit."""
    ny, nx = work.shape
    g = np.zeros_like(work)
    g[:, 1:-1] = 0.5 * (work[:, 2:] - work[:, :-2])
    if usable is not None:
        g[:, 1:-1] *= usable[:, 2:] & usable[:, :-2]
    rows = np.arange(ny, dtype=float)
    peak = np.argmax(g, axis=1).astype(float)
    coef = np.polyfit(rows, peak, 1)
    off = peak - np.polyval(coef, rows)
    keep = np.abs(off) <= 5.0 * robust_sigma(off) + 3.0
    return np.polyfit(rows[keep], peak[keep], 1) if np.count_nonzero(keep) >= 2 else coef


def line_numbers(n: int, transposed: bool, roi) -> np.ndarray:
    """The image line (row; column when ``transposed``) of each of the region's ``n`` lines."""
    if hasattr(roi, "to_roi"):
        roi = roi.to_roi()
    x0, y0 = (0, 0) if roi is None else (int(roi[0]), int(roi[1]))
    return np.arange(n) + (x0 if transposed else y0)


def line_positions(work: np.ndarray, coef, usable=None):
    """Per line (row of ``work``) the edge position (column, px) and its 1-sigma; NaN where not measured.

    Examples
    --------
    >>> from scipy.special import ndtr
    >>> y, x = np.mgrid[0:40, 0:30].astype(float)
    >>> xe = 12.3 + 0.07 * y[:, :1] + 0.5 * np.sin(y[:, :1] / 3)
    >>> pos, sig = line_positions(ndtr((x - xe) / 0.8), np.array([0.07, 12.3]))
    >>> bool(np.max(np.abs(pos - xe[:, 0])) < 2e-3)
    True
    """
    ok_px = np.ones(work.shape, dtype=bool) if usable is None else np.asarray(usable, dtype=bool)
    half_t = max(4, min(16, work.shape[1] // 3))
    start = _first_positions(work, coef, ok_px, half_t, all_ok=usable is None or bool(ok_px.all()))
    nan = np.full(start.shape, np.nan)
    if np.count_nonzero(np.isfinite(start)) < 4:
        return nan, nan
    cols = np.rint(_nan0(start))[:, None] + np.arange(-half_t, half_t + 1)[None, :]
    spline = _template(work, ok_px, cols, np.broadcast_to(start[:, None], cols.shape))
    half = _half_width(spline)
    pos = start
    for wide in (True, True, False):
        h = min(half + 2, half_t) if wide else half
        pos, sig, cols = _fit_lines(work, pos, ok_px, spline, h, final=not wide)
        if np.count_nonzero(np.isfinite(pos)) < 4:
            return nan, nan
        if wide:
            spline = _template(work, ok_px, cols, np.broadcast_to(pos[:, None], cols.shape))
    return pos + _centre(spline, half), sig


def _first_positions(work, coef, ok_px, half_t: int, all_ok: bool = False) -> np.ndarray:
    """Derivative centroid per line near the derivative's peak (searched around the fitted edge); NaN where the
    window leaves the region or touches an unusable pixel (``all_ok``: every pixel is usable)."""
    ny, nx = work.shape
    cols = np.arange(nx, dtype=float)
    g = np.zeros_like(work)
    g[:, 1:-1] = 0.5 * (work[:, 2:] - work[:, :-2])
    if not all_ok:
        g[:, 1:-1] *= ok_px[:, 2:] & ok_px[:, :-2]
    gs = g.copy()
    gs[:, 1:-1] = 0.25 * g[:, :-2] + 0.5 * g[:, 1:-1] + 0.25 * g[:, 2:]
    fitted = np.polyval(coef, np.arange(ny, dtype=float))
    spread = robust_sigma(np.argmax(gs, axis=1) - fitted)
    band = float(np.clip(4.0 * spread + 4.0, 4.0, nx / 2.0))
    peak = np.argmax(np.where(np.abs(cols[None, :] - fitted[:, None]) <= band, gs, -np.inf), axis=1)
    h = max(3, half_t // 2)
    lo, hi = peak - h, peak + h
    inside = (lo >= 1) & (hi <= nx - 2)
    kb = peak[:, None] + np.arange(-h, h + 1)[None, :]  # the window's columns (in range where ``inside``)
    gw = g.take(_row_take(np.minimum(np.maximum(kb, 0), nx - 1), nx))
    tot = gw.sum(axis=1)
    if all_ok:
        clean = True
    else:
        bad_px = np.cumsum(np.concatenate([np.zeros((ny, 1), int), ~ok_px], axis=1), axis=1)
        lo_c, hi_c = np.clip(lo - 1, 0, nx - 1), np.clip(hi + 1, 0, nx - 1)
        clean = (bad_px[np.arange(ny), hi_c + 1] - bad_px[np.arange(ny), lo_c]) == 0
    good = inside & clean & (tot > 0)
    cen = np.full(ny, np.nan)
    cen[good] = (gw * kb).sum(axis=1)[good] / tot[good]
    return cen


def _template(work, ok_px, cols, place):
    """The edge's line profile ``T(u)``: a least-squares cubic B-spline through the pixels ``cols`` (lines x
    samples) at ``u = column - place`` (NaN places and unusable pixels left out)."""
    nx = work.shape[1]
    kc = _clip(cols, 0, nx - 1).astype(int)  # cols are finite (placed from finite or zeroed starts)
    flat = _row_take(kc, nx)
    take = np.isfinite(place) & (cols >= 0) & (cols <= nx - 1) & ok_px.take(flat)
    u = (cols - place)[take]
    v = work.take(flat)[take]
    # the columns are whole pixels, so a line's samples share its phase frac(-place): the gap from the lines
    gap = _phase_gap(-place[:, 0][take.any(axis=1)])
    if gap > _MAX_GAP_PX:
        raise InputError(
            f"image: the lines' sub-pixel edge phases leave a {gap:.2f} px gap (> {_MAX_GAP_PX}); the edge is "
            "too close to a pixel axis for its length: tilt it by 2-10 deg or use more lines"
        )
    step = max(_KNOT_PX, 1.25 * gap)
    lo_u, hi_u = float(u.min()), float(u.max())
    inner = np.arange(np.ceil(lo_u / step) * step, hi_u, step)
    inner = inner[(inner > lo_u + 0.5 * step) & (inner < hi_u - 0.5 * step)]
    knots = np.concatenate([[lo_u] * 4, inner, [hi_u] * 4])
    try:
        return _lsq_spline(u, v, knots)
    except (np.linalg.LinAlgError, ValueError):
        raise InputError("image: the edge's line profile cannot be estimated (too few lines or phases)") from None


def _phase_gap(u: np.ndarray) -> float:
    """The largest gap in the sub-pixel phases ``frac(u)`` (cyclic): exact for up to :data:`_SORT_PHASES`
    phases (sorted); for more, exact where it matters: when 64 bins of the phases leave no empty run longer
    than 23 bins the gap is below 25 / 64 < 0.4 px, where the template neither refuses (> 0.75) nor widens its
    knots (1.25 x gap > 0.5), and the bound is returned; else the exact gap from the sorted phases."""
    if u.size == 0:
        return 1.0
    frac = np.mod(u, 1.0)
    if frac.size <= _SORT_PHASES:  # few lines: sorting them is cheaper than the bins
        frac.sort()
        return float(max(np.max(np.diff(frac), initial=0.0), frac[0] + 1.0 - frac[-1]))
    nb = 64
    empty = np.bincount(np.minimum((frac * nb).astype(np.intp), nb - 1), minlength=nb) == 0
    if not empty.any():
        return 2.0 / nb
    if not empty.all():
        # longest cyclic run of empty bins: start from a filled bin
        e = np.roll(empty, -int(np.argmin(empty)))
        edges = np.diff(np.concatenate([[0], e.view(np.int8), [0]]))
        run = int(np.max(np.nonzero(edges == -1)[0] - np.nonzero(edges == 1)[0]))
        if run + 2 <= 25:
            return (run + 2) / nb
    frac = np.sort(frac)
    return float(np.max(np.diff(np.concatenate([frac, frac[:1] + 1.0]))))


def _lsq_spline(u, v, knots) -> BSpline:
    """Least-squares cubic B-spline on ``knots`` through (u, v): the banded normal equations (each sample
    touches 4 basis functions) solved by Cholesky; the B-spline basis is well conditioned, so this agrees with
    a QR solution (scipy's ``make_lsq_spline``) to rounding.  Refuses (LinAlgError) a singular system."""
    nc = len(knots) - 4
    first, cols = _basis_cols(u, knots, nc)
    # per knot interval the sums of the products of its 4 basis functions (one bincount each), then added
    # into the band: A[p, p + d] = sum_a G_(a, a + d)[p - a]
    n_int = nc - 3
    ab = np.zeros((4, nc))  # upper band storage: ab[3 + i - j, j] = A[i, j]
    rhs = np.zeros(nc)
    for a in range(4):
        rhs[a : a + n_int] += np.bincount(first, weights=cols[a] * v, minlength=n_int)
        for d in range(4 - a):
            g = np.bincount(first, weights=cols[a] * cols[a + d], minlength=n_int)
            ab[3 - d, a + d : a + d + n_int] += g
    if not (ab[3].min() > 0.0 and np.isfinite(ab.sum() + rhs.sum())):
        raise np.linalg.LinAlgError("a basis function holds no sample")
    _, coef, info = dpbsv(ab, rhs, lower=0)  # scipy.linalg.solveh_banded's own LAPACK call
    if info != 0:
        raise np.linalg.LinAlgError("the spline's normal matrix is not positive definite")
    return BSpline.construct_fast(knots, coef, 3)


def _basis(u, t, nc: int):
    """The 4 cubic B-splines nonzero at each ``u`` (Cox-de Boor, de Boor's triangle; the NURBS Book A2.2):
    (index of the first, values (n, 4))."""
    first, cols = _basis_cols(u, t, nc)
    return first, np.stack(cols, axis=1)


def _basis_cols(u, t, nc: int):
    """:func:`_basis` as (index of the first, the 4 values as separate contiguous arrays)."""
    i = np.clip(np.searchsorted(t, u, side="right") - 1, 3, nc - 1)
    l1, l2, l3 = (u - t[i + 1 - j] for j in (1, 2, 3))
    r1, r2, r3 = (t[i + j] - u for j in (1, 2, 3))
    # de Boor's triangle unrolled (degree 1, 2, 3): the same operations without the zero start terms
    temp = 1.0 / (r1 + l1)
    n0, n1 = r1 * temp, l1 * temp
    temp = n0 / (r1 + l2)
    n0, saved = r1 * temp, l2 * temp
    temp = n1 / (r2 + l1)
    n1, n2 = saved + r2 * temp, l1 * temp
    temp = n0 / (r1 + l3)
    n0, saved = r1 * temp, l3 * temp
    temp = n1 / (r2 + l2)
    n1, saved = saved + r2 * temp, l2 * temp
    temp = n2 / (r3 + l1)
    n2, n3 = saved + r3 * temp, l1 * temp
    return i - 3, [n0, n1, n2, n3]


class _Cubic:
    """A cubic spline as polynomials on its knot intervals: value and derivative in one pass."""

    def __init__(self, spline):
        t = spline.t
        self.bx = t[3:-3]  # (the template's knots: 4-fold ends, strictly increasing inside)
        # the pieces' power coefficients (highest first) from the spline's derivatives at each piece's left end
        c = list(PPoly.from_spline(spline).c[:, 3 : t.size - 4])
        # rows (c0, c1, c2, c3, 3 c0, 2 c1) per piece: value ((c0 dx + c1) dx + c2) dx + c3, slope
        # (3 c0 dx + 2 c1) dx + c2
        self.table = np.stack(c + [3.0 * c[0], 2.0 * c[1]])
        inner = np.diff(self.bx[1:-1])
        # the template's knots are uniform inside (np.arange): the interval by arithmetic, not a search (at a
        # knot it may pick the neighbouring piece, whose value and slope agree there to rounding: C2 spline)
        self.uniform = inner.size >= 2 and float(inner.max() - inner.min()) <= 1e-9 * float(inner[0])
        if self.uniform:
            self.inv = (inner.size) / float(self.bx[-2] - self.bx[1])

    @classmethod
    def of(cls, spline) -> _Cubic:
        """The piecewise form of ``spline``, made once per spline (kept on it)."""
        cubic = getattr(spline, "_satchain_cubic", None)
        if cubic is None:
            cubic = cls(spline)
            spline._satchain_cubic = cubic
        return cubic

    def index(self, u):
        """The knot interval of each ``u`` (the ends extended)."""
        if not self.uniform:
            return np.clip(np.searchsorted(self.bx, u, side="right") - 1, 0, self.bx.size - 2)
        i = np.floor((u - self.bx[1]) * self.inv).astype(np.intp)
        i += 1
        return np.minimum(np.maximum(i, 0, out=i), self.bx.size - 2, out=i)

    def __call__(self, u, out=None):
        """(value, slope) at ``u``; into ``out = (value array, slope array)`` when given."""
        i = self.index(u)
        dx = u - self.bx.take(i)
        c0, c1, c2, c3, d0, d1 = self.table.take(i, axis=1)  # the pieces' coefficients at once
        if out is None:
            out = np.empty_like(dx), np.empty_like(dx)
        np.add(((c0 * dx + c1) * dx + c2) * dx, c3, out=out[0])
        np.add((d0 * dx + d1) * dx, c2, out=out[1])
        return out

    def value(self, u):
        """The value at ``u`` (as :meth:`__call__`'s first array)."""
        i = self.index(u)
        dx = u - self.bx.take(i)
        c0, c1, c2, c3 = self.table[:4].take(i, axis=1)
        return ((c0 * dx + c1) * dx + c2) * dx + c3


def _rise(spline):
    """(u grid, profile normalised to its plateaus 0 -> 1) over the spline's range."""
    lo_u, hi_u = spline.t[0], spline.t[-1]
    uu = np.arange(lo_u, hi_u, 0.01)
    t = _Cubic.of(spline).value(uu)  # the spline's value (its pieces, as the fits use it)
    a, b = float(t[:150].sum()) / 150, float(t[-150:].sum()) / 150
    return uu, ((t - a) / (b - a) if b != a else np.zeros_like(t))


def _half_width(spline) -> int:
    """Fitting half-width W (px): 1.5 x the 10-90 % rise + 3, in [4, the template's reach - 1]."""
    uu, rel = _rise(spline)
    u10, u90 = (float(uu[np.argmax(rel >= q)]) for q in (0.1, 0.9))
    reach = int(min(-spline.t[0], spline.t[-1])) - 1
    return int(np.clip(np.ceil(1.5 * abs(u90 - u10)) + 3, 4, max(4, reach)))


def _centre(spline, half: int) -> float:
    """The edge's centre in ``u``: the 50 % crossing of ``T`` between its plateaus (the means of ``T`` over
    the outer 1.5 px of each side), the centre of a symmetric blur."""
    uu, rel = _rise(spline)
    i = int(np.argmax(rel >= 0.5))
    if i == 0:
        return float(uu[0])
    return float(uu[i - 1] + (0.5 - rel[i - 1]) * (uu[i] - uu[i - 1]) / (rel[i] - rel[i - 1]))


def _fit_lines(work, start, ok_px, spline, half: int, final: bool = True):
    """Gauss-Newton fit of ``a + c T(k - x)`` to each line over 2 W + 1 pixels around ``start``; ``final``
    False (a pass whose positions only place the next template): the residuals of the last step's start.

    Returns (x, sigma_x, the pixels' columns)."""
    ny, nx = work.shape
    lo_u, hi_u = spline.t[0], spline.t[-1]
    x = _nan0(start)
    k = np.rint(x)[:, None] + np.arange(-half, half + 1)[None, :]
    kc = np.clip(k, 0, nx - 1).astype(int)
    ok = np.isfinite(start) & (k[:, 0] >= 0) & (k[:, -1] <= nx - 1)
    flat = _row_take(kc, nx)
    ok &= ok_px.take(flat).all(axis=1)
    v = work.take(flat)
    cubic = _Cubic.of(spline)
    # per pixel (1, T, T', v): their Gram matrix holds the normal equations, and the residual's sums follow
    # from it (linear in r = v - a - c T)
    q = np.empty(v.shape + (4,))
    q[..., 0] = 1.0
    q[..., 3] = v
    cubic(_clip(k - x[:, None], lo_u, hi_u), out=(q[..., 1], q[..., 2]))
    gram = np.matmul(q.transpose(0, 2, 1), q)  # (lines, 4, 4)
    a, c = _levels(gram)
    scale = np.abs(c) + np.abs(a) + 1e-300
    tol_ac = _TOL_STEP * scale[ok, None]
    s_ok = None  # the last step (measurable lines)
    for it in range(9):
        if it > 0:
            cubic(_clip(k - x[:, None], lo_u, hi_u), out=(q[..., 1], q[..., 2]))
            gram = np.matmul(q.transpose(0, 2, 1), q)
        if it == 8:
            break
        step = _solve(gram, a, c)
        a_r, c_r = a, c  # the levels of the residual at this step's start
        a, c = a + step[:, 0], c + step[:, 1]
        x = x + _clip(step[:, 2], -0.5, 0.5)
        s_ok, prev = np.abs(step[ok]), s_ok
        if _converged(s_ok, prev, tol_ac):
            if not final:  # a wide pass: only the positions go on (residuals moved by < 1e-5 px steps)
                return (*_accept(ok, x, start, (a, c, _rss(gram, a_r, c_r), None), half), k)
            cubic(_clip(k - x[:, None], lo_u, hi_u), out=(q[..., 1], q[..., 2]))
            gram = np.matmul(q.transpose(0, 2, 1), q)
            break
    if not final:
        return (*_accept(ok, x, start, (a, c, _rss(gram, a, c), None), half), k)
    r = v - (a[:, None] + c[:, None] * q[..., 1])  # the final residuals, summed directly (no cancellation)
    return (*_accept(ok, x, start, (a, c, np.einsum("ij,ij->i", r, r), _normal(gram, c)), half), k)


def _converged(s, prev, tol_ac) -> bool:
    """Gauss-Newton has converged: for every measurable line, each of its steps ``s`` (|da|, |dc|, |dx|) is
    below :data:`_TOL_STEP` px (``tol_ac`` for the levels), or the steps still to come are: the iteration
    converges linearly here (each step ~0.03 x the last at SNR 100), so after a step ``s`` that follows
    ``prev`` the rest add up to ``s r / (1 - r)`` with ``r = s / prev`` (a step that did not shrink: inf)."""
    if (s[:, 2] < _TOL_STEP).all() and (s[:, :2] < tol_ac).all():
        return True
    if prev is None:
        return False
    left = np.full_like(s, np.inf)
    np.divide(s * s, prev - s, out=left, where=s < prev)
    np.minimum(left, s, out=left)  # (a step below the tolerance passes as it did)
    return bool((left[:, 2] < _TOL_STEP).all() and (left[:, :2] < tol_ac).all())


def _row_take(kc: np.ndarray, nx: int) -> np.ndarray:
    """Flat indices of the columns ``kc`` (lines x samples, in range) of a C-ordered (lines, nx) array:
    ``a.take(_row_take(kc, nx))`` is ``np.take_along_axis(a, kc, axis=1)`` without its overhead."""
    return kc + (np.arange(kc.shape[0]) * nx)[:, None]


def _nan0(a: np.ndarray) -> np.ndarray:
    """``np.nan_to_num`` of positions (NaN or finite, never inf: NaN -> 0), without its overhead."""
    return np.where(np.isnan(a), 0.0, a)


def _clip(a, lo, hi):
    """``np.clip`` (NaN kept) without its dispatch overhead."""
    return np.minimum(np.maximum(a, lo), hi)


def _levels(gram):
    """Per line least-squares (a, c) of ``v = a + c T`` from the Gram matrix of ``(1, T, T', v)``."""
    n, st, stt, sv, stv = gram[:, 0, 0], gram[:, 0, 1], gram[:, 1, 1], gram[:, 0, 3], gram[:, 1, 3]
    var = n * stt - st * st
    c = (n * stv - st * sv) / np.where(var > 0, var, 1.0)
    return (sv - c * st) / n, c


def _rss(gram, a, c):
    """Per line ``sum (v - a - c T)^2`` from the Gram matrix of ``(1, T, T', v)`` (by expansion: to a few
    1e-16 of ``sum v^2``, enough for the acceptance tests of a pass that only places the next template)."""
    n, st, stt, sv, stv, svv = (gram[:, i, j] for i, j in ((0, 0), (0, 1), (1, 1), (0, 3), (1, 3), (3, 3)))
    rss = svv - 2.0 * (a * sv + c * stv) + a * a * n + 2.0 * a * c * st + c * c * stt
    return np.maximum(rss, 0.0)


def _normal(gram, c):
    """The normal matrices ``J^T J`` (lines, 3, 3) of the Jacobian ``(1, T, -c T')`` from the Gram matrix of
    ``(1, T, T', v)``."""
    s = np.array([1.0, 1.0, -1.0])[None, :] * np.stack([np.ones_like(c), np.ones_like(c), c], axis=1)
    return gram[:, :3, :3] * s[:, :, None] * s[:, None, :]


def _solve(gram, a, c):
    """Per line least-squares Gauss-Newton step for the residual ``r = v - a - c T`` (lines whose normal matrix
    is singular: no step): the 3 x 3 normal equations (:func:`_normal`'s entries) by Gaussian elimination
    written out, the lines as the vector axis; ``J^T r`` from the Gram matrix of ``(1, T, T', v)``, linear in
    ``r``."""
    m = -c
    a00, a01, a11 = gram[:, 0, 0], gram[:, 0, 1], gram[:, 1, 1]
    a02, a12, a22 = gram[:, 0, 2] * m, gram[:, 1, 2] * m, gram[:, 2, 2] * (m * m)
    jr = gram[:, :3, 3] - a[:, None] * gram[:, :3, 0] - c[:, None] * gram[:, :3, 1]
    b0, b1, b2 = jr[:, 0], jr[:, 1], jr[:, 2] * m
    with np.errstate(divide="ignore", invalid="ignore"):
        l10, l20 = a01 / a00, a02 / a00
        p11, p12, p22 = a11 - l10 * a01, a12 - l10 * a02, a22 - l20 * a02
        e1, e2 = b1 - l10 * b0, b2 - l20 * b0
        l21 = p12 / p11
        q22 = p22 - l21 * p12
        out = np.empty((c.size, 3))
        out[:, 2] = (e2 - l21 * e1) / q22
        out[:, 1] = (e1 - p12 * out[:, 2]) / p11
        out[:, 0] = (b0 - a01 * out[:, 1] - a02 * out[:, 2]) / a00
    # a positive pivot each (the matrix is positive semi-definite): else singular, no step
    good = (a00 > 0) & (p11 > 1e-14 * a11) & (q22 > 1e-14 * a22)
    return np.where(good[:, None], out, 0.0)


def _accept(ok, x, start, fit, half: int):
    """(x, sigma_x), NaN for the lines whose fit failed or departs from the others; ``fit = (a, c, each line's
    residual sum of squares over its 2 half + 1 pixels, normal matrices J^T J)`` (None: sigma_x not computed,
    None)."""
    a, c, rss, jtj = fit
    n_px = 2 * half + 1
    ok = ok & np.isfinite(x) & (np.abs(x - _nan0(start)) <= 0.5 * half)
    if np.count_nonzero(ok) < 3:
        return np.full(x.shape, np.nan), np.full(x.shape, np.nan)
    c_med = _median(c[ok])
    rms = np.sqrt(rss / n_px)
    ok &= np.abs(c - c_med) <= _CONTRAST_TOL * abs(c_med)
    ok &= rms <= _RMS_TOL * _median(rms[ok]) + 0.005 * abs(c_med)
    pos = np.where(ok, x, np.nan)
    if jtj is None:
        return pos, None
    n_ok = int(np.count_nonzero(ok))
    noise2 = float(np.sum(rss[ok])) / max(n_ok * (n_px - 3), 1)
    return pos, np.where(ok, np.sqrt(noise2 * _inv22(jtj, ok)), np.nan)


def _inv22(a, ok):
    """Element (2, 2) of the inverse of each 3 x 3 symmetric ``a`` (its cofactor over the determinant); the
    pseudo-inverse's for the ``ok`` lines whose matrix is near singular."""
    a00, a01, a02, a11, a12, a22 = (a[:, i, j] for i, j in ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)))
    cof = a00 * a11 - a01 * a[:, 1, 0]
    det = a00 * (a11 * a22 - a12 * a12) + a01 * (a02 * a12 - a01 * a22) + a02 * (a01 * a12 - a02 * a11)
    diag = np.abs(a00 * a11 * a22)
    with np.errstate(all="ignore"):
        out = cof / det
        weak = ok & ~(np.abs(det) > 1e-10 * diag)
        if weak.any():
            out[weak] = np.linalg.pinv(a[weak])[:, 2, 2]
    return out
