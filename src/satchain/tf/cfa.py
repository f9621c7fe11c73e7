"""Sampling of a Bayer colour filter array: each colour plane's lattice, its reciprocal lattice (where it
aliases), its Nyquist frequency along any direction, and its MTF at that Nyquist from the system OTF.

A Bayer array ``[detector] cfa`` ("RGGB", "GRBG", "GBRG" or "BGGR": the 2x2 cell read row by row from pixel
(row 0, column 0)) puts one colour filter on each photosite (Bayer, US patent 3,971,065, 1976). Each colour's
photosites form a lattice (pixel units, ``(x, y)`` = (column, row), x ACT, y ALT):

``red``, ``blue``
    a rectangular lattice of pitch 2 px in x and y (basis ``(2, 0), (0, 2)``; 1/4 of the sites). Its
    reciprocal lattice is the points ``(m, n) / 2`` cy/px, so its first Brillouin zone is the square
    ``|fx|, |fy| <= 1/4`` cy/px: the Nyquist frequency is ``1/(4p)`` along each axis and ``sqrt(2)/(4p)``
    (0.354 cy/px) along the diagonals.
``green``
    a quincunx (basis ``(1, 1), (1, -1)``; 1/2 of the sites): a square lattice of pitch ``sqrt(2)`` px turned
    by 45 deg. Its reciprocal lattice is the points ``(m + n, m - n) / 2`` cy/px (``(1/2, 1/2)``, ``(1, 0)``,
    ...), its first Brillouin zone the diamond ``|fx| + |fy| <= 1/2`` cy/px: the Nyquist frequency is ``1/(2p)``
    along the axes (as a monochrome array) but only ``1/(2 sqrt(2) p)`` (0.354 cy/px) along the diagonals.

An input frequency ``f`` reappears in a colour plane's samples at ``f - g`` for every reciprocal-lattice point
``g`` (Dubois, "Frequency-domain methods for demosaicking of Bayer-sampled color images", IEEE Signal Process.
Lett. 12(12), 2005; Alleysson, Susstrunk & Herault, IEEE Trans. Image Process. 14(4), 2005): the replica of
``g`` carries the phase ``exp(-2 pi i g . o)`` of the lattice origin ``o``, which the pattern's phase sets
(RGGB and BGGR move the red lattice by one pixel diagonally): the phase changes the sign of aliased terms,
never their modulus. The photosite aperture (the active width's sinc) is the same for every colour: the
plane's pre-sampling MTF is the system MTF (of that colour's spectral response), only its sampling differs.

Frequencies are cycles per pixel of the full array (``f_cy_per_px``; cy/mm = cy/px / pitch_mm) unless a
name says otherwise; directions are angles from +x (ACT) towards +y (ALT), in degrees.

Examples
--------
>>> round(nyquist_cy_per_px("RGGB", "red", direction_deg=0.0), 6), round(nyquist_cy_per_px("RGGB", "green"), 6)
(0.25, 0.5)
>>> round(nyquist_cy_per_px("RGGB", "green", direction_deg=45.0), 4)
0.3536
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from satchain._validate import as_float_array, check_choice, check_range
from satchain.config.sections_cfa import CFA_COLOURS, CFA_PATTERNS
from satchain.units import MM_PER_M

__all__ = [
    "CFA_COLOURS",
    "CFA_PATTERNS",
    "PlaneLattice",
    "aliased_fraction",
    "alias_frequencies_cy_per_px",
    "cfa_sites",
    "first_alias_cy_per_px",
    "grid_nyquist_cy_per_px",
    "in_passband",
    "nyquist_cy_per_px",
    "plane_lattice",
    "plane_mtf",
    "plane_mtf_at_nyquist",
]

_LETTER = {"R": "red", "G": "green", "B": "blue"}
_BASIS_PX = {
    "red": ((2.0, 0.0), (0.0, 2.0)),
    "blue": ((2.0, 0.0), (0.0, 2.0)),
    "green": ((1.0, 1.0), (1.0, -1.0)),
}


def _check(pattern: str, colour: str) -> None:
    check_choice("cfa pattern", pattern, CFA_PATTERNS)
    check_choice("colour", colour, CFA_COLOURS)


def cfa_sites(pattern: str, colour: str) -> tuple[tuple[int, int], ...]:
    """The ``(row, col)`` positions of ``colour`` in the pattern's 2x2 cell (the cell repeats every 2 px).

    Examples
    --------
    >>> cfa_sites("RGGB", "green"), cfa_sites("BGGR", "red")
    (((0, 1), (1, 0)), ((1, 1),))
    """
    _check(pattern, colour)
    return tuple((i // 2, i % 2) for i, c in enumerate(pattern) if _LETTER[c] == colour)


@dataclass(frozen=True)
class PlaneLattice:
    """The lattice of one colour's photosites: ``origin_px + m a1 + n a2`` (``(x, y)`` in pixels of the full
    array) with ``basis_px = (a1, a2)``.

    Attributes
    ----------
    colour : str
    basis_px : ndarray, shape (2, 2)
        Rows ``a1``, ``a2`` (x, y), px.
    origin_px : ndarray, shape (2,)
        One site, ``(x, y)`` = (column, row), px.
    """

    colour: str
    basis_px: np.ndarray
    origin_px: np.ndarray

    @property
    def reciprocal_cy_per_px(self) -> np.ndarray:
        """Rows ``b1``, ``b2`` with ``a_i . b_j = delta_ij`` (cy/px): the reciprocal lattice ``m b1 + n b2`` is
        where the plane's spectrum repeats (its alias positions)."""
        return np.linalg.inv(self.basis_px).T

    @property
    def sites_per_pixel(self) -> float:
        """The fraction of the array's photosites in this lattice (1/4 red, 1/2 green, 1/4 blue)."""
        return 1.0 / abs(float(np.linalg.det(self.basis_px)))

    @property
    def pitch_px(self) -> float:
        """The lattice's own pitch (px): 2 for red and blue, sqrt(2) for green (along the diagonals)."""
        return float(np.hypot(*self.basis_px[0]))

    def replica_phase(self, g_cy_per_px) -> np.ndarray:
        """The phase factor ``exp(-2 pi i g . origin)`` of the spectrum's replica at reciprocal-lattice
        point(s) ``g`` (shape (..., 2)): 1 at g = 0; a pattern's phase changes it, never its modulus."""
        g = np.asarray(g_cy_per_px, dtype=float)
        return np.exp(-2j * np.pi * (g @ self.origin_px))


