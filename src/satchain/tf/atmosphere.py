"""Atmospheric transfer functions: turbulence (Fried) and aerosol adjacency.

**Turbulence.** The long-exposure OTF of Kolmogorov turbulence is ``exp(-3.44 (lambda nu / r0)^(5/3))`` with
``nu`` the angular frequency (cycles/rad) and ``r0`` Fried's parameter (Fried 1966, JOSA 56, 1372); the
short-exposure (tilt-removed) OTF multiplies the exponent by ``1 - (lambda nu / D)^(1/3)``. For a camera
looking down on a point of the ground, the wave is spherical and starts at the ground: turbulence at height
``h`` is weighted by ``(h / H)^(5/3)`` (Fried 1966; the "shower-curtain" effect), so the boundary layer that
dominates ground-based seeing barely blurs a satellite image:

    r0 = [0.423 k^2 sec(zeta) int_0^H Cn2(h) (h / H)^(5/3) dh]^(-3/5)          (down-looking)
    r0 = [0.423 k^2 sec(zeta) int_0^inf Cn2(h) dh]^(-3/5)                      (up-looking, plane wave)

with the Hufnagel-Valley 5/7 profile (Valley 1980, Appl. Opt. 19, 574; r0 = 5 cm at 0.5 um looking up).

**Aerosol adjacency.** Light scattered by aerosols reaches the sensor from a wide neighbourhood: a fraction
``s`` of the signal has a broad PSF (here exponential, ``exp(-r / L) / (2 pi L^2)`` on the ground), the rest is
direct. ``OTF = (1 - s) + s (1 + (2 pi L f_ground)^2)^(-3/2)`` (a first-order model after Kaufman 1982, J.
Geophys. Res. 87, 4137): a contrast loss ``s`` at image frequencies, no loss at the scene mean.
"""

from __future__ import annotations

import numpy as np
from scipy import integrate

from satchain._validate import check_range
from satchain.units import MM_PER_M

__all__ = ["aerosol_otf", "fried_r0_m", "hufnagel_valley_cn2", "turbulence_otf"]


def hufnagel_valley_cn2(h_m, *, wind_m_per_s: float = 21.0, ground_cn2: float = 1.7e-14) -> np.ndarray:
    """Hufnagel-Valley refractive-index structure constant ``Cn2(h)`` (m^-2/3); defaults are HV 5/7.

    Examples
    --------
    >>> float(hufnagel_valley_cn2(0.0)) > 1e-14
    True
    """
    h = np.asarray(h_m, dtype=float)
    w = check_range("wind_m_per_s", wind_m_per_s, 0, 200)
    a = check_range("ground_cn2", ground_cn2, 0, 1e-10)
    return (
        0.00594 * (w / 27.0) ** 2 * (1e-5 * h) ** 10 * np.exp(-h / 1000.0)
        + 2.7e-16 * np.exp(-h / 1500.0)
        + a * np.exp(-h / 100.0)
    )


def fried_r0_m(
    wavelength_m: float,
    *,
    altitude_m: float,
    zenith_deg: float = 0.0,
    looking: str = "down",
    cn2=hufnagel_valley_cn2,
) -> float:
    """Fried's parameter for a path between the ground and ``altitude_m`` (see the module docstring).

    Examples
    --------
    >>> round(fried_r0_m(0.5e-6, altitude_m=30e3, looking="up"), 3)   # HV 5/7 is designed for 5 cm
    0.05
    """
    lam = check_range("wavelength_m", wavelength_m, 1e-8, 1e-4)
    H = check_range("altitude_m", altitude_m, 0, None, lo_open=True)
    zen = check_range("zenith_deg", zenith_deg, 0, 80)
    if looking not in ("down", "up"):
        from satchain.errors import ConfigError

        raise ConfigError(f"looking = {looking!r}: must be 'down' or 'up'")
    top = min(H, 30e3)
    if looking == "down":
        weight = lambda h: cn2(h) * (h / H) ** (5.0 / 3.0)  # noqa: E731
    else:
        weight = cn2
    pts = [100.0, 1000.0, 5000.0, 15000.0]
    val, _ = integrate.quad(weight, 0.0, top, points=[p for p in pts if p < top], limit=200)
    k = 2 * np.pi / lam
    return float((0.423 * k**2 / np.cos(np.radians(zen)) * val) ** (-3.0 / 5.0))


def turbulence_otf(
    fx_cy_per_mm,
    fy_cy_per_mm,
    *,
    wavelength_m: float,
    focal_length_m: float,
    r0_m: float,
    aperture_diameter_m: float | None = None,
) -> np.ndarray:
    """Turbulence OTF at focal-plane frequencies: long exposure, or short exposure when the aperture is given.

    Examples
    --------
    >>> float(turbulence_otf(0.0, 0.0, wavelength_m=6.5e-7, focal_length_m=6.8, r0_m=0.1))
    1.0
    """
    lam = check_range("wavelength_m", wavelength_m, 1e-8, 1e-4)
    f = check_range("focal_length_m", focal_length_m, 0, None, lo_open=True)
    r0 = check_range("r0_m", r0_m, 0, None, lo_open=True)
    fx, fy = np.broadcast_arrays(np.asarray(fx_cy_per_mm, float), np.asarray(fy_cy_per_mm, float))
    x = lam * np.hypot(fx, fy) * MM_PER_M * f  # lambda * angular frequency (cycles/rad)
    expo = 3.44 * (x / r0) ** (5.0 / 3.0)
    if aperture_diameter_m is not None:
        d = check_range("aperture_diameter_m", aperture_diameter_m, 0, None, lo_open=True)
        expo = expo * np.clip(1.0 - (x / d) ** (1.0 / 3.0), 0.0, None)
    return np.exp(-expo)


def aerosol_otf(f_cy_per_m_ground, *, scattered_fraction: float, psf_scale_m: float) -> np.ndarray:
    """Aerosol adjacency OTF at ground frequencies (isotropic; see the module docstring).

    Examples
    --------
    >>> float(aerosol_otf(0.0, scattered_fraction=0.2, psf_scale_m=200.0))
    1.0
    >>> round(float(aerosol_otf(1.0, scattered_fraction=0.2, psf_scale_m=200.0)), 6)
    0.8
    """
    s = check_range("scattered_fraction", scattered_fraction, 0, 1, hi_open=True)
    L = check_range("psf_scale_m", psf_scale_m, 0, None, lo_open=True)
    f = np.asarray(f_cy_per_m_ground, float)
    return (1.0 - s) + s * (1.0 + (2 * np.pi * L * f) ** 2) ** -1.5
