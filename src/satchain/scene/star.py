"""Pixel-area averages of a sinusoidal Siemens star, ``sin(cycles * theta)`` over an annulus.

The star is a smooth field of the polar angle, so it cannot be drawn as coverage of a polygon. Its pixel
average is reduced exactly to one-dimensional integrals over the pixel's four edges: fanning the pixel
from the star centre ``O`` into signed triangles ``(O, A, B)``, the area element of the fan is
``cross(A, B) / 2 dt`` along ``P(t) = A + t (B - A)``, and the part of each ray inside the annulus
``r_in <= r <= R`` is the fraction ``c(r) = (clip(r, r_in, R)^2 - r_in^2) / r^2`` of the ray's
triangle. Hence (Green's theorem in polar form)::

    integral_{pixel & annulus} sin(k theta) dA
        = sum_edges cross(A, B) / 2 * integral_0^1 sin(k theta(t)) c(|P(t)|) dt

A pixel wholly inside the annulus needs no ``c``: its edges' ``r_in^2 / r^2`` parts add up to
``r_in^2 / 2`` times the integral of the exact differential ``sin(k theta) d theta`` around the pixel, zero.
Its edge terms are ``cross(A, B) / 2 * integral_0^1 sin(k theta(t)) dt``, by Gauss-Legendre: 4 points per
panel, panels short enough that the phase ``k theta`` moves by at most 0.5 rad per panel (it moves by at most
``k ds / d``, ``d`` the edge's distance from O; the panels are sized as if ``k`` were at least 4, so that
``theta(t)`` itself, whose singularity lies at the distance ``d`` from the edge, is resolved too), or one
3-point panel where it moves by at most 0.1 rad, or one 2-point panel up to 0.004 rad (every rule below ~1e-12
of the edge integral). The pixels are taken in blocks:
a block wholly inside ``r_in`` or outside ``R`` is zero, one wholly inside the annulus is done as above with
the rule its nearest point needs. In a block that meets a circle every edge is classified: one inside
``r_in`` is zero, one outside ``R`` is ``(R^2 - r_in^2) / (2k) (cos k theta_A - cos k theta_B)``, one inside
the annulus is its Gauss-Legendre term plus ``r_in^2 / (2k) (cos k theta_B - cos k theta_A)``, and one that
crosses ``r_in`` or ``R`` (where ``c`` has kinks) is split there and its pieces integrated with composite
4-point Gauss-Legendre of ``sin(k theta) c`` (panels of at most 0.5 rad as above). The relative error of every
edge term is below ~1e-9; the edge terms are ~``r / p`` times a pixel's area, so pixel averages are accurate
to ~``1e-9 r / p`` (below 1e-6 for stars up to ~1000 pixels in radius).
Inside ``r_in`` the star is uniform (its mean): a real star's centre cannot be printed either, and
``r_in`` must be > 0.

Examples
--------
>>> s = sine_star_average((0, 0, 40, 40), pixel_m=0.5, center_m=(10.0, 10.0), cycles=8,
...                       inner_radius_m=1.0, radius_m=9.0)
>>> abs(float(s.sum())) < 1e-9   # a whole number of cycles over the full annulus averages to zero
True
"""

from __future__ import annotations

import math

import numpy as np

from satchain._validate import check_positive
from satchain.scene.shapes import Window, check_window

__all__ = ["sine_star_average"]

_GL_X, _GL_W = np.polynomial.legendre.leggauss(4)
_GL_X = (_GL_X + 1.0) / 2.0
_GL_W = _GL_W / 2.0
_MAX_PHASE_PER_PANEL = 0.5
#: panels are sized as if k were at least this: theta(t) itself must be resolved near the centre
_K_MIN = 4


def _roots(ax, ay, dx, dy, r):
    """Parameters t in (0, 1) where |A + t D| = r; 1.0 where there is none."""
    dd = dx * dx + dy * dy
    ad = ax * dx + ay * dy
    disc = ad * ad - dd * (ax * ax + ay * ay - r * r)
    sq = np.sqrt(np.maximum(disc, 0.0))
    out = []
    for t in ((-ad - sq) / dd, (-ad + sq) / dd):
        out.append(np.where((disc > 0) & (t > 0) & (t < 1), t, 1.0))
    return out


