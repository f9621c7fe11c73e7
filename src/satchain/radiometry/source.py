"""The source side of the radiometric chain: the sun, the atmosphere's transmission and the surface.

Solar spectral irradiance at the top of the atmosphere ``E0(lambda)`` (W m^-2 m^-1: the ASTM G173-03
extraterrestrial table shipped with satchain, or a 5778 K black body seen at 1 AU), irradiance on horizontal
ground ``E = E0 cos(sza) T_down``, the radiance of a Lambertian surface ``L = rho E / pi`` and the radiance at
the top of the atmosphere ``L_toa = L_surface T_up + L_path``; plus the spectral unit conversions. Part of
:mod:`satchain.radiometry`, which re-exports every public name.

References: J. R. Schott, *Remote Sensing: The Image Chain Approach*, 2nd ed., Oxford 2007, ch. 3-5.

Examples
--------
>>> lam, e0 = solar_spectrum()
>>> round(float(np.trapezoid(e0, lam)), 1)
1347.9
"""

from __future__ import annotations

import functools
import math
from importlib import resources

import numpy as np
from scipy import constants as _c

from satchain._validate import as_float_array, check_choice, check_positive, check_range
from satchain.errors import InputError

__all__ = [
    "AU_M",
    "C_M_PER_S",
    "H_J_S",
    "K_J_PER_K",
    "SIGMA_W_PER_M2_K4",
    "SOLAR_SPECTRA",
    "SUN_RADIUS_M",
    "atmosphere_transmissions",
    "lambertian_radiance",
    "photon_radiance",
    "planck_solar_irradiance",
    "planck_spectral_radiance",
    "solar_spectrum",
    "spectral_per_m_to_per_um",
    "spectral_per_um_to_per_m",
    "surface_irradiance",
    "toa_radiance",
]

H_J_S = _c.h  # Planck constant (exact, SI 2019)
C_M_PER_S = _c.c
K_J_PER_K = _c.k
SIGMA_W_PER_M2_K4 = _c.Stefan_Boltzmann
SUN_RADIUS_M = 6.957e8  # IAU 2015 nominal solar radius
AU_M = 1.495978707e11  # IAU 2012 astronomical unit
SOLAR_SPECTRA = ("astm_g173_etr", "planck_5778k")


# ---------------------------------------------------------------------------- units
def spectral_per_m_to_per_um(value):
    """A spectral density per metre of wavelength -> per micrometre (``W m^-2 sr^-1 m^-1 -> ... um^-1``).

    Examples
    --------
    >>> float(spectral_per_m_to_per_um(1e8))
    100.0
    """
    return np.asarray(value, dtype=float) * 1e-6


def spectral_per_um_to_per_m(value):
    """A spectral density per micrometre -> per metre of wavelength (inverse of the above).

    Examples
    --------
    >>> float(spectral_per_um_to_per_m(100.0))
    100000000.0
    """
    return np.asarray(value, dtype=float) * 1e6


def photon_radiance(wavelength_m, radiance_w):
    """Watts -> photons per second: divide a spectral power quantity by the photon energy ``h c / lambda``.

    Works for any radiometric quantity (radiance, irradiance, flux), spectral or not.

    Examples
    --------
    >>> round(float(photon_radiance(5e-7, 1.0)) / 1e18, 4)  # 1 W at 500 nm: 5e-7 / (h c) photons/s
    2.5171
    """
    lam = as_float_array("wavelength_m", wavelength_m)
    return np.asarray(radiance_w, dtype=float) * lam / (H_J_S * C_M_PER_S)


# ---------------------------------------------------------------------------- the sun
def solar_spectrum(name: str = "astm_g173_etr", wavelength_m=None) -> tuple[np.ndarray, np.ndarray]:
    """Solar spectral irradiance at the top of the atmosphere, mean Sun-Earth distance.

    Parameters
    ----------
    name : {"astm_g173_etr", "planck_5778k"}
        ``"astm_g173_etr"``: the ASTM G173-03 extraterrestrial table (package data
        ``satchain/data/astm_g173_etr.csv``, 280-4000 nm, integral 1347.9 W/m^2); ``"planck_5778k"``:
        :func:`planck_solar_irradiance` at 5778 K.
    wavelength_m : array_like, optional
        Wavelengths to return (the table is interpolated linearly, 0 outside 280-4000 nm). Default: the
        table's own wavelengths (for both names, so the two are directly comparable).

    Returns
    -------
    wavelength_m, irradiance_w_per_m2_per_m : ndarray

    Examples
    --------
    >>> lam, e0 = solar_spectrum()
    >>> round(float(np.trapezoid(e0, lam)), 1)
    1347.9
    """
    check_choice("illumination.solar_spectrum", name, SOLAR_SPECTRA)
    lam_tab, e_tab = _astm_g173()
    lam = lam_tab.copy() if wavelength_m is None else as_float_array("wavelength_m", wavelength_m)
    if name == "planck_5778k":
        return lam, planck_solar_irradiance(lam)
    return lam, np.interp(lam, lam_tab, e_tab, left=0.0, right=0.0)


