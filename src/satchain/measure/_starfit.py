"""Siemens-star fitting helpers: sub-pixel centre, angular harmonic spectrum, per-annulus harmonic fits.

Centre.  For a trial centre ``c`` every pixel of a band of radii is given its polar angle about ``c``; the
pixels are grouped in annuli (membership fixed by the starting centre, so the cost is smooth in ``c``) and in
each annulus ``a + b cos(n th) + c sin(n th)`` is fitted by least squares.  The residual sum of squares
``J(c)`` is minimised (coarse grid, then Nelder-Mead); a wrong centre mixes the n-th harmonic into its
neighbours ``n +- 1`` and raises ``J``.  This is an ordinary non-linear least-squares problem in the centre
(the linear coefficients profiled out), so its covariance is ``2 s^2 H^-1`` with ``H`` the Hessian of ``J``
and ``s^2 = J / (N - p)`` the residual variance.

Star frame.  Every helper takes ``lin``, the linear map (2x2, unit determinant) from an image pixel step
``(dcol, drow)`` to the star's own frame (a star imaged through a shear, an along-track scale or a rotation is an
ellipse in the image and a circle there): radii and polar angles are computed in that frame about a centre given
in image pixels (None: the identity, the image's own axes).  It may also be a :class:`StarFrame`, which adds
each image row's offset (a pushbroom line of sight that moves in time displaces whole rows): row ``i`` sees the
star where the mean map puts image point ``(x + du_i, y + dv_i)``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.optimize import minimize

from satchain.errors import ConfigError

__all__ = [
    "StarFrame",
    "annulus_fit",
    "coarse_center",
    "fit_center",
    "harmonic_spectrum",
    "polar",
    "star_map",
    "symmetry_center",
]


class StarFrame(NamedTuple):
    """The star's frame with per-row offsets: ``lin`` (2x2 or None) and ``du``, ``dv`` (image px, per row of
    the region measured: row ``i`` sees the mean map's point of ``(x + du[i], y + dv[i])``)."""

    lin: tuple | None
    du: np.ndarray
    dv: np.ndarray


def polar(x, y, xc: float, yc: float, lin=None) -> tuple[np.ndarray, np.ndarray]:
    """Radius and polar angle (rad, from the frame's +x towards its +y) of image pixels ``(x, y)`` (``y`` whole
    rows) about the image point ``(xc, yc)``, in the star's frame: ``lin @ (x - xc, y - yc)`` (see the module
    docstring; a :class:`StarFrame` adds each row's offset first)."""
    dx, dy = np.asarray(x, float) - xc, np.asarray(y, float) - yc
    if isinstance(lin, StarFrame):
        rows = np.rint(np.asarray(y, float)).astype(int)
        dx, dy, lin = dx + lin.du[rows], dy + lin.dv[rows], lin.lin
    if lin is not None:
        (a, b), (d, e) = lin
        dx, dy = a * dx + b * dy, d * dx + e * dy
    return np.hypot(dx, dy), np.arctan2(dy, dx)