def _piece_integrals(ax, ay, dx, dy, t, k, r_in, r_out, panels):
    """Sum over pieces [t_i, t_i+1] of integral sin(k theta) c(|P|) dt, composite Gauss-Legendre."""
    ta, length = t[:, :-1, None, None], np.diff(t, axis=-1)[:, :, None, None]
    tt = ta + length * ((np.arange(panels)[:, None] + _GL_X[None, :]) / panels)
    px = ax[:, None, None, None] + tt * dx[:, None, None, None]
    py = ay[:, None, None, None] + tt * dy[:, None, None, None]
    r2 = px * px + py * py
    with np.errstate(invalid="ignore", divide="ignore"):
        c = np.where(r2 > 0, (np.clip(r2, r_in * r_in, r_out * r_out) - r_in * r_in) / r2, 0.0)
    f = np.sin(k * np.arctan2(py, px)) * c
    return np.sum((f @ _GL_W).sum(axis=-1) * np.diff(t, axis=-1), axis=-1) / panels


def _edge_integrals(ax, ay, bx, by, k: int, r_in: float, r_out: float):
    """``cross(A, B) / 2 * integral_0^1 sin(k theta) c(|P|) dt`` for flat arrays of directed edges.

    Edges are grouped by the number of panels their phase needs (``k * length / max(r_in, distance
    of the segment from O)`` radians, at most 0.5 per panel) and by whether they cross a circle.
    """
    dx, dy = bx - ax, by - ay
    roots = np.stack([*_roots(ax, ay, dx, dy, r_in), *_roots(ax, ay, dx, dy, r_out)], axis=-1)
    crosses = np.any(roots < 1.0, axis=-1)
    dd = dx * dx + dy * dy
    tc = np.clip(-(ax * dx + ay * dy) / dd, 0.0, 1.0)
    dist = np.hypot(ax + tc * dx, ay + tc * dy)
    phase = max(k, _K_MIN) * np.sqrt(dd) / np.maximum(dist, r_in)
    panels = np.maximum(1, np.ceil(phase / _MAX_PHASE_PER_PANEL)).astype(np.int64)
    out = np.zeros(ax.shape)
    for crossing in (False, True):
        for n in np.unique(panels[crosses == crossing]):
            sel = np.flatnonzero((crosses == crossing) & (panels == n))
            if crossing:
                t = np.sort(np.concatenate([np.zeros((sel.size, 1)), roots[sel], np.ones((sel.size, 1))], 1), 1)
            else:
                t = np.tile([0.0, 1.0], (sel.size, 1))
            out[sel] = _piece_integrals(ax[sel], ay[sel], dx[sel], dy[sel], t, k, r_in, r_out, int(n))
    return 0.5 * (ax * by - ay * bx) * out


def sine_star_average(
    window: Window,
    *,
    pixel_m: float,
    center_m: tuple[float, float],
    cycles: int,
    inner_radius_m: float,
    radius_m: float,
) -> np.ndarray:
    """Per-pixel ``(1 / p^2) integral_{pixel & annulus} sin(cycles * theta) dA``.

    ``theta = atan2(y - cy, x - cx)`` in scene coordinates (x right/ACT, y down/ALT, so theta turns
    clockwise on screen); the annulus is ``inner_radius_m <= r <= radius_m``.

    Returns
    -------
    ndarray, float64, shape (height, width) of ``window``.
    """
    row0, col0, h, w = check_window(window)
    p = check_positive("pixel_m", pixel_m)
    r_in = check_positive("inner_radius_m", inner_radius_m)
    r_out = check_positive("radius_m", radius_m)
    star = _Star(int(cycles), r_in, r_out, p)
    xs = (col0 + np.arange(w + 1)) * p - center_m[0]
    ys = (row0 + np.arange(h + 1)) * p - center_m[1]
    out = np.empty((h, w))
    for r0 in range(0, h, _BLOCK[0]):
        r1 = min(h, r0 + _BLOCK[0])
        for c0 in range(0, w, _BLOCK[1]):
            c1 = min(w, c0 + _BLOCK[1])
            out[r0:r1, c0:c1] = star.block(xs[c0 : c1 + 1], ys[r0 : r1 + 1])
    return out / (p * p)


