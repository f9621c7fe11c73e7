"""Spectral responses of a camera's bands (pure: numbers in, numbers out): a (super-)Gaussian filter or a table,
with the support the band spans and a quadrature of the response over it.

A ``[[bands]]`` entry's ``response`` (:class:`satchain.config.sections_light.Band`) is a
:class:`SuperGaussianResponse` (a Gaussian for ``order = 1``) or a :class:`TabulatedResponse` (``response_file``);
:func:`response_quadrature` turns it into the optics' wavelengths and weights, and its :attr:`support_m` into the
radiometric band. This module lives in ``config`` (not ``radiometry``) because the system's validation and
``ImagingSystem.for_band`` use it, and ``config`` sits below ``radiometry`` in the layers.

The quadrature splits the support into ``n`` equal bins; each node is the centroid of the response over its bin and
its weight the response's integral over the bin. So the weights sum to the response's area and their centroid is
the response's centroid exactly (up to the fine sampling of each bin), whatever the shape.

Examples
--------
>>> r = SuperGaussianResponse(center_m=6.6e-7, fwhm_m=6e-8)
>>> lam, w = response_quadrature(r, 11)
>>> round(float(np.sum(w * lam) / np.sum(w)) * 1e9, 6), round(float(np.sum(w)) / r.area_m, 4)
(660.0, 0.9998)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["SUPPORT_FLOOR", "SuperGaussianResponse", "TabulatedResponse", "response_quadrature", "response_table"]

#: A super-Gaussian's support ends where it falls to this fraction of its peak.
SUPPORT_FLOOR = 1e-3

_LN2 = math.log(2.0)


@dataclass(frozen=True)
class SuperGaussianResponse:
    """``R(lambda) = exp(-ln2 |2 (lambda - center) / fwhm|^(2 order))``, peak 1: a Gaussian for ``order = 1``; a
    higher order has a flatter top and steeper edges (an interference filter) with the same FWHM. Its support
    reaches :data:`SUPPORT_FLOOR` of the peak; its area is ``fwhm Gamma(1 + 1/(2n)) / ln2^(1/(2n))``
    (``fwhm sqrt(pi / (4 ln 2))`` for a Gaussian).

    Examples
    --------
    >>> round(SuperGaussianResponse(5e-7, 1e-7)(5.5e-7).item(), 6)  # half maximum at centre + FWHM/2
    0.5
    """

    center_m: float
    fwhm_m: float
    order: int = 1

    def __call__(self, wavelength_m) -> np.ndarray:
        u = 2.0 * np.abs(np.asarray(wavelength_m, dtype=float) - self.center_m) / self.fwhm_m
        return np.exp(-_LN2 * u ** (2 * self.order))

    @property
    def support_m(self) -> tuple[float, float]:
        half = 0.5 * self.fwhm_m * (math.log(1.0 / SUPPORT_FLOOR) / _LN2) ** (1.0 / (2 * self.order))
        return self.center_m - half, self.center_m + half

    @property
    def area_m(self) -> float:
        """The integral of the (untruncated) response over wavelength, m."""
        p = 1.0 / (2 * self.order)
        return self.fwhm_m * math.gamma(1.0 + p) / _LN2**p

    @property
    def knots_m(self) -> np.ndarray:
        return np.empty(0)


@dataclass(frozen=True)
class TabulatedResponse:
    """A response given as a table (linear between the points, 0 outside): ``wavelengths_m`` strictly increasing,
    ``values`` >= 0 (a filter's transmission, not renormalised). Its support runs from the last zero before the
    first positive value to the first zero after the last one (the table's ends where it is positive there).

    Examples
    --------
    >>> TabulatedResponse((4e-7, 5e-7, 6e-7, 7e-7), (0.0, 1.0, 1.0, 0.0)).support_m
    (4e-07, 7e-07)
    """

    wavelengths_m: tuple[float, ...]
    values: tuple[float, ...]

    def __call__(self, wavelength_m) -> np.ndarray:
        return np.interp(np.asarray(wavelength_m, dtype=float), self.wavelengths_m, self.values, left=0.0, right=0.0)

    @property
    def support_m(self) -> tuple[float, float]:
        pos = np.flatnonzero(np.asarray(self.values) > 0)
        i0, i1 = max(int(pos[0]) - 1, 0), min(int(pos[-1]) + 1, len(self.values) - 1)
        return float(self.wavelengths_m[i0]), float(self.wavelengths_m[i1])

    @property
    def area_m(self) -> float:
        """The integral of the table (exact: it is linear between its points), m."""
        return float(np.trapezoid(self.values, self.wavelengths_m))

    @property
    def knots_m(self) -> np.ndarray:
        return np.asarray(self.wavelengths_m, dtype=float)


Response = SuperGaussianResponse | TabulatedResponse


def response_table(response: Response, n: int = 161) -> tuple[np.ndarray, np.ndarray]:
    """The response sampled over its support: ``n`` equal steps plus a table's own points (so linear
    interpolation of the result reproduces a table exactly). Returns ``(wavelength_m, response)``.

    Examples
    --------
    >>> lam, r = response_table(SuperGaussianResponse(5e-7, 1e-7), 5)
    >>> len(lam), round(float(r.max()), 6)
    (5, 1.0)
    """
    lo, hi = response.support_m
    k = response.knots_m
    lam = np.union1d(np.linspace(lo, hi, n), k[(k > lo) & (k < hi)])
    return lam, response(lam)


def response_quadrature(
    response: Response, n: int = 11, *, samples_per_bin: int = 200
) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights of the response over its support: ``n`` equal bins, each node the centroid of the response
    over its bin, each weight its integral there (m); bins where the response is 0 are left out.

    ``sum(weights)`` is the area over the support and ``sum(weights * nodes) / sum(weights)`` its centroid (the
    bins are integrated by the trapezoid rule on ``samples_per_bin`` steps plus a table's own points).

    Examples
    --------
    >>> lam, w = response_quadrature(TabulatedResponse((5e-7, 6e-7), (1.0, 1.0)), 2)
    >>> [round(float(x) * 1e9, 3) for x in lam], [round(float(x) * 1e9, 3) for x in w]
    ([525.0, 575.0], [50.0, 50.0])
    """
    if n < 1:
        raise ValueError(f"n = {n!r}: must be >= 1 (nodes of the quadrature)")
    lo, hi = response.support_m
    edges = np.linspace(lo, hi, n + 1)
    lam, r = response_table(response, n * samples_per_bin + 1)
    lam = np.union1d(lam, edges)
    r = response(lam)
    seg = 0.5 * np.diff(lam)
    cum0 = np.concatenate([[0.0], np.cumsum(seg * (r[1:] + r[:-1]))])
    lr = lam * r
    cum1 = np.concatenate([[0.0], np.cumsum(seg * (lr[1:] + lr[:-1]))])
    at = np.searchsorted(lam, edges)
    w = np.diff(cum0[at])
    m = np.diff(cum1[at])
    keep = w > 0
    return m[keep] / w[keep], w[keep]