def _band(data: np.ndarray, xc: float, yc: float, r_lo: float, r_hi: float, width: float, lin=None):
    """Pixels of the band ``r_lo <= r < r_hi`` about (xc, yc): x, y, values, annulus index, count."""
    ny, nx = data.shape
    y, x = np.mgrid[0:ny, 0:nx]
    r = polar(x, y, xc, yc, lin)[0]
    sel = (r >= r_lo) & (r < r_hi)
    k = ((r[sel] - r_lo) // width).astype(int)
    return x[sel].astype(float), y[sel].astype(float), data[sel], k, int(k.max()) + 1 if k.size else 0


def _rss(c, x, y, v, k, nk: int, n: int, lin=None) -> float:
    """Residual sum of squares of the per-annulus fits a + b cos(n th) + c sin(n th) about centre c."""
    th = polar(x, y, c[0], c[1], lin)[1]
    co, si = np.cos(n * th), np.sin(n * th)
    cols = (np.ones_like(co), co, si)
    g = np.empty((nk, 3, 3))
    rhs = np.empty((nk, 3))
    for i in range(3):
        rhs[:, i] = np.bincount(k, cols[i] * v, nk)
        for j in range(i, 3):
            g[:, i, j] = g[:, j, i] = np.bincount(k, cols[i] * cols[j], nk)
    ok = np.linalg.det(g) > 1e-9
    beta = np.linalg.solve(g[ok], rhs[ok][..., None])[..., 0]
    return float(np.sum(v * v) - np.sum(beta * rhs[ok]))


class _Cost:
    """``J(c)`` over a fixed band of pixels (a callable for the optimiser)."""

    def __init__(self, x, y, v, k, nk: int, n: int, lin=None):
        self.args = (x, y, v, k, nk, n, lin)
        self.size = v.size

    def __call__(self, c) -> float:
        return _rss(c, *self.args)


def symmetry_center(data: np.ndarray) -> tuple[float, float]:
    """Centre of point symmetry (any star, odd or even cycles): the peak of ``|d * d|`` (self-convolution of
    the mean-removed region) is at twice the centre; within the middle half of the region, parabolic
    sub-pixel.  A start for :func:`fit_center`, good to a fraction of a pixel on a star.
    """
    ny, nx = data.shape
    d = data - data.mean()
    big = (2 * ny, 2 * nx)
    conv = np.abs(np.fft.irfft2(np.fft.rfft2(d, big) ** 2, big))
    y0, y1, x0, x1 = ny // 2, ny + ny // 2 - 1, nx // 2, nx + nx // 2 - 1  # centre in the middle half
    win = conv[y0:y1, x0:x1]
    iy, ix = np.unravel_index(int(np.argmax(win)), win.shape)
    iy, ix = iy + y0, ix + x0

    def vertex(a, b, c):
        den = a - 2 * b + c
        return 0.0 if den == 0 else float(np.clip(0.5 * (a - c) / den, -0.5, 0.5))

    sy = iy + (vertex(conv[iy - 1, ix], conv[iy, ix], conv[iy + 1, ix]) if 0 < iy < big[0] - 1 else 0.0)
    sx = ix + (vertex(conv[iy, ix - 1], conv[iy, ix], conv[iy, ix + 1]) if 0 < ix < big[1] - 1 else 0.0)
    return sx / 2.0, sy / 2.0


def fit_center(
    data: np.ndarray, n: int, start_xy, r_lo: float, r_hi: float, *, search_px: float, width_px: float = 2.0, lin=None
):
    """Sub-pixel star centre near ``start_xy``: grid search within ``search_px``, then Nelder-Mead.

    Returns ``(x, y, cov)`` with ``cov`` the 2x2 covariance (px^2), or None where the Hessian is not
    positive definite (a flat cost: no star, or no information on the centre).
    """
    cx, cy = float(start_xy[0]), float(start_xy[1])
    best = (cx, cy)
    for round_ in range(2):  # second round: annulus membership about the improved centre
        x, y, v, k, nk = _band(data, best[0], best[1], r_lo, r_hi, width_px, lin)
        if nk < 2:
            return cx, cy, None
        cost = _Cost(x, y, v, k, nk, n, lin)
        if search_px > 0:
            offs = np.arange(-search_px, search_px + 1e-9, 0.5)
            grid = [(best[0] + dx, best[1] + dy) for dy in offs for dx in offs]
            best = min(grid, key=cost)
            search_px = 0.0
        b0 = np.array(best)
        simplex = np.array([b0, b0 + (0.25, 0.0), b0 + (0.0, 0.25)])
        res = minimize(
            cost, b0, method="Nelder-Mead", options={"xatol": 1e-3, "fatol": 1e-12, "initial_simplex": simplex}
        )
        moved = float(np.hypot(res.x[0] - best[0], res.x[1] - best[1]))
        best = (float(res.x[0]), float(res.x[1]))
        if round_ == 0 and moved < 0.25:  # membership barely changes: no second round needed
            break
    j0 = cost(np.array(best))
    h = 0.05
    hess = np.empty((2, 2))
    e = np.eye(2) * h
    b = np.array(best)
    for i in range(2):
        for jj in range(2):
            hess[i, jj] = (
                cost(b + e[i] + e[jj]) - cost(b + e[i] - e[jj]) - cost(b - e[i] + e[jj]) + cost(b - e[i] - e[jj])
            ) / (4 * h * h)
    s2 = j0 / max(cost.size - 3 * cost.args[4] - 2, 1)
    try:
        ev = np.linalg.eigvalsh(hess)
        cov = 2.0 * s2 * np.linalg.inv(hess) if np.all(ev > 0) else None
    except np.linalg.LinAlgError:
        cov = None
    return best[0], best[1], cov


def harmonic_spectrum(data: np.ndarray, xc: float, yc: float, r_lo: float, r_hi: float, m_max: int, lin=None):
    """Amplitude of angular harmonics m = 1..m_max in the band (annulus means removed, 2-px annuli).

    Returns (m, amplitude, noise amplitude) where the noise amplitude is the 1-sigma of one harmonic's
    amplitude estimated from the harmonics' median power (most harmonics hold noise only).
    """
    x, y, v, k, nk = _band(data, xc, yc, r_lo, r_hi, 2.0, lin)
    mean = np.bincount(k, v, nk) / np.maximum(np.bincount(k, None, nk), 1)
    d = v - mean[k]
    th = polar(x, y, xc, yc, lin)[1]
    m = np.arange(1, m_max + 1)
    amp = np.empty(m.size)
    for i0 in range(0, m.size, 64):  # blocks keep the (pixels x harmonics) matrix small
        mm = m[i0 : i0 + 64]
        amp[i0 : i0 + 64] = 2 * np.abs(np.exp(-1j * np.outer(th, mm)).T @ d) / max(d.size, 1)
    return m, amp, float(np.median(amp))


def annulus_fit(theta: np.ndarray, values: np.ndarray, n: int, shapes=()):
    """Least-squares ``a + g1 cos th + g2 sin th + (b + sum_j b_j u_j) cos(n th) + (c + sum_j c_j u_j) sin(n th)``
    (the ``g`` terms take a linear illumination gradient out of the fit and of the noise): (a, amplitude,
    amplitude sigma, residual sigma, relative gradient ``|g| / a``).  The amplitude is debiased for the noise
    (Rice: E[A^2] = A^2 + var b + var c), so pure noise gives ~0.  Its sigma is the one along the fitted phase
    (linearised; the two quadratures' variances differ when few pixels sample the wave unevenly, as in a
    sector of a star centred on the pixel lattice) when the amplitude exceeds 3 sigma, their mean otherwise.

    ``shapes`` are per-sample variables ``u_j`` along which the star's amplitude may change (e.g. the radius
    offset and its square, the angle to a sector's axis); the amplitude returned is ``|b + i c|``, the one where
    every ``u_j = 0``.  Without them the local amplitude, which changes across a band of radii and angles, is
    averaged with weights set by where the pixels fall on the wave: for a star centred on the pixel lattice
    those weights are far from uniform (see :func:`satchain.measure.star._annuli`).
    """
    cols = [np.ones_like(theta), np.cos(n * theta), np.sin(n * theta)]
    if n != 1:
        cols += [np.cos(theta), np.sin(theta)]
    for u in shapes:
        cols += [u * cols[1], u * cols[2]]
    design = np.column_stack(cols)
    beta, *_ = np.linalg.lstsq(design, values, rcond=None)
    resid = values - design @ beta
    dof = max(values.size - design.shape[1], 1)
    s = float(np.sqrt(np.sum(resid**2) / dof))
    cov = s * s * np.linalg.pinv(design.T @ design)
    c2 = cov[1:3, 1:3]
    a2 = float(beta[1] ** 2 + beta[2] ** 2)
    amp = float(np.sqrt(max(a2 - np.trace(c2), 0.0)))
    sb = float(np.sqrt(0.5 * np.trace(c2)))
    if a2 > 9 * np.trace(c2):  # clear signal: the amplitude's variance is the one along its phase
        u = beta[1:3] / np.sqrt(a2)
        sb = float(np.sqrt(max(u @ c2 @ u, 0.0)))
    grad = float(np.hypot(beta[3], beta[4]) / beta[0]) if n != 1 and beta[0] > 0 else 0.0
    return float(beta[0]), amp, sb, s, grad


def coarse_center(data: np.ndarray, n: int, start_xy, r_lo: float, r_hi: float, *, search_px: float, lin=None):
    """Centre maximising the coherent ``n``-th angular harmonic power ``|sum (v - mean) exp(-i n th)|^2`` of the
    pixels at radii ``r_lo + search_px .. r_hi - search_px`` about ``start_xy``, over a 1-px grid within
    ``search_px`` of it, then a 0.25-px grid around the best; returns ``(x, y, at_limit)`` with ``at_limit``
    True when the best lies on the grid's border (no maximum inside: the centre is farther off).

    A centre off by ``d`` turns the phase of the harmonic at radius ``r`` by up to ``n d / r``: the sum stays
    coherent only near the true centre, so the maximum finds it from a start several px off, where the
    per-annulus least squares of :func:`fit_center` (which needs a start within ~1 px) cannot.
    """
    cx, cy = float(start_xy[0]), float(start_xy[1])
    ny, nx = data.shape
    y, x = np.mgrid[0:ny, 0:nx]
    r = polar(x, y, cx, cy, lin)[0]
    lo, hi = r_lo + search_px, r_hi - search_px
    if hi - lo < 4:
        lo, hi = r_lo, r_hi
    sel = np.flatnonzero(((r >= lo) & (r < hi)).ravel())
    if sel.size > 40000:  # a regular subset keeps the search cheap on large stars
        sel = sel[:: int(np.ceil(sel.size / 40000))]
    xs, ys = x.ravel()[sel].astype(float), y.ravel()[sel].astype(float)
    v = data.ravel()[sel] - float(np.mean(data.ravel()[sel]))

    def power(c) -> float:
        return float(np.abs(np.sum(v * np.exp(-1j * n * polar(xs, ys, c[0], c[1], lin)[1]))) ** 2)

    best, at_limit = (cx, cy), False
    for step, half in ((1.0, float(np.floor(search_px))), (0.25, 1.0)):
        offs = np.arange(-half, half + 1e-9, step)
        grid = [(best[0] + dx, best[1] + dy) for dy in offs for dx in offs]
        k = int(np.argmax([power(c) for c in grid]))
        if step == 1.0:
            at_limit = bool(max(abs(grid[k][0] - cx), abs(grid[k][1] - cy)) >= half - 1e-9 and half > 0)
        best = grid[k]
    return best[0], best[1], at_limit


def star_map(image_affine, directions_deg: dict) -> tuple[tuple | None, dict, tuple[float, float]]:
    """The star frame of a star imaged through ``image_affine`` (scene metres -> image ``(col, row)``: an
    ``affine.Affine`` or ``(a, b, c, d, e, f)`` with ``col = a x + b y + c``, ``row = d x + e y + f``; its
    linear part only): ``lin``, the pixel-step -> star-frame map scaled to unit determinant (star-frame units are
    the image's mean pixel, ``sqrt |det|`` metres); per direction ``(beta, s)``: the star-frame polar angle
    ``beta`` (rad) of the tangent whose grating has its image wave vector along the direction
    (``directions_deg``: deg from +x, y downwards), and ``s``, image cy/px per star-frame cy/unit along it; the
    half-extents (px) along x and y of the image ellipse of a unit circle of the star frame.

    The wave vector of a grating ``k`` (cy per star unit) is ``lin^T k`` in the image (cy/px): along the image
    direction ``u`` it is ``k`` parallel to ``lin^-T u``, and ``|lin^T k| = |k| / |lin^-T u|``.
    ``image_affine = None``: the image's own axes (``lin`` None, ``beta`` the direction, ``s = 1``).
    """
    if image_affine is None:
        return None, {k: (float(np.deg2rad(deg)), 1.0) for k, deg in directions_deg.items()}, (1.0, 1.0)
    try:
        a, b, _, d, e, _ = (float(v) for v in tuple(image_affine)[:6])
    except (TypeError, ValueError):
        raise ConfigError(f"image_affine = {image_affine!r}: must be an affine.Affine or (a, b, c, d, e, f)") from None
    det = a * e - b * d
    if not (np.isfinite([a, b, d, e]).all() and abs(det) > 0):
        raise ConfigError(f"image_affine = {image_affine!r}: its linear part must be finite and invertible")
    to_px = np.array([[a, b], [d, e]]) / np.sqrt(abs(det))  # star-frame step -> pixel step (unit determinant)
    lin = np.linalg.inv(to_px)
    dirs = {}
    for k, deg in directions_deg.items():
        u = np.array([np.cos(np.deg2rad(deg)), np.sin(np.deg2rad(deg))])
        w = to_px.T @ u  # lin^-T u
        dirs[k] = (float(np.arctan2(w[1], w[0])), float(1.0 / np.hypot(*w)))
    extent = (float(np.hypot(*to_px[0])), float(np.hypot(*to_px[1])))
    return tuple(map(tuple, lin.tolist())), dirs, extent