def plane_lattice(pattern: str, colour: str) -> PlaneLattice:
    """The lattice of ``colour``'s photosites for ``pattern``: its basis and the site of the 2x2 cell that is
    its origin (the first one read row by row).

    Examples
    --------
    >>> lat = plane_lattice("RGGB", "green")
    >>> lat.origin_px.tolist(), lat.reciprocal_cy_per_px.tolist(), lat.sites_per_pixel
    ([1.0, 0.0], [[0.5, 0.5], [0.5, -0.5]], 0.5)
    """
    row, col = cfa_sites(pattern, colour)[0]
    return PlaneLattice(colour, np.array(_BASIS_PX[colour], dtype=float), np.array([col, row], dtype=float))


def alias_frequencies_cy_per_px(pattern: str, colour: str, *, f_max_cy_per_px: float = 1.0) -> np.ndarray:
    """The nonzero reciprocal-lattice points ``g`` of ``colour``'s lattice with ``|gx|, |gy| <= f_max`` (cy/px),
    nearest first, shape (n, 2) as ``(fx, fy)``: an input frequency ``f`` also appears at ``f - g``.

    Examples
    --------
    >>> alias_frequencies_cy_per_px("RGGB", "red", f_max_cy_per_px=0.5)[:4].tolist()
    [[0.0, -0.5], [-0.5, 0.0], [0.5, 0.0], [0.0, 0.5]]
    """
    f_max = check_range("f_max_cy_per_px", f_max_cy_per_px, 0, 16, lo_open=True)
    b = plane_lattice(pattern, colour).reciprocal_cy_per_px
    n = int(math.ceil(2 * f_max / min(np.abs(b[b != 0])))) + 1
    m = np.arange(-n, n + 1)
    mm, nn = (a.ravel() for a in np.meshgrid(m, m, indexing="ij"))
    g = mm[:, None] * b[0] + nn[:, None] * b[1]
    keep = (np.abs(g) <= f_max + 1e-12).all(axis=1) & (np.hypot(g[:, 0], g[:, 1]) > 0)
    g = g[keep] + 0.0  # no negative zeros
    order = np.lexsort((g[:, 0], g[:, 1], np.round(np.hypot(g[:, 0], g[:, 1]), 12)))
    return g[order]