@functools.lru_cache(maxsize=1)
def _astm_g173() -> tuple[np.ndarray, np.ndarray]:
    """The ASTM G173-03 extraterrestrial table (m; W m^-2 m^-1), read once per process (read-only arrays: a
    radiometric budget asks for it several times, each band of a banded run again)."""
    ref = resources.files("satchain") / "data" / "astm_g173_etr.csv"
    with ref.open("r") as fh:
        table = np.loadtxt(fh, delimiter=",", comments="#")
    lam, e = table[:, 0] * 1e-9, table[:, 1] * 1e9  # nm -> m; per nm -> per m
    lam.flags.writeable = False
    e.flags.writeable = False
    return lam, e


def planck_spectral_radiance(wavelength_m, temperature_k: float):
    """Black-body spectral radiance ``B = 2 h c^2 / lambda^5 / (exp(h c / (lambda k T)) - 1)``.

    In W m^-2 sr^-1 m^-1; its integral over wavelength is ``sigma T^4 / pi`` (Stefan-Boltzmann).

    Examples
    --------
    >>> round(float(planck_spectral_radiance(5e-7, 5778.0)) * 1e-13, 4)  # W m^-2 sr^-1 m^-1
    2.6376
    """
    lam = as_float_array("wavelength_m", wavelength_m)
    t = check_positive("temperature_k", temperature_k)
    if np.any(lam <= 0):
        raise InputError("wavelength_m: must be > 0")
    x = H_J_S * C_M_PER_S / (lam * K_J_PER_K * t)
    with np.errstate(over="ignore"):
        return 2.0 * H_J_S * C_M_PER_S**2 / lam**5 / np.expm1(x)


def planck_solar_irradiance(wavelength_m, *, temperature_k: float = 5778.0, distance_m: float = AU_M):
    """Irradiance of a black-body Sun: ``E = pi B(lambda, T) (R_sun / d)^2`` (W m^-2 m^-1).

    A Lambertian sphere of radius ``R_sun`` seen from ``d``: its total is ``sigma T^4 (R_sun / d)^2``,
    1366.8 W/m^2 at 5778 K and 1 AU (the IAU 2015 nominal effective temperature, 5772 K, gives the
    nominal total solar irradiance, 1361 W/m^2).

    Examples
    --------
    >>> lam = np.linspace(1e-8, 1e-4, 200001)
    >>> round(float(np.trapezoid(planck_solar_irradiance(lam), lam)), 1)
    1366.8
    >>> round(float(np.trapezoid(planck_solar_irradiance(lam, temperature_k=5772.0), lam)))
    1361
    """
    d = check_positive("distance_m", distance_m)
    return math.pi * planck_spectral_radiance(wavelength_m, temperature_k) * (SUN_RADIUS_M / d) ** 2


# ---------------------------------------------------------------------------- sun to sensor
def atmosphere_transmissions(absorption: float, path: str = "both") -> tuple[float, float]:
    """One-pass transmission ``1 - absorption`` on the paths ``path`` names: ``(T_down, T_up)``.

    Examples
    --------
    >>> atmosphere_transmissions(0.23, "down")
    (0.77, 1.0)
    """
    a = check_range("illumination.atmosphere_absorption", absorption, 0.0, 1.0, hi_open=True)
    check_choice("illumination.atmosphere_path", path, ("both", "down", "up"))
    t = 1.0 - a
    return (t if path in ("both", "down") else 1.0, t if path in ("both", "up") else 1.0)


def surface_irradiance(solar_irradiance, *, sun_zenith_deg: float, transmission_down: float = 1.0):
    """Irradiance on horizontal ground: ``E = E0 cos(sza) T_down`` (direct beam only, no skylight).

    Examples
    --------
    >>> float(surface_irradiance(1000.0, sun_zenith_deg=60.0, transmission_down=0.77))
    385.0000000000001
    """
    sza = check_range("illumination.sun_zenith_deg", sun_zenith_deg, 0.0, 90.0, hi_open=True)
    t = check_range("transmission_down", transmission_down, 0.0, 1.0)
    return np.asarray(solar_irradiance, dtype=float) * math.cos(math.radians(sza)) * t


def lambertian_radiance(irradiance, *, reflectance: float):
    """Radiance leaving a Lambertian surface: ``L = rho E / pi`` (Schott 2007, sec. 3.2).

    Examples
    --------
    >>> round(float(lambertian_radiance(math.pi, reflectance=0.2)), 12)
    0.2
    """
    rho = check_range("illumination.reflectance", reflectance, 0.0, 1.0)
    return rho * np.asarray(irradiance, dtype=float) / math.pi


def toa_radiance(surface_radiance, *, transmission_up: float = 1.0, path_radiance=0.0):
    """Radiance at the top of the atmosphere: ``L_toa = L_surface T_up + L_path``.

    Examples
    --------
    >>> float(toa_radiance(10.0, transmission_up=0.77, path_radiance=1.0))
    8.7
    """
    t = check_range("transmission_up", transmission_up, 0.0, 1.0)
    return np.asarray(surface_radiance, dtype=float) * t + np.asarray(path_radiance, dtype=float)
