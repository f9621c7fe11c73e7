"""The sensor side of the radiometric chain: the camera equation and the photo-electrons of one pixel.

Focal-plane irradiance of an extended source ``E_fp = pi L_toa tau (1 - eps^2) / (4 F#^2)`` and the electrons
one pixel collects in one exposure ``N = t A_pix integral E_fp QE lambda / (h c) dlambda``; band integrals of
spectral quantities. Part of :mod:`satchain.radiometry`, which re-exports every public name.

References: J. R. Schott, *Remote Sensing: The Image Chain Approach*, 2nd ed., Oxford 2007, ch. 4;
R. D. Fiete, *Modeling the Imaging Chain of Digital Cameras*, SPIE 2010, ch. 5-6; G. C. Holst and
T. S. Lomheim, *CMOS/CCD Sensors and Camera Systems*, 2nd ed., SPIE 2011, ch. 4.

Examples
--------
>>> e_fp = focal_plane_irradiance(100.0, f_number=10.0)  # W m^-2 sr^-1 -> W m^-2
>>> round(float(e_fp), 6)
0.785398
"""

from __future__ import annotations

import math

import numpy as np

from satchain._validate import as_float_array, check_positive, check_range
from satchain.errors import InputError
from satchain.radiometry.source import photon_radiance

__all__ = ["band_radiance", "electrons_per_pixel", "focal_plane_irradiance"]


def focal_plane_irradiance(radiance, *, f_number: float, transmission: float = 1.0, obscuration_ratio=0.0):
    """Camera equation for an extended source: ``E_fp = pi L tau (1 - eps^2) / (4 F#^2)``.

    The small-angle form (paraxial, on axis, no vignetting; Schott 2007 eq. 4.32; Fiete 2010 eq. 5.23;
    Holst & Lomheim 2011 sec. 4.2). The exact form for an aplanatic lens, ``pi L / (1 + 4 F#^2)``, differs
    by ``1 / (1 + 1 / (4 F#^2))``: 0.26 % at f/9.72. ``eps`` is the linear central-obscuration ratio, so
    ``eps^2`` is the blocked fraction of the pupil area; ``tau`` the optics transmission.

    Examples
    --------
    >>> round(float(focal_plane_irradiance(100.0, f_number=10.0, obscuration_ratio=0.5)), 6)
    0.589049
    """
    n = check_positive("optics.f_number", f_number)
    tau = check_range("optics.transmission", transmission, 0.0, 1.0)
    eps = check_range("optics.obscuration_ratio", obscuration_ratio, 0.0, 1.0, hi_open=True)
    return math.pi * np.asarray(radiance, dtype=float) * tau * (1.0 - eps**2) / (4.0 * n**2)


def electrons_per_pixel(
    wavelength_m, irradiance_w_per_m2_per_m, *, pixel_area_m2: float, integration_time_s: float, qe=1.0
) -> float:
    """Photo-electrons collected by one pixel in one exposure (one TDI stage).

    ``N = t A integral E_fp(lambda) QE(lambda) lambda / (h c) dlambda`` (trapezoid over the given grid;
    Fiete 2010 eq. 6.5). ``qe`` is a number or an array on ``wavelength_m``.

    Examples
    --------
    >>> lam = np.array([500e-9, 501e-9])  # 1 W/m^2 in 1 nm, on 1e-10 m^2 for 1 ms: 1e-13 J at ~500.5 nm
    >>> round(electrons_per_pixel(lam, [1e9, 1e9], pixel_area_m2=1e-10, integration_time_s=1e-3))
    251958
    """
    lam = as_float_array("wavelength_m", wavelength_m, ndim=1)
    e = as_float_array("irradiance_w_per_m2_per_m", irradiance_w_per_m2_per_m, ndim=1)
    if lam.shape != e.shape or lam.size < 2:
        raise InputError(
            f"wavelength_m and irradiance_w_per_m2_per_m: need equal 1-D shapes of >= 2 values, "
            f"got {lam.shape} and {e.shape}"
        )
    a = check_positive("pixel_area_m2", pixel_area_m2)
    t = check_positive("integration_time_s", integration_time_s)
    q = np.broadcast_to(np.asarray(qe, dtype=float), lam.shape)
    return float(t * a * np.trapezoid(photon_radiance(lam, e) * q, lam))


def _band_grid(lam: np.ndarray, band_m: tuple[float, float]) -> np.ndarray:
    lo, hi = band_m
    inside = (lam > lo * (1 + 1e-12)) & (lam < hi * (1 - 1e-12))  # table points on an edge count once
    return np.concatenate([[lo], lam[inside], [hi]])


def band_radiance(wavelength_m, spectral, band_m: tuple[float, float]) -> float:
    """Integral of a spectral quantity (per m of wavelength) over ``band_m`` (linear interpolation at
    the band edges, trapezoid inside).

    Examples
    --------
    >>> round(band_radiance([4e-7, 1e-6], [1e6, 1e6], (5e-7, 7e-7)), 9)  # 1 W/m^2/um over 0.2 um
    0.2
    """
    lam = as_float_array("wavelength_m", wavelength_m, ndim=1)
    y = as_float_array("spectral", spectral, ndim=1)
    lb = _band_grid(lam, band_m)
    return float(np.trapezoid(np.interp(lb, lam, y), lb))
