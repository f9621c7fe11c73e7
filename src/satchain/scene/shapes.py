"""Exact area-coverage rasterisation of shapes defined in ground metres.

Coordinate convention (used by the whole of :mod:`satchain.scene`)
-------------------------------------------------------------------
* The scene origin ``(x, y) = (0, 0)`` is the **top-left corner of pixel [0, 0]**.
* ``x`` (metres) is across-track (ACT) and increases to the right, along the columns.
* ``y`` (metres) is along-track (ALT) and increases **downwards**, along the rows.
* At pixel size ``p`` the pixel ``[i, j]`` covers ``x in [j p, (j + 1) p)``, ``y in [i p, (i + 1) p)``.
* A *window* is ``(row0, col0, height, width)`` in pixels at that pixel size.

Because ``y`` points down, an angle measured from ``+x`` towards ``+y`` turns clockwise on screen.

Polygon coverage is exact (up to floating point): by Green's theorem the area of a polygon inside the
pixel box ``[x0, x1] x [y0, y1]`` is the signed sum, over the polygon's edges, of
``integral (clamp(y_e(x), y0, y1) - y0) dx`` over the part of the edge above the pixel's column. For a
straight edge the integrand is a clipped linear ramp whose integral is closed form, so every pixel's
value is the exact covered fraction, and it depends only on the pixel's own footprint (a window renders
identically to the same crop of a full render). The cost of one polygon is proportional to the number
of pixels its edges cross plus one cumulative sum over its bounding box, not to the window size.

Curved outlines (discs, hyperbolas) are replaced by polygons whose outline deviates from the curve by
at most ``tol_px * pixel_m``; a pixel's coverage error is then at most ``L * tol_px / pixel_m`` where
``L`` is the length of outline inside the pixel (``L <= ~1.5 pixel_m`` for the smooth curves used
here), so the default ``tol_px = 1e-4`` gives errors below ``2e-4``, inside the 1e-3 requirement.

Examples
--------
>>> cov = polygon_coverage([[0.5, 0.5], [2.5, 0.5], [2.5, 1.5], [0.5, 1.5]], (0, 0, 2, 3), pixel_m=1.0)
>>> cov.tolist()
[[0.25, 0.5, 0.25], [0.25, 0.5, 0.25]]
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from satchain._validate import as_float_array, check_positive
from satchain.errors import ConfigError, InputError

__all__ = [
    "Window",
    "bbox_of",
    "check_window",
    "disc_vertices",
    "hyperbola_vertices",
    "paint_polygon",
    "place",
    "polygon_area",
    "polygon_coverage",
    "rectangle",
    "rings_coverage",
    "sub_window",
]

Window = tuple[int, int, int, int]

#: default outline tolerance of curved shapes, in render pixels
DEFAULT_TOL_PX = 1e-4


def check_window(window, name: str = "window") -> Window:
    """Validate ``(row0, col0, height, width)``: integers, height and width >= 1.

    Examples
    --------
    >>> check_window((0, 5, 10, 20))
    (0, 5, 10, 20)
    """
    try:
        vals = tuple(window)
    except TypeError:
        raise ConfigError(f"{name} = {window!r}: must be (row0, col0, height, width)") from None
    if len(vals) != 4:
        raise ConfigError(f"{name} = {window!r}: must have 4 entries (row0, col0, height, width)")
    out = []
    for v in vals:
        if isinstance(v, bool) or not float(v).is_integer():
            raise ConfigError(f"{name} = {window!r}: entries must be integers")
        out.append(int(v))
    if out[2] < 1 or out[3] < 1:
        raise ConfigError(f"{name} = {window!r}: height and width must be >= 1")
    return tuple(out)  # type: ignore[return-value]


def bbox_of(vertices_m) -> tuple[float, float, float, float]:
    """``(xmin, ymin, xmax, ymax)`` of an ``(N, 2)`` vertex array (metres)."""
    v = np.asarray(vertices_m, dtype=float)
    return (float(v[:, 0].min()), float(v[:, 1].min()), float(v[:, 0].max()), float(v[:, 1].max()))


def sub_window(bbox_m, window: Window, pixel_m: float) -> Window | None:
    """Part of ``window`` (absolute pixel indices) that can be touched by ``bbox_m``, or None.

    A one-pixel margin absorbs rounding; pixels in it get exactly zero coverage.

    Examples
    --------
    >>> sub_window((1.2, 0.0, 2.5, 0.9), (0, 0, 10, 10), 1.0)
    (0, 0, 2, 4)
    """
    row0, col0, h, w = window
    xmin, ymin, xmax, ymax = bbox_m
    c_lo = max(col0, math.floor(xmin / pixel_m) - 1)
    c_hi = min(col0 + w, math.ceil(xmax / pixel_m) + 1)
    r_lo = max(row0, math.floor(ymin / pixel_m) - 1)
    r_hi = min(row0 + h, math.ceil(ymax / pixel_m) + 1)
    if c_hi <= c_lo or r_hi <= r_lo:
        return None
    return (r_lo, c_lo, r_hi - r_lo, c_hi - c_lo)


def polygon_area(vertices_m) -> float:
    """Unsigned area of a simple polygon (shoelace formula), m^2.

    Examples
    --------
    >>> polygon_area([[0, 0], [2, 0], [2, 3], [0, 3]])
    6.0
    """
    v = np.asarray(vertices_m, dtype=float)
    x, y = v[:, 0], v[:, 1]
    return float(abs(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)) / 2.0)


def _ramp_integral(ta, tb, width):
    """Exact ``integral max(t, 0)`` over an interval of ``width`` where ``t`` is linear from ta to tb."""
    pa, pb = ta > 0, tb > 0
    both = width * (ta + tb) * 0.5
    pos = np.where(pa, ta, tb)
    neg = np.where(pa, tb, ta)
    with np.errstate(divide="ignore", invalid="ignore"):
        one = width * pos * pos / (pos - neg) * 0.5
    return np.where(pa & pb, both, np.where(pa ^ pb, one, 0.0))


def _expand(starts, counts):
    """Ragged expansion: owner index and value ``start + k`` for k < count of each owner."""
    counts = np.maximum(counts, 0)
    owner = np.repeat(np.arange(counts.size), counts)
    first = np.cumsum(counts) - counts
    return owner, starts[owner] + (np.arange(owner.size) - first[owner])


def _ring_edges(rings, p: float, r0: int, c0: int):
    """Directed edges (ua, va, ub, vb) in window pixel units, each ring oriented so -(loop y dx) > 0."""
    parts = []
    for ring in rings:
        u, v = ring[:, 0] / p - c0, ring[:, 1] / p - r0
        if -np.sum((np.roll(u, -1) - u) * (np.roll(v, -1) + v)) < 0:
            u, v = u[::-1], v[::-1]
        parts.append((u, v, np.roll(u, -1), np.roll(v, -1)))
    return (np.concatenate(a) for a in zip(*parts, strict=True))


def rings_coverage(rings, window: Window, pixel_m: float) -> np.ndarray:
    """Summed exact coverage of disjoint polygon rings (metres) on every pixel of ``window`` (no checks)."""
    p = pixel_m
    r0, c0, h, w = window
    ua, va, ub, vb = _ring_edges(rings, p, r0, c0)
    du = ub - ua
    sgn = -np.sign(du)
    swap = du < 0
    ul, vl = np.where(swap, ub, ua), np.where(swap, vb, va)
    ur, vr = np.where(swap, ua, ub), np.where(swap, va, vb)
    xl, xr = np.maximum(ul, 0.0), np.minimum(ur, float(w))
    keep = (du != 0) & (xr > xl)
    ul, vl, ur, vr, xl, xr, sgn = (a[keep] for a in (ul, vl, ur, vr, xl, xr, sgn))
    slope = (vr - vl) / (ur - ul)
    jlo = np.clip(np.floor(xl).astype(np.int64), 0, w - 1)
    jhi = np.clip(np.ceil(xr).astype(np.int64) - 1, 0, w - 1)
    e, j = _expand(jlo, jhi - jlo + 1)
    cxl, cxr = np.maximum(xl[e], j), np.minimum(xr[e], j + 1.0)
    dx = np.maximum(cxr - cxl, 0.0)
    cvl = vl[e] + slope[e] * (cxl - ul[e])
    cvr = vl[e] + slope[e] * (cxr - ul[e])
    s = sgn[e]
    vmin, vmax = np.minimum(cvl, cvr), np.maximum(cvl, cvr)
    ia = np.clip(np.floor(vmin), -1, h).astype(np.int64)
    ib = np.clip(np.floor(vmax), -1, h).astype(np.int64)
    # rows strictly above the edge in this column are covered over dx: a run from row 0 to row ia
    fill_to = np.clip(ia, 0, h)
    delta = np.zeros((h + 1) * w)
    delta += np.bincount(j, weights=s * dx, minlength=(h + 1) * w)
    delta -= np.bincount(fill_to * w + j, weights=s * dx, minlength=(h + 1) * w)
    cov = np.cumsum(delta.reshape(h + 1, w), axis=0)[:h]
    r_lo, r_hi = np.clip(ia, 0, h), np.clip(ib, -1, h - 1)
    c, i = _expand(r_lo, r_hi - r_lo + 1)
    k0 = _ramp_integral(cvl[c] - i, cvr[c] - i, dx[c])
    k1 = _ramp_integral(cvl[c] - i - 1, cvr[c] - i - 1, dx[c])
    cov += np.bincount(i * w + j[c], weights=s[c] * (k0 - k1), minlength=h * w).reshape(h, w)
    return cov


def polygon_coverage(vertices_m, window, *, pixel_m: float) -> np.ndarray:
    """Exact fraction of each pixel of ``window`` covered by a simple polygon.

    Parameters
    ----------
    vertices_m : array_like, shape (N, 2)
        Vertices ``(x, y)`` in scene metres (either orientation; the ring closes itself).
    window : (row0, col0, height, width)
        Pixels to render at ``pixel_m``.
    pixel_m : float
        Render pixel size (m).

    Returns
    -------
    ndarray, float64, shape (height, width), values in [0, 1].

    Examples
    --------
    >>> tri = [[0, 0], [4, 0], [0, 4]]
    >>> float(polygon_coverage(tri, (0, 0, 4, 4), pixel_m=1.0).sum())
    8.0
    """
    window = check_window(window)
    p = check_positive("pixel_m", pixel_m)
    v = as_float_array("vertices_m", vertices_m, ndim=2)
    if v.shape[0] < 3 or v.shape[1] != 2:
        raise InputError(f"vertices_m: must have shape (N >= 3, 2), got {v.shape}")
    row0, col0, h, w = window
    out = np.zeros((h, w))
    sub = sub_window(bbox_of(v), window, p)
    if sub is not None:
        r, c, sh, sw = sub
        out[r - row0 : r - row0 + sh, c - col0 : c - col0 + sw] = rings_coverage([v], sub, p)
    return np.clip(out, 0.0, 1.0)


def paint_polygon(image: np.ndarray, rings, reflectance: float, window: Window, pixel_m: float) -> None:
    """Compose uniform polygons over ``image`` (the rendered ``window``) in place, painter's order.

    ``image = image * (1 - cov) + reflectance * cov`` where ``cov`` is the exact coverage of ``rings``
    (one ``(N, 2)`` vertex array in metres, or a list of disjoint ones sharing a reflectance). Only the
    pixels of the rings' bounding box are touched.

    Examples
    --------
    >>> img = np.zeros((2, 2))
    >>> paint_polygon(img, rectangle(0.0, 0.0, 1.0, 2.0), 0.8, (0, 0, 2, 2), 1.0)
    >>> img.tolist()
    [[0.8, 0.0], [0.8, 0.0]]
    """
    if isinstance(rings, np.ndarray) and rings.ndim == 2:
        rings = [rings]
    rings = [np.asarray(r, dtype=float) for r in rings]
    if not rings:
        return
    lo = np.min([r.min(axis=0) for r in rings], axis=0)
    hi = np.max([r.max(axis=0) for r in rings], axis=0)
    sub = sub_window((lo[0], lo[1], hi[0], hi[1]), window, pixel_m)
    if sub is None:
        return
    r, c, sh, sw = sub
    cov = np.clip(rings_coverage(rings, sub, pixel_m), 0.0, 1.0)
    view = image[r - window[0] : r - window[0] + sh, c - window[1] : c - window[1] + sw]
    view += (reflectance - view) * cov


def rectangle(x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    """Axis-aligned rectangle ``[x0, x1] x [y0, y1]`` as a (4, 2) vertex array.

    Examples
    --------
    >>> rectangle(0, 0, 2, 1).tolist()
    [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]]
    """
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)


def place(vertices_local, origin_m: Sequence[float], rotation_deg: float = 0.0) -> np.ndarray:
    """Local ``(u, v)`` metres -> scene ``(x, y)``: rotate by ``rotation_deg`` then translate by origin.

    ``x = x0 + u cos(a) - v sin(a)``, ``y = y0 + u sin(a) + v cos(a)``; with y pointing down a positive
    angle turns clockwise on screen.

    Examples
    --------
    >>> place([[1.0, 0.0]], (10.0, 20.0), 90.0).round(12).tolist()
    [[10.0, 21.0]]
    """
    v = np.asarray(vertices_local, dtype=float)
    a = math.radians(rotation_deg)
    ca, sa = math.cos(a), math.sin(a)
    x = origin_m[0] + v[:, 0] * ca - v[:, 1] * sa
    y = origin_m[1] + v[:, 0] * sa + v[:, 1] * ca
    return np.stack([x, y], axis=1)


def disc_vertices(center_m: Sequence[float], radius_m: float, *, tol_m: float) -> np.ndarray:
    """Regular polygon standing in for a disc: outline within ``tol_m`` of the circle, same area.

    The circumradius ``rho = R sqrt(2 pi / (N sin(2 pi / N)))`` makes the N-gon's area equal to
    ``pi R^2`` exactly; N is the smallest count with ``rho (1 - cos(pi / N)) <= tol_m``.

    Examples
    --------
    >>> v = disc_vertices((0.0, 0.0), 2.0, tol_m=1e-4)
    >>> round(polygon_area(v) / (math.pi * 4.0), 12)
    1.0
    """
    r = check_positive("radius_m", radius_m)
    tol = min(check_positive("tol_m", tol_m), r / 4)
    n = max(16, math.ceil(math.pi / math.acos(1.0 - tol / (1.2 * r))))
    rho = r * math.sqrt(2 * math.pi / (n * math.sin(2 * math.pi / n)))
    a = np.arange(n) * (2 * math.pi / n)
    return np.stack([center_m[0] + rho * np.cos(a), center_m[1] + rho * np.sin(a)], axis=1)


def hyperbola_vertices(a_m2: float, s0_m: float, s1_m: float, *, tol_m: float) -> np.ndarray:
    """Points ``(s, a / s)`` for ``s`` in ``[s0, s1]`` (``s0 > 0``), chords within ``tol_m`` of the curve.

    The chord between samples ``h`` apart deviates from ``t = a / s`` by at most ``t'' h^2 / 8`` with
    ``t'' = 2 a / s^3``; sampling uniform in ``s^(-1/2)`` makes that bound equal to ``tol_m`` everywhere.

    Examples
    --------
    >>> v = hyperbola_vertices(2.0, 1.0, 4.0, tol_m=1e-3)
    >>> bool(np.allclose(v[:, 1], 2.0 / v[:, 0])), float(v[0, 0]), float(v[-1, 0])
    (True, 1.0, 4.0)
    """
    if a_m2 <= 0:
        return np.array([[s0_m, 0.0], [s1_m, 0.0]])
    q0, q1 = s0_m**-0.5, s1_m**-0.5
    n = max(2, math.ceil(1.5 * math.sqrt(a_m2 / tol_m) * (q0 - q1)) + 1)
    s = np.linspace(q0, q1, n) ** -2.0
    s[0], s[-1] = s0_m, s1_m
    return np.stack([s, a_m2 / s], axis=1)