def _near_points(pattern: str, colour: str) -> np.ndarray:
    """The reciprocal points that bound the first Brillouin zone (the nearest shells suffice for these
    lattices)."""
    return alias_frequencies_cy_per_px(pattern, colour, f_max_cy_per_px=1.0)


def nyquist_cy_per_px(pattern: str, colour: str, *, direction_deg: float = 0.0) -> float:
    """The plane's Nyquist frequency along a direction: where the ray from f = 0 leaves its first Brillouin
    zone, ``min over g (g . u > 0) of |g|^2 / (2 g . u)`` (cy/px). Frequencies beyond it alias.

    Red and blue: 0.25 along x and y, 0.354 along the diagonals; green: 0.5 along x and y, 0.354 along the
    diagonals (the quincunx's zone is a diamond).

    Examples
    --------
    >>> round(nyquist_cy_per_px("GRBG", "blue", direction_deg=90.0), 6)
    0.25
    """
    angle = math.radians(check_range("direction_deg", direction_deg, -360, 360))
    u = np.array([math.cos(angle), math.sin(angle)])
    g = _near_points(pattern, colour)
    gu = g @ u
    ahead = gu > 1e-12
    return float(np.min(np.sum(g[ahead] ** 2, axis=1) / (2.0 * gu[ahead])))


def grid_nyquist_cy_per_px(colour: str) -> float:
    """Half the sampling frequency of the plane's own grid along its own axes, ``1 / (2 pitch)``: 0.25 cy/px
    for red and blue (pitch 2 px), ``1 / (2 sqrt(2))`` = 0.354 cy/px for green (pitch sqrt(2) px, along the
    diagonals). A slanted edge measured on the plane's own grid reports its MTF "at Nyquist" here (0.5 cy per
    plane pixel), along the edge normal.

    Examples
    --------
    >>> grid_nyquist_cy_per_px("red"), round(grid_nyquist_cy_per_px("green"), 4)
    (0.25, 0.3536)
    """
    check_choice("colour", colour, CFA_COLOURS)
    return 0.5 / float(np.hypot(*_BASIS_PX[colour][0]))


def in_passband(fx_cy_per_px, fy_cy_per_px, pattern: str, colour: str) -> np.ndarray:
    """True where ``(fx, fy)`` lies inside the plane's first Brillouin zone (closer to 0 than to any
    reciprocal-lattice point, boundary included): the frequencies the plane samples without aliasing."""
    fx, fy = np.broadcast_arrays(np.asarray(fx_cy_per_px, float), np.asarray(fy_cy_per_px, float))
    g = _near_points(pattern, colour)
    proj = fx[..., None] * g[:, 0] + fy[..., None] * g[:, 1]
    return np.all(proj <= 0.5 * np.sum(g**2, axis=1) + 1e-12, axis=-1)


def first_alias_cy_per_px(fx_cy_per_px, fy_cy_per_px, pattern: str, colour: str) -> tuple[np.ndarray, np.ndarray]:
    """Where an input frequency ``(fx, fy)`` appears in the plane's samples: ``f - g`` for the
    reciprocal-lattice point ``g`` nearest to ``f`` (``f`` itself inside the passband).

    Examples
    --------
    >>> [round(float(v), 6) for v in first_alias_cy_per_px(0.3, 0.0, "RGGB", "red")]
    [-0.2, 0.0]
    >>> [round(float(v), 6) for v in first_alias_cy_per_px(0.3, 0.0, "RGGB", "green")]
    [0.3, 0.0]
    """
    fx, fy = np.broadcast_arrays(np.asarray(fx_cy_per_px, float), np.asarray(fy_cy_per_px, float))
    g = np.vstack([np.zeros((1, 2)), _near_points(pattern, colour)])
    lat = plane_lattice(pattern, colour)  # fold into one lattice cell first: exact for any f
    shift = np.rint(np.stack([fx, fy], axis=-1) @ lat.basis_px.T) @ lat.reciprocal_cy_per_px
    fx, fy = fx - shift[..., 0], fy - shift[..., 1]
    d2 = (fx[..., None] - g[:, 0]) ** 2 + (fy[..., None] - g[:, 1]) ** 2
    best = np.argmin(d2 - 1e-12 * (np.arange(len(g)) == 0), axis=-1)
    return fx - g[best, 0], fy - g[best, 1]


