"""Slanted-edge location (used by :mod:`satchain.measure.edge`): the edge position per line from windowed
derivative centroids and a robust (Tukey bisquare) polynomial fit whose degree (1-3) is chosen from the data,
and the projection of every pixel onto the fitted edge's local normal; the region and its orientation
(:func:`edge_region`, :func:`orient_edge`), shared with :mod:`satchain.measure.jitter`."""

from __future__ import annotations

import math

import numpy as np
from scipy.ndimage import uniform_filter

from satchain.errors import InputError
from satchain.measure._common import crop_roi, fill_invalid, median, robust_sigma, valid_mask, zero_fill_mask

__all__ = ["MIN_ROWS", "curvature", "edge_region", "locate_edge", "orient_edge", "project"]

MIN_ROWS = 8
SHORT_ROWS = 20
F_DEGREE = 30.0  # F statistic a higher fit degree must beat ...
SAGITTA_PX = 0.1  # ... while moving the edge by more than this (px)


def edge_region(image, roi, valid, nodata):
    """(float64 region, its valid mask or None, flags): excluded pixels filled from their nearest valid ones;
    without ``valid`` and ``nodata``, an integer image's evident zero fill is excluded (flagged)."""
    mask, flags = valid_mask(image, valid, nodata), []
    if mask is None and valid is None and nodata is None:
        mask, note = zero_fill_mask(image)
        flags = [("nodata_fill" if mask is not None else "nodata_fill_unsure", note)] if note else []
    if mask is None:
        return crop_roi(image, roi, min_size=12), None, flags
    data = crop_roi(fill_invalid(image, mask), roi, min_size=12)
    ok = crop_roi(mask.astype(np.float64), roi, name="valid", min_size=12) > 0.5
    if np.count_nonzero(ok) < 64:
        raise InputError(f"image: the region holds {np.count_nonzero(ok)} valid pixel(s) (< 64); nothing to measure")
    return data, ok, flags