def _span_sq(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least and greatest ``u^2`` for ``u`` between ``a`` and ``b`` (elementwise, ``a < b``)."""
    a2, b2 = a * a, b * b
    return np.where((a < 0) & (b > 0), 0.0, np.minimum(a2, b2)), np.maximum(a2, b2)


class _Star:
    """Edge terms of one star on axis-aligned pixel edges of length ``p``."""

    def __init__(self, k: int, r_in: float, r_out: float, p: float) -> None:
        self.k, self.r_in, self.r_out, self.p = k, r_in, r_out, p

    def block(self, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
        """``p^2`` times the pixel averages of the pixels between the corner coordinates ``xs`` and ``ys``."""
        k, p = self.k, self.p
        ri2, ro2 = self.r_in**2, self.r_out**2
        x_lo, x_hi = _span_sq(xs[:1], xs[-1:])
        y_lo, y_hi = _span_sq(ys[:1], ys[-1:])
        lo2, hi2 = float(x_lo[0] + y_lo[0]), float(x_hi[0] + y_hi[0])
        if hi2 <= ri2 or lo2 >= ro2:  # wholly inside r_in or outside R
            return np.zeros((ys.size - 1, xs.size - 1))
        if lo2 >= ri2 and hi2 <= ro2:  # wholly inside the annulus: no c, no r_in term
            rule, panels = _rule(max(k, _K_MIN) * p / np.sqrt(lo2))
            gh = _gauss_sin(ys[:, None], xs[None, :-1], k, p, rule, panels, horizontal=True)
            gv = _gauss_sin(xs[None, :], ys[:-1, None], k, p, rule, panels, horizontal=False)
            hint, vint = (-0.5 * p) * ys[:, None] * gh, (0.5 * p) * xs[None, :] * gv
        else:
            hint, vint = self._mixed(xs, ys)
        # counter-clockwise in (x right, y down): top, right, -bottom, -left
        return hint[:-1] + vint[:, 1:] - hint[1:] - vint[:, :-1]

    def _mixed(self, xs: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Horizontal and vertical edge terms of a block that meets a circle, each edge classified."""
        k, w = self.k, xs.size - 1
        cos_k = np.cos(k * np.arctan2(ys[:, None], xs[None, :]))  # cos(k theta) at every corner
        hx_lo, hx_hi = _span_sq(xs[:-1], xs[1:])
        y_lo, y_hi = _span_sq(ys[:-1], ys[1:])
        # horizontal edges, left -> right: (ys.size) x w; cross(A, B) = -y p
        hint = self.edges(
            np.broadcast_to(ys[:, None], (ys.size, w)),
            np.broadcast_to(xs[None, :-1], (ys.size, w)),
            (ys * ys)[:, None] + hx_lo[None, :],
            (ys * ys)[:, None] + hx_hi[None, :],
            cos_k[:, :-1],
            cos_k[:, 1:],
            horizontal=True,
        )
        # vertical edges, top -> bottom: (ys.size - 1) x (w + 1); cross(A, B) = x p
        shape = (ys.size - 1, w + 1)
        vint = self.edges(
            np.broadcast_to(xs[None, :], shape),
            np.broadcast_to(ys[:-1, None], shape),
            y_lo[:, None] + (xs * xs)[None, :],
            y_hi[:, None] + (xs * xs)[None, :],
            cos_k[:-1, :],
            cos_k[1:, :],
            horizontal=False,
        )
        return hint, vint

    def edges(self, const, start, lo2, hi2, cos_a, cos_b, *, horizontal: bool) -> np.ndarray:
        """Edge terms for edges on the lines ``y = const`` (``horizontal``; x from ``start`` to ``start + p``)
        or ``x = const`` (y from ``start`` to ``start + p``); ``lo2``/``hi2``: least/greatest r^2 on each edge,
        ``cos_a``/``cos_b``: ``cos(k theta)`` at its ends."""
        k, r_in, r_out, p = self.k, self.r_in, self.r_out, self.p
        ri2, ro2 = r_in * r_in, r_out * r_out
        dcos = cos_a - cos_b
        out = np.where(lo2 >= ro2, (ro2 - ri2) / (2 * k) * dcos, 0.0)  # outside R (inside r_in: 0)
        inside = (lo2 >= ri2) & (hi2 <= ro2)
        crossing = ~inside & (lo2 < ro2) & (hi2 > ri2)
        sel = np.nonzero(inside)
        if sel[0].size:
            c, a = const[sel], start[sel]
            phase = max(k, _K_MIN) * p / np.sqrt(lo2[sel])
            g = np.empty(c.size)
            for rule, panels, chosen in _rules(phase):
                g[chosen] = _gauss_sin(c[chosen], a[chosen], k, p, rule, panels, horizontal=horizontal)
            cross = -c * p if horizontal else c * p
            out[sel] = 0.5 * cross * g - ri2 / (2 * k) * dcos[sel]
        sel = np.nonzero(crossing)
        if sel[0].size:
            c, a = const[sel], start[sel]
            if horizontal:
                out[sel] = _edge_integrals(a, c, a + p, c, k, r_in, r_out)
            else:
                out[sel] = _edge_integrals(c, a, c, a + p, k, r_in, r_out)
        return out


_GL = {n: ((x + 1.0) / 2.0, w / 2.0) for n, (x, w) in ((n, np.polynomial.legendre.leggauss(n)) for n in (2, 3, 4))}
#: (points, largest phase change across the edge in rad) for one-panel rules below 4 points (~1e-10 of the edge)
_SHORT_RULES = ((2, 0.004), (3, 0.1))
#: pixels per block (rows, columns): a block wholly inside or outside a circle skips the per-edge classification
_BLOCK = (32, 64)


def _rule(phase: float) -> tuple[tuple[np.ndarray, np.ndarray], int]:
    """The Gauss-Legendre rule and panel count for edges whose phase moves by at most ``phase`` rad."""
    for n, limit in _SHORT_RULES:
        if phase <= limit:
            return _GL[n], 1
    return _GL[4], max(1, math.ceil(phase / _MAX_PHASE_PER_PANEL))


def _rules(phase: np.ndarray):
    """``(rule, panels, indices)``: the Gauss-Legendre rule and number of panels for each group of edges."""
    done = np.zeros(phase.shape, bool)
    for n, limit in _SHORT_RULES:
        chosen = ~done & (phase <= limit)
        done |= chosen
        if chosen.any():
            yield _GL[n], 1, np.flatnonzero(chosen)
    panels = np.maximum(1, np.ceil(phase / _MAX_PHASE_PER_PANEL)).astype(np.int64)
    for n in np.unique(panels[~done]):
        yield _GL[4], int(n), np.flatnonzero(~done & (panels == n))


def _gauss_sin(const, start, k: int, p: float, rule, panels: int, *, horizontal: bool) -> np.ndarray:
    """``integral_0^1 sin(k theta) dt`` along edges of length ``p`` (see :meth:`_Star.edges`), composite
    Gauss-Legendre ``rule`` on ``panels`` equal panels."""
    nodes, weights = rule
    t = ((np.arange(panels)[:, None] + nodes[None, :]) / panels).ravel()
    w = np.tile(weights, panels) / panels
    along, c = start[..., None] + p * t, const[..., None]
    ang = np.arctan2(c, along) if horizontal else np.arctan2(along, c)
    ang *= k
    return np.sin(ang, out=ang) @ w