def aliased_fraction(fx_cy_per_px, fy_cy_per_px, mtf, pattern: str, colour: str) -> float:
    """The fraction of the system MTF that lies beyond the plane's Nyquist: ``sum(MTF outside the first
    Brillouin zone) / sum(MTF)`` over the caller's frequency samples, which must sample the region of interest
    uniformly (a square grid up to 1 cy/px, or a uniform cut along one direction). The same system MTF gives
    a larger fraction for red and blue than for green, and 0 for a band limit inside the zone.

    Examples
    --------
    >>> f = np.linspace(0.0, 1.0, 101)
    >>> round(aliased_fraction(f, 0.0, np.clip(1 - f, 0, None), "RGGB", "red"), 4)
    0.5495
    """
    m = np.abs(as_float_array("mtf", mtf))
    fx, fy, m = np.broadcast_arrays(np.asarray(fx_cy_per_px, float), np.asarray(fy_cy_per_px, float), m)
    total = float(np.sum(m))
    if total <= 0:
        return 0.0
    return float(np.sum(m[~in_passband(fx, fy, pattern, colour)]) / total)


def plane_mtf(
    system_otf: Callable[[np.ndarray, np.ndarray], np.ndarray],
    f_cy_per_px,
    *,
    pitch_x_m: float,
    pitch_y_m: float,
    direction_deg: float = 0.0,
) -> np.ndarray:
    """A colour plane's pre-sampling MTF along a direction: ``|OTF(f cos a / p_x, f sin a / p_y)|``, the
    system OTF (a callable of focal-plane cy/mm, e.g. :class:`satchain.tf.budget.SystemOTF` of the colour's
    spectral response) at ``f_cy_per_px``. The photosite aperture is in that OTF at the array's own pitch and
    active width: a colour plane samples more coarsely, its photosites are no larger.

    Examples
    --------
    >>> from satchain.tf.detector import pixel_otf
    >>> otf = lambda fx, fy: pixel_otf(fx, fy, active_width_x_m=5e-6, active_width_y_m=5e-6)
    >>> round(float(plane_mtf(otf, 0.25, pitch_x_m=5e-6, pitch_y_m=5e-6)), 4)  # sinc(1/4)
    0.9003
    """
    f = np.asarray(f_cy_per_px, dtype=float)
    a = math.radians(check_range("direction_deg", direction_deg, -360, 360))
    px_mm = check_range("pitch_x_m", pitch_x_m, 0, None, lo_open=True) * MM_PER_M
    py_mm = check_range("pitch_y_m", pitch_y_m, 0, None, lo_open=True) * MM_PER_M
    return np.abs(np.asarray(system_otf(f * math.cos(a) / px_mm, f * math.sin(a) / py_mm)))


def plane_mtf_at_nyquist(
    system_otf: Callable[[np.ndarray, np.ndarray], np.ndarray],
    pattern: str,
    colour: str,
    *,
    pitch_x_m: float,
    pitch_y_m: float,
    direction_deg: float = 0.0,
) -> float:
    """The plane's MTF at its own Nyquist along a direction (:func:`nyquist_cy_per_px`): the system MTF
    evaluated there (ACT, ``direction_deg = 0``: at 1/(4 p) for red and blue, 1/(2 p) for green).

    Examples
    --------
    >>> from satchain.tf.detector import pixel_otf
    >>> otf = lambda fx, fy: pixel_otf(fx, fy, active_width_x_m=5e-6, active_width_y_m=5e-6)
    >>> round(plane_mtf_at_nyquist(otf, "RGGB", "green", pitch_x_m=5e-6, pitch_y_m=5e-6), 4)  # sinc(1/2)
    0.6366
    """
    f = nyquist_cy_per_px(pattern, colour, direction_deg=direction_deg)
    return float(plane_mtf(system_otf, f, pitch_x_m=pitch_x_m, pitch_y_m=pitch_y_m, direction_deg=direction_deg))
