"""Radiometry: sun -> surface -> top of atmosphere -> focal plane -> electrons; noise and SNR.

The chain, spectrally (wavelength ``lambda`` in m, spectral quantities per metre of wavelength):

1. solar spectral irradiance at the top of the atmosphere ``E0(lambda)`` (W m^-2 m^-1): the ASTM G173-03
   extraterrestrial table shipped with satchain, or a 5778 K black body seen at 1 AU;
2. irradiance on a horizontal ground ``E = E0 cos(sza) T_down``;
3. radiance leaving a Lambertian surface of reflectance ``rho``: ``L_surface = rho E / pi``;
4. radiance at the top of the atmosphere ``L_toa = L_surface T_up + L_path``;
5. focal-plane irradiance by the camera equation ``E_fp = pi L_toa tau (1 - eps^2) / (4 F#^2)``;
6. electrons per pixel ``N = t A_pix integral E_fp QE lambda / (h c) dlambda`` per TDI stage, times stages.

``T_down`` / ``T_up`` are ``1 - atmosphere_absorption`` on the paths ``illumination.atmosphere_path`` names
(the reference paper: albedo 0.2, 23 % absorption, its Figure 2). Then the noise budget (shot, dark, read,
quantisation, PRNU; CCD- or CMOS-style accumulation over TDI stages), the SNR at a reflectance and the
*contrast* SNR of the GIQE (7 % and 15 % targets).

References: J. R. Schott, *Remote Sensing: The Image Chain Approach*, 2nd ed., Oxford 2007, ch. 3-5 and
13; R. D. Fiete, *Modeling the Imaging Chain of Digital Cameras*, SPIE 2010, ch. 5-6; G. C. Holst and
T. S. Lomheim, *CMOS/CCD Sensors and Camera Systems*, 2nd ed., SPIE 2011, ch. 4 and 6.

Examples
--------
>>> from satchain import load_preset
>>> r = radiometric_budget(load_preset("ankarasat3"))
>>> r.snr > 50, r.saturated
(True, False)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from importlib import resources
from typing import Any

import numpy as np
from scipy import constants as _c

from satchain._validate import as_float_array, check_choice, check_positive, check_range
from satchain.errors import ConfigError, InputError

__all__ = [
    "AU_M",
    "NoiseBudget",
    "RadiometryResult",
    "SOLAR_SPECTRA",
    "SUN_RADIUS_M",
    "atmosphere_transmissions",
    "band_radiance",
    "contrast_snr",
    "electrons_per_pixel",
    "focal_plane_irradiance",
    "lambertian_radiance",
    "noise_budget",
    "photon_radiance",
    "planck_solar_irradiance",
    "planck_spectral_radiance",
    "radiometric_budget",
    "signal_electrons",
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
GIQE_REFLECTANCES = (0.07, 0.15)


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
    ref = resources.files("satchain") / "data" / "astm_g173_etr.csv"
    with ref.open("r") as fh:
        table = np.loadtxt(fh, delimiter=",", comments="#")
    lam_tab, e_tab = table[:, 0] * 1e-9, table[:, 1] * 1e9  # nm -> m; per nm -> per m
    lam = lam_tab if wavelength_m is None else as_float_array("wavelength_m", wavelength_m)
    if name == "planck_5778k":
        return lam, planck_solar_irradiance(lam)
    return lam, np.interp(lam, lam_tab, e_tab, left=0.0, right=0.0)


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


# ---------------------------------------------------------------------------- noise
@dataclass(frozen=True)
class NoiseBudget:
    """Noise terms in electrons rms at one signal level, after TDI accumulation; ``total_e`` is their
    quadrature sum."""

    signal_e: float
    shot_e: float
    dark_e: float
    read_e: float
    quantisation_e: float
    prnu_e: float
    total_e: float

    @property
    def snr(self) -> float:
        return self.signal_e / self.total_e if self.total_e > 0 else math.inf

    def to_dict(self) -> dict[str, float]:
        return {
            "signal_e": self.signal_e,
            "shot_noise_e": self.shot_e,
            "dark_noise_e": self.dark_e,
            "read_noise_e": self.read_e,
            "quantisation_noise_e": self.quantisation_e,
            "prnu_noise_e": self.prnu_e,
            "total_noise_e": self.total_e,
            "snr": self.snr,
        }


def noise_budget(
    signal_e: float,
    *,
    stages: int = 1,
    integration_time_s: float = 0.0,
    read_noise_e: float = 0.0,
    dark_current_e_per_s: float = 0.0,
    readout: str = "ccd",
    full_well_e: float | None = None,
    bit_depth: int | None = None,
    prnu: float = 0.0,
) -> NoiseBudget:
    """Temporal noise of a TDI pixel whose accumulated signal is ``signal_e`` electrons.

    * shot: ``sqrt(signal)`` (Poisson);
    * dark: ``sqrt(i_dark t N)``, the shot noise of the dark charge over ``N`` stages;
    * read: ``sigma_read`` for ``readout="ccd"`` (charge summed in the charge domain, read once) or
      ``sqrt(N) sigma_read`` for ``"cmos"`` (digital TDI: every stage is read and the reads are summed;
      Holst & Lomheim 2011 sec. 6.7);
    * quantisation: ``q / sqrt(12)`` with ``q = full_well / 2^bits`` electrons per DN (the ADC range spans
      the full well), once for CCD, ``sqrt(N)`` times for CMOS digital TDI (every stage is digitised);
    * PRNU: ``prnu signal / sqrt(N)`` -- a gain spread between pixels, averaged over the ``N`` pixels a TDI
      column sums (0 unless given; it is fixed-pattern and removed by flat-fielding).

    The total is the quadrature sum (independent terms).

    Examples
    --------
    >>> nb = noise_budget(10000.0, stages=4, read_noise_e=30.0, readout="cmos")
    >>> nb.shot_e, nb.read_e, round(nb.total_e, 3)
    (100.0, 60.0, 116.619)
    """
    s = check_range("signal_e", signal_e, 0.0, None, error=InputError)
    n = int(check_range("detector.tdi_stages", stages, 1, None))
    t = check_range("integration_time_s", integration_time_s, 0.0, None)
    check_choice("detector.readout", readout, ("ccd", "cmos"))
    accum = math.sqrt(n) if readout == "cmos" else 1.0
    shot = math.sqrt(s)
    dark = math.sqrt(check_range("detector.dark_current_e_per_s", dark_current_e_per_s, 0.0, None) * t * n)
    read = check_range("detector.read_noise_e", read_noise_e, 0.0, None) * accum
    quant = 0.0
    if bit_depth is not None:
        if full_well_e is None:
            raise ConfigError(f"detector.bit_depth = {bit_depth!r} needs detector.full_well_e (e- per DN)")
        bits = int(check_range("detector.bit_depth", bit_depth, 1, 32))
        quant = check_positive("detector.full_well_e", full_well_e) / 2.0**bits / math.sqrt(12.0) * accum
    prnu_e = check_range("detector.prnu", prnu, 0.0, 1.0) * s / math.sqrt(n)
    total = math.sqrt(shot**2 + dark**2 + read**2 + quant**2 + prnu_e**2)
    return NoiseBudget(s, shot, dark, read, quant, prnu_e, total)


# ---------------------------------------------------------------------------- a whole system
@dataclass(frozen=True)
class RadiometryResult:
    """The radiometric budget of an ImagingSystem at one surface reflectance.

    Spectra are on ``wavelength_m`` (the solar table's grid, 280-4000 nm) in W m^-2 (sr^-1) m^-1;
    band quantities are integrated over ``band_m``. Electrons are per pixel; ``signal_e`` and ``noise`` are
    after accumulation over ``tdi_stages``. ``contrast_snr`` is the GIQE contrast SNR (see
    :func:`contrast_snr`).
    """

    wavelength_m: np.ndarray
    solar_irradiance_w_per_m2_per_m: np.ndarray
    radiance_surface_w_per_m2_sr_per_m: np.ndarray
    radiance_toa_w_per_m2_sr_per_m: np.ndarray
    band_m: tuple[float, float]
    reflectance: float
    sun_zenith_deg: float
    transmission_down: float
    transmission_up: float
    solar_spectrum: str
    solar_irradiance_band_w_per_m2: float
    radiance_surface_band_w_per_m2_sr: float
    radiance_toa_band_w_per_m2_sr: float
    focal_plane_irradiance_band_w_per_m2: float
    integration_time_s: float
    line_time_s: float
    tdi_stages: int
    readout: str
    electrons_per_stage_e: float
    signal_e: float
    noise: NoiseBudget
    snr: float
    full_well_e: float | None
    well_fill: float | None
    saturated: bool
    signal_7pct_e: float
    signal_15pct_e: float
    contrast_snr: float

    def to_dict(self, *, include_spectra: bool = False) -> dict[str, Any]:
        """JSON-ready dict; names carry their units. Spectra (per um) only with ``include_spectra``."""
        d: dict[str, Any] = {
            "band_m": list(self.band_m),
            "reflectance": self.reflectance,
            "sun_zenith_deg": self.sun_zenith_deg,
            "atmosphere_transmission_down": self.transmission_down,
            "atmosphere_transmission_up": self.transmission_up,
            "solar_spectrum": self.solar_spectrum,
            "solar_irradiance_band_w_per_m2": self.solar_irradiance_band_w_per_m2,
            "radiance_surface_band_w_per_m2_sr": self.radiance_surface_band_w_per_m2_sr,
            "radiance_toa_band_w_per_m2_sr": self.radiance_toa_band_w_per_m2_sr,
            "focal_plane_irradiance_band_w_per_m2": self.focal_plane_irradiance_band_w_per_m2,
            "integration_time_s": self.integration_time_s,
            "line_time_s": self.line_time_s,
            "tdi_stages": self.tdi_stages,
            "readout": self.readout,
            "electrons_per_stage_e": self.electrons_per_stage_e,
            "signal_e": self.signal_e,
            "noise": self.noise.to_dict(),
            "snr": self.snr,
            "full_well_e": self.full_well_e,
            "well_fill": self.well_fill,
            "saturated": self.saturated,
            "signal_7pct_e": self.signal_7pct_e,
            "signal_15pct_e": self.signal_15pct_e,
            "contrast_snr": self.contrast_snr,
        }
        if include_spectra:
            d["spectra"] = {
                "wavelength_m": self.wavelength_m.tolist(),
                "solar_irradiance_w_per_m2_per_um": spectral_per_m_to_per_um(
                    self.solar_irradiance_w_per_m2_per_m
                ).tolist(),
                "radiance_surface_w_per_m2_sr_per_um": spectral_per_m_to_per_um(
                    self.radiance_surface_w_per_m2_sr_per_m
                ).tolist(),
                "radiance_toa_w_per_m2_sr_per_um": spectral_per_m_to_per_um(
                    self.radiance_toa_w_per_m2_sr_per_m
                ).tolist(),
            }
        return d


def _band_grid(lam: np.ndarray, band_m: tuple[float, float]) -> np.ndarray:
    lo, hi = band_m
    inside = (lam > lo * (1 + 1e-12)) & (lam < hi * (1 - 1e-12))  # table points on an edge count once
    return np.concatenate([[lo], lam[inside], [hi]])


def _spectra(system, reflectance: float) -> dict[str, Any]:
    """Solar, surface and TOA spectra of ``system`` on the solar table grid."""
    il = system.illumination
    lam, e0 = solar_spectrum(il.solar_spectrum)
    t_down, t_up = atmosphere_transmissions(il.atmosphere_absorption, il.atmosphere_path)
    e_ground = surface_irradiance(e0, sun_zenith_deg=il.sun_zenith_deg, transmission_down=t_down)
    l_surface = lambertian_radiance(e_ground, reflectance=reflectance)
    l_path = spectral_per_um_to_per_m(il.path_radiance_w_per_m2_sr_per_um)
    l_toa = toa_radiance(l_surface, transmission_up=t_up, path_radiance=l_path)
    return dict(lam=lam, e0=e0, l_surface=l_surface, l_toa=l_toa, t_down=t_down, t_up=t_up)


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


def _stage_electrons(system, spectral_toa_radiance: np.ndarray, lam: np.ndarray) -> float:
    """Electrons per pixel per TDI stage from a TOA spectral radiance, over the system's band."""
    o, det = system.optics, system.detector
    lb = _band_grid(lam, system.radiometry.band_m)
    e_fp = focal_plane_irradiance(
        np.interp(lb, lam, spectral_toa_radiance),
        f_number=o.f_number,
        transmission=o.transmission,
        obscuration_ratio=o.obscuration_ratio,
    )
    return electrons_per_pixel(
        lb,
        e_fp,
        pixel_area_m2=det.active_area_m2,
        integration_time_s=system.integration_time_s,
        qe=det.qe_at(lb),
    )


def signal_electrons(system, reflectance=None) -> np.ndarray | float:
    """Accumulated signal (electrons per pixel, all TDI stages) for surface reflectance(s).

    Linear in reflectance plus the path-radiance term: ``N(rho) = rho N_1 + N_path``. Default: the
    system's ``illumination.reflectance``.

    Examples
    --------
    >>> from satchain import load_preset
    >>> s = load_preset("ankarasat3")
    >>> n = signal_electrons(s, [0.1, 0.2])
    >>> round(float(n[1] / n[0]), 12)
    2.0
    """
    rho = system.illumination.reflectance if reflectance is None else reflectance
    r = as_float_array("reflectance", rho)
    if np.any((r < 0) | (r > 1)):
        raise InputError(f"reflectance = {rho!r}: must be in [0, 1]")
    sp = _spectra(system, 1.0)
    il = system.illumination
    per_rho = _stage_electrons(system, sp["l_surface"] * sp["t_up"], sp["lam"])
    path = 0.0
    if il.path_radiance_w_per_m2_sr_per_um > 0:
        flat = np.full_like(sp["lam"], float(spectral_per_um_to_per_m(il.path_radiance_w_per_m2_sr_per_um)))
        path = _stage_electrons(system, flat, sp["lam"])
    n = (r * per_rho + path) * system.detector.tdi_stages
    return float(n) if n.ndim == 0 else n


def _noise(system, signal_e: float) -> NoiseBudget:
    det = system.detector
    return noise_budget(
        signal_e,
        stages=det.tdi_stages,
        integration_time_s=system.integration_time_s,
        read_noise_e=det.read_noise_e,
        dark_current_e_per_s=det.dark_current_e_per_s,
        readout=det.readout,
        full_well_e=det.full_well_e,
        bit_depth=det.bit_depth,
        prnu=det.prnu,
    )


def snr_vs_reflectance(system, reflectances) -> np.ndarray:
    """SNR (signal / total noise) of uniform surfaces of the given reflectances.

    Examples
    --------
    >>> from satchain import load_preset
    >>> snr = snr_vs_reflectance(load_preset("ankarasat3"), [0.05, 0.2, 0.5])
    >>> bool(snr[0] < snr[1] < snr[2])
    True
    """
    n = np.atleast_1d(signal_electrons(system, reflectances))
    return np.array([_noise(system, float(v)).snr for v in n])


def contrast_snr(system) -> float:
    """The GIQE contrast SNR: ``(S_15% - S_7%) / sigma(S_15%)``.

    The signal difference between Lambertian targets of 15 % and 7 % reflectance, divided by the total rms
    noise at the brighter (15 %) level -- the definition of the GIQE 3/4 (Leachtenauer et al. 1997,
    Applied Optics 36(32), "SNR: signal-to-noise ratio for a 7 % and 15 % reflectance difference") as
    implemented in the US government's IBSM / AFRL pyBSM (``photon_detector_SNR``: noise of the larger of
    target and background signal), and kept by GIQE 5 (NGA 2015: "contrast SNR ... as defined for GIQE 3").
    The targets are lit and seen through the system's own ``[illumination]`` (sun angle, atmosphere),
    not the GIQE's original standard conditions. No MTFC noise gain is applied here: GIQE 3/4 divide
    ``G / SNR``; GIQE 5 assumes its own optimal processing.

    Examples
    --------
    >>> from satchain import load_preset
    >>> 20 < contrast_snr(load_preset("ankarasat3")) < 500
    True
    """
    s7, s15 = np.atleast_1d(signal_electrons(system, list(GIQE_REFLECTANCES)))
    return float((s15 - s7) / _noise(system, float(s15)).total_e)


def radiometric_budget(system, *, reflectance: float | None = None) -> RadiometryResult:
    """The whole radiometric chain of ``system`` at a surface reflectance (default: the system's).

    Sun -> ground -> Lambertian surface -> TOA -> camera equation -> electrons -> noise -> SNR; plus full-well
    check and the GIQE contrast SNR. Saturation: the accumulated charge (CCD-style TDI) or one stage's
    charge (CMOS digital TDI) reaches ``detector.full_well_e``.

    Examples
    --------
    >>> from satchain import load_preset
    >>> r = radiometric_budget(load_preset("ankarasat3"), reflectance=0.2)
    >>> round(r.radiance_toa_band_w_per_m2_sr / r.radiance_surface_band_w_per_m2_sr, 2)
    0.77
    """
    il, det = system.illumination, system.detector
    rho = il.reflectance if reflectance is None else check_range("reflectance", reflectance, 0.0, 1.0)
    sp = _spectra(system, rho)
    lam, band = sp["lam"], system.radiometry.band_m
    signal = float(signal_electrons(system, rho))
    per_stage = signal / det.tdi_stages
    noise = _noise(system, signal)
    fill = None
    if det.full_well_e is not None:
        fill = (signal if det.readout == "ccd" else per_stage) / det.full_well_e
    s7, s15 = np.atleast_1d(signal_electrons(system, list(GIQE_REFLECTANCES)))
    l_toa_band = band_radiance(lam, sp["l_toa"], band)
    o = system.optics
    e_fp = focal_plane_irradiance(
        l_toa_band, f_number=o.f_number, transmission=o.transmission, obscuration_ratio=o.obscuration_ratio
    )
    return RadiometryResult(
        wavelength_m=lam,
        solar_irradiance_w_per_m2_per_m=sp["e0"],
        radiance_surface_w_per_m2_sr_per_m=sp["l_surface"],
        radiance_toa_w_per_m2_sr_per_m=sp["l_toa"],
        band_m=tuple(band),
        reflectance=rho,
        sun_zenith_deg=il.sun_zenith_deg,
        transmission_down=sp["t_down"],
        transmission_up=sp["t_up"],
        solar_spectrum=il.solar_spectrum,
        solar_irradiance_band_w_per_m2=band_radiance(lam, sp["e0"], band),
        radiance_surface_band_w_per_m2_sr=band_radiance(lam, sp["l_surface"], band),
        radiance_toa_band_w_per_m2_sr=l_toa_band,
        focal_plane_irradiance_band_w_per_m2=float(e_fp),
        integration_time_s=system.integration_time_s,
        line_time_s=system.line_time_s,
        tdi_stages=det.tdi_stages,
        readout=det.readout,
        electrons_per_stage_e=per_stage,
        signal_e=signal,
        noise=noise,
        snr=noise.snr,
        full_well_e=det.full_well_e,
        well_fill=fill,
        saturated=bool(fill is not None and fill >= 1.0),
        signal_7pct_e=float(s7),
        signal_15pct_e=float(s15),
        contrast_snr=float((s15 - s7) / _noise(system, float(s15)).total_e),
    )