def orient_edge(data: np.ndarray, ok=None):
    """Return (work array whose rows cross the edge, its valid mask or None, direction, transposed, sign making
    the ESF rise)."""
    sm = uniform_filter(data, 3)
    gx = np.abs(np.diff(sm, axis=1)).sum()
    gy = np.abs(np.diff(sm, axis=0)).sum()
    transposed = gy > gx
    work = data.T if transposed else data
    q = max(2, work.shape[1] // 4)
    sign = 1.0 if work[:, -q:].mean() >= work[:, :q].mean() else -1.0
    okw = None if ok is None else (ok.T if transposed else ok)
    return work * sign, okw, ("ALT" if transposed else "ACT"), transposed, sign


_median = median
_robust_sigma = robust_sigma


class _Poly:
    """Weighted least-squares polynomials of degree <= 3 on fixed abscissae ``t``, by the normal equations in
    the centred, scaled variable ``s = (t - m) / h`` (in [-1, 1]: the moment matrix is well conditioned, so
    the fit equals ``np.polyfit``'s QR solution to rounding).  Coefficients are ascending in ``s``."""

    def __init__(self, t: np.ndarray, max_deg: int = 3):
        lo, hi = float(t.min()), float(t.max())
        self.m, self.h = 0.5 * (lo + hi), max(0.5 * (hi - lo), 0.5)
        s = (t - self.m) / self.h
        self.pt = np.empty((2 * max_deg + 1, s.size))  # the powers s^0 .. s^(2 deg), by repeated products
        self.pt[0] = 1.0
        if max_deg > 0:
            self.pt[1] = s
        for k in range(2, 2 * max_deg + 1):
            np.multiply(self.pt[k - 1], s, out=self.pt[k])

    def fit(self, y: np.ndarray, deg: int, w=None) -> np.ndarray:
        """Ascending coefficients in ``s`` minimising ``sum w (y - poly)^2`` (``w`` None: all 1)."""
        n1 = deg + 1
        mom = self.pt[: 2 * deg + 1].sum(axis=1) if w is None else self.pt[: 2 * deg + 1] @ w
        rhs = self.pt[:n1] @ (y if w is None else w * y)
        q = _cholesky_solve(mom.tolist(), rhs.tolist())
        if q is None:  # degenerate abscissae: the minimum-norm least squares
            sw = np.ones_like(y) if w is None else np.sqrt(w)
            return np.linalg.lstsq(self.pt[:n1].T * sw[:, None], y * sw, rcond=None)[0]
        return np.array(q)

    def nested_fits(self, y: np.ndarray) -> dict:
        """``{k: value(fit(y, k))}`` for k = 1, 2, 3 (unweighted), from one factorisation of the cubic's moment
        matrix: each lower degree's is its leading block, the same factor."""
        mom = self.pt[:7].sum(axis=1).tolist()
        lo, rows = _cholesky_rows(mom, 4)
        out = {}
        for k in (1, 2, 3):
            if k + 1 <= rows:
                q = np.array(_cholesky_back(lo, (self.pt[: k + 1] @ y).tolist(), k + 1))
            else:
                q = self.fit(y, k)
            out[k] = self.value(q)
        return out

    def value(self, q: np.ndarray) -> np.ndarray:
        """The polynomial of ascending coefficients ``q`` at the abscissae."""
        return q @ self.pt[: q.size]

    def coef(self, q: np.ndarray) -> np.ndarray:
        """``q`` as ``np.polyval`` coefficients in ``t`` (descending): ``sum_j q_j (t - m)^j / h^j`` expanded."""
        n = len(q)
        a = [0.0] * n
        for j, qj in enumerate(q.tolist()):
            qj /= self.h**j
            for i in range(j + 1):
                a[i] += qj * math.comb(j, i) * (-self.m) ** (j - i)
        return np.array(a[::-1])


def _cholesky_solve(mom: list, rhs: list):
    """Solve the Hankel system ``sum_j mom[i + j] q_j = rhs[i]`` (symmetric positive definite, n <= 4) by a
    Cholesky factorisation in plain floats (a LAPACK call costs more than the arithmetic here); None when it is
    not positive definite."""
    n = len(rhs)
    if n == 2:  # a straight line (most fits): the same steps, unrolled
        if not mom[0] > 0.0:
            return None
        l00 = math.sqrt(mom[0])
        l10 = mom[1] / l00
        v = mom[2] - l10 * l10
        if not v > 1e-13 * abs(mom[2]):
            return None
        l11 = math.sqrt(v)
        z0 = rhs[0] / l00
        z1 = (rhs[1] - l10 * z0) / l11
        q1 = z1 / l11
        return [(z0 - l10 * q1) / l00, q1]
    lo, rows = _cholesky_rows(mom, n)
    return _cholesky_back(lo, rhs, n) if rows == n else None


def _cholesky_rows(mom: list, n: int):
    """The Cholesky factor (lists) of the Hankel matrix ``mom[i + j]``, row by row, and how many leading rows
    are positive definite (the factor of a leading block is the leading block of the factor)."""
    lo = [[0.0] * n for _ in range(n)]
    for i in range(n):
        for j in range(i + 1):
            v = mom[i + j] - sum(lo[i][k] * lo[j][k] for k in range(j))
            if i == j:
                if not v > 1e-13 * abs(mom[2 * i]):
                    return lo, i
                lo[i][i] = math.sqrt(v)
            else:
                lo[i][j] = v / lo[j][j]
    return lo, n


def _cholesky_back(lo: list, rhs: list, n: int) -> list:
    """Solve with the leading ``n`` rows of the factor ``lo`` (forward, then back substitution)."""
    z = [0.0] * n
    for i in range(n):
        z[i] = (rhs[i] - sum(lo[i][k] * z[k] for k in range(i))) / lo[i][i]
    q = [0.0] * n
    for i in reversed(range(n)):
        q[i] = (z[i] - sum(lo[k][i] * q[k] for k in range(i + 1, n))) / lo[i][i]
    return q


_IRLS_TOL_PX = 1e-6  # robust_polyfit stops when the fit moves by less (px)
_FIRST_TOL_PX = 1e-3  # ... for the first line through the whole-pixel peaks (only where to search)


def robust_polyfit(
    t, y, deg: int, scale_floor: float = 0.05, tol: float = _IRLS_TOL_PX
) -> tuple[np.ndarray, np.ndarray]:
    """Polynomial fit with Tukey-bisquare iteratively reweighted least squares; returns (coef, weights).

    Up to 10 reweightings; it stops once the fit moves by < ``tol`` (1e-6 px): the reweighting converges
    linearly (each move ~0.1-0.15 x the last), so the moves left add up to ~1e-7 px."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    w = np.ones_like(y)
    poly = _Poly(t, deg)
    q = poly.fit(y, deg)
    fit = poly.value(q)
    for _ in range(10):
        r = y - fit
        s = max(_robust_sigma(r), scale_floor)
        u = r / (4.685 * s)
        w = 1.0 - u * u  # (1 - u^2)^2 where |u| < 1 (exactly where u * u < 1), else 0
        np.fmax(w, 0.0, out=w)  # (NaN -> 0 as well)
        w *= w
        if np.count_nonzero(w) <= deg + 2:
            raise InputError("image: no straight edge found (edge positions do not line up)")
        q = poly.fit(y, deg, w)
        new = poly.value(q)
        moved = float(np.abs(new - fit).max())
        fit = new
        if moved < tol:
            break
    return poly.coef(q), w


def pick_degree(t, y, w):
    """Degree 1-3 for the edge positions: a higher one must beat F > 30 and move the edge by > 0.1 px."""
    use = w > 0
    t, y = t[use], y[use]
    poly = _Poly(t)
    best = 1
    fits = poly.nested_fits(y)
    rss = {k: float(np.sum((y - fits[k]) ** 2)) for k in (1, 2, 3)}
    for k in (2, 3):
        dof = t.size - k - 1
        if dof < 4:
            break
        f_stat = (rss[best] - rss[k]) / max(rss[k] / dof, 1e-30)
        move = float(np.max(np.abs(fits[k] - fits[best])))
        if f_stat > F_DEGREE and move > SAGITTA_PX:
            best = k
    return best


def ridge_centroids(work, g, coef, half, valid=None):
    """Windowed derivative centroids along the fitted ridge; returns (rows used, centroids, per-row steps)."""
    ny, nx = work.shape
    rows = np.arange(ny, dtype=float)
    centre = np.polyval(coef, rows)
    keep = (centre - half >= 1) & (centre + half <= nx - 2)
    if valid is not None:  # lines whose window (and its derivative's reach) touches an excluded pixel: unused
        lo = np.clip(np.floor(centre - half).astype(int) - 1, 0, nx - 1)
        hi = np.clip(np.ceil(centre + half).astype(int) + 1, 0, nx - 1)
        cbad = np.concatenate([np.zeros((ny, 1), int), np.cumsum(~valid, axis=1)], axis=1)
        keep &= (cbad[np.arange(ny), hi + 1] - cbad[np.arange(ny), lo]) == 0  # no excluded pixel in lo..hi
    if np.count_nonzero(keep) < MIN_ROWS:
        raise InputError(
            f"image: the edge crosses fewer than {MIN_ROWS} lines inside the region "
            f"(found {int(np.count_nonzero(keep))}); use a longer edge or a larger ROI"
        )
    # the window |column - centre| <= half of each kept line: 2 half or 2 half + 1 columns from ceil(centre - half)
    rk, ck = rows[keep], centre[keep]
    kb = np.ceil(ck - half)[:, None] + np.arange(2 * half + 1)[None, :]
    gb = g.take((rk * nx)[:, None].astype(np.intp) + kb.astype(np.intp))
    gw = np.where(kb <= ck[:, None] + half, gb, 0.0)
    tot = gw.sum(axis=1)
    good = tot > 0
    if np.count_nonzero(good) < MIN_ROWS:
        raise InputError("image: no edge found (the derivative has no consistent ridge)")
    cen = (gw * kb).sum(axis=1)[good] / tot[good]
    return rk[good], cen, tot[good], int(np.count_nonzero(keep))


def _window_bounds(coef, rows: np.ndarray, half: int) -> np.ndarray:
    """What :func:`ridge_centroids`' windows (and the lines it keeps) depend on: ``floor`` and ``ceil`` of each
    line's ``centre -+ half``; equal bounds give equal centroids."""
    centre = np.polyval(coef, rows)
    lo, hi = centre - half, centre + half
    return np.stack([np.floor(lo), np.ceil(lo), np.floor(hi), np.ceil(hi)])


def locate_edge(work: np.ndarray, deg: int | None, valid=None):
    """Edge position per row: windowed centroid of the derivative + robust polynomial fit, iterated.

    ``deg`` None chooses the degree from the positions (:func:`pick_degree`).  Refuses regions where the
    positions of many lines do not line up or their steps differ (a corner, a second edge); returns
    (coef, rows used, flags, (rows used, their edge positions)).  Lines whose edge window touches a pixel
    outside ``valid`` are not used.
    """
    ny, nx = work.shape
    g = np.zeros_like(work)
    g[:, 1:-1] = 0.5 * (work[:, 2:] - work[:, :-2])
    if valid is not None:
        g[:, 1:-1] *= valid[:, 2:] & valid[:, :-2]
    gs = uniform_filter(g, size=(min(5, ny), 3), mode="nearest")
    rows = np.arange(ny, dtype=float)
    seen = np.ones(ny, dtype=bool) if valid is None else np.any(gs != 0, axis=1)
    if np.count_nonzero(seen) < MIN_ROWS:
        raise InputError(f"image: fewer than {MIN_ROWS} lines hold valid pixels across the edge")
    # where to look first (the derivative's whole-pixel peaks): the windows it places are iterated below
    peaks = np.argmax(gs, axis=1)[seen].astype(float)
    coef, _ = robust_polyfit(rows[seen], peaks, 1, scale_floor=1.0, tol=_FIRST_TOL_PX)
    half = max(4, min(12, nx // 6))
    cur = deg or 1
    last: int | None = None
    r_prev = cen_prev = bounds = np.empty(0)  # compared only once ``last`` is set (from the second pass on)
    for it in range(4):
        if cur > 1 and len(coef) < cur + 1:
            coef = np.concatenate([np.zeros(cur + 1 - len(coef)), coef])
        new_bounds = _window_bounds(coef, rows, half)
        if cur == last and np.array_equal(new_bounds, bounds):
            break  # the same windows: the same centroids again, and the fit (deterministic) would repeat exactly
        bounds = new_bounds
        r_used, cen, step, n_keep = ridge_centroids(work, g, coef, half, valid)
        if cur == last and np.array_equal(r_used, r_prev) and np.array_equal(cen, cen_prev):
            break  # the same centroids again: the fit (deterministic) would repeat exactly
        r_prev, cen_prev = r_used, cen
        prev, coef, w = coef, *robust_polyfit(r_used, cen, cur)
        last = cur
        if deg is None and it < 3:
            cur = pick_degree(r_used, cen, w)
        if cur == last and prev.shape == coef.shape and np.array_equal(prev, coef):
            break  # the same fit again: further passes repeat it exactly
    inl = w > 0
    med = median(step[inl])
    odd = inl & (np.abs(step - med) > 0.3 * abs(med))
    bad = (n_keep - np.count_nonzero(inl)) + np.count_nonzero(odd)
    if bad > 0.2 * n_keep:
        raise InputError(
            f"image: no edge found along {bad} of {n_keep} lines (their edge positions or steps do not match "
            "one straight edge: no edge, a corner or a second edge); give an ROI around one straight edge"
        )
    good = inl & ~odd
    used = r_used[good].astype(int)
    flags = []
    if used.size < SHORT_ROWS:
        flags.append(
            ("short_edge", f"short edge: {used.size} lines (< {SHORT_ROWS}); MTF noise and angle error are large")
        )
    if len(coef) > 2:
        k = curvature(coef, used)
        flags.append(
            (
                "curved_edge",
                f"curved edge: radius about {1 / max(abs(k), 1e-12):.0f} px; positions fitted with a degree-"
                f"{len(coef) - 1} polynomial",
            )
        )
    return coef, used, flags, (r_used[good], cen[good])


def curvature(coef, rows) -> float:
    """Curvature (1/px) of x(r) = polyval(coef, r) at the middle row."""
    if len(coef) < 3:
        return 0.0
    r = float(np.mean(rows))
    d1 = np.polyval(np.polyder(coef), r)
    d2 = np.polyval(np.polyder(coef, 2), r)
    return float(d2 / (1 + d1 * d1) ** 1.5)


def project(work: np.ndarray, rows: np.ndarray, coef, shift=None):
    """Signed distance of every pixel centre to the fitted edge along its local normal; ``shift`` (px along the
    row, one per row of ``rows``) moves each row's edge from the polynomial (:mod:`satchain.measure.edge._align`).

    Returns (distances, values, slope at the middle row, each row's sub-pixel phase frac(-x_e))."""
    nx = work.shape[1]
    xe = np.polyval(coef, rows.astype(float))
    if shift is not None:
        xe = xe + shift
    slope_r = np.polyval(np.polyder(coef), rows.astype(float)) if len(coef) > 1 else np.zeros(rows.size)
    cos_t = 1.0 / np.sqrt(1.0 + slope_r**2)
    d = (np.arange(nx)[None, :] - xe[:, None]) * cos_t[:, None]
    slope = float(np.polyval(np.polyder(coef), rows.mean())) if len(coef) > 1 else 0.0
    return d.ravel(), work.ravel(), slope, np.mod(-xe, 1.0)
