"""The radiometric budget of a whole :class:`~satchain.config.system.ImagingSystem`: signal, noise, SNR, GIQE SNR.

Chains :mod:`satchain.radiometry.source` (sun, atmosphere, surface), :mod:`satchain.radiometry.focal_plane`
(camera equation, electrons) and :mod:`satchain.radiometry.noise` over the system's band, stages and
detector. Part of :mod:`satchain.radiometry`, which re-exports every public name.

Examples
--------
>>> from satchain import load_preset
>>> r = radiometric_budget(load_preset("ankarasat3"))
>>> r.snr > 50, r.saturated
(True, False)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TypedDict

import numpy as np

from satchain._validate import as_float_array, check_range
from satchain.errors import InputError
from satchain.radiometry.focal_plane import _band_grid, band_radiance, electrons_per_pixel, focal_plane_irradiance
from satchain.radiometry.noise import NoiseBudget, noise_budget
from satchain.radiometry.source import (
    atmosphere_transmissions,
    lambertian_radiance,
    solar_spectrum,
    spectral_per_m_to_per_um,
    spectral_per_um_to_per_m,
    surface_irradiance,
    toa_radiance,
)

if TYPE_CHECKING:
    from satchain.config.system import ImagingSystem

__all__ = [
    "GIQE_REFLECTANCES",
    "RadiometryResult",
    "contrast_snr",
    "radiometric_budget",
    "signal_electrons",
    "snr_vs_reflectance",
]

GIQE_REFLECTANCES = (0.07, 0.15)


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


def _spectra(system: ImagingSystem, reflectance: float) -> dict[str, Any]:
    """Solar, surface and TOA spectra of ``system`` on the solar table grid."""
    il = system.illumination
    lam, e0 = solar_spectrum(il.solar_spectrum)
    t_down, t_up = atmosphere_transmissions(il.atmosphere_absorption, il.atmosphere_path)
    e_ground = surface_irradiance(e0, sun_zenith_deg=il.sun_zenith_deg, transmission_down=t_down)
    l_surface = lambertian_radiance(e_ground, reflectance=reflectance)
    l_path = spectral_per_um_to_per_m(il.path_radiance_w_per_m2_sr_per_um)
    l_toa = toa_radiance(l_surface, transmission_up=t_up, path_radiance=l_path)
    return dict(lam=lam, e0=e0, l_surface=l_surface, l_toa=l_toa, t_down=t_down, t_up=t_up)


def _stage_electrons(system: ImagingSystem, spectral_toa_radiance: np.ndarray, lam: np.ndarray) -> float:
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


def signal_electrons(system: ImagingSystem, reflectance=None) -> np.ndarray | float:
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


def _noise(system: ImagingSystem, signal_e: float) -> NoiseBudget:
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


def snr_vs_reflectance(system: ImagingSystem, reflectances) -> np.ndarray:
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


def contrast_snr(system: ImagingSystem) -> float:
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


def radiometric_budget(system: ImagingSystem, *, reflectance: float | None = None) -> RadiometryResult:
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
    signal = float(signal_electrons(system, rho))
    noise = _noise(system, signal)
    s7, s15 = np.atleast_1d(signal_electrons(system, list(GIQE_REFLECTANCES)))
    return RadiometryResult(
        wavelength_m=sp["lam"],
        solar_irradiance_w_per_m2_per_m=sp["e0"],
        radiance_surface_w_per_m2_sr_per_m=sp["l_surface"],
        radiance_toa_w_per_m2_sr_per_m=sp["l_toa"],
        band_m=system.radiometry.band_m,
        reflectance=rho,
        sun_zenith_deg=il.sun_zenith_deg,
        transmission_down=sp["t_down"],
        transmission_up=sp["t_up"],
        solar_spectrum=il.solar_spectrum,
        **_band_values(system, sp),
        integration_time_s=system.integration_time_s,
        line_time_s=system.line_time_s,
        tdi_stages=det.tdi_stages,
        readout=det.readout,
        electrons_per_stage_e=signal / det.tdi_stages,
        signal_e=signal,
        noise=noise,
        snr=noise.snr,
        full_well_e=det.full_well_e,
        **_well_fill(system, signal),
        signal_7pct_e=float(s7),
        signal_15pct_e=float(s15),
        contrast_snr=float((s15 - s7) / _noise(system, float(s15)).total_e),
    )


class _BandValues(TypedDict):
    """The band-integrated fields of :class:`RadiometryResult`."""

    solar_irradiance_band_w_per_m2: float
    radiance_surface_band_w_per_m2_sr: float
    radiance_toa_band_w_per_m2_sr: float
    focal_plane_irradiance_band_w_per_m2: float


def _band_values(system: ImagingSystem, sp: dict[str, Any]) -> _BandValues:
    """The band-integrated quantities of :class:`RadiometryResult` from the spectra of :func:`_spectra`."""
    lam, band, o = sp["lam"], system.radiometry.band_m, system.optics
    l_toa_band = band_radiance(lam, sp["l_toa"], band)
    e_fp = focal_plane_irradiance(
        l_toa_band, f_number=o.f_number, transmission=o.transmission, obscuration_ratio=o.obscuration_ratio
    )
    return {
        "solar_irradiance_band_w_per_m2": band_radiance(lam, sp["e0"], band),
        "radiance_surface_band_w_per_m2_sr": band_radiance(lam, sp["l_surface"], band),
        "radiance_toa_band_w_per_m2_sr": l_toa_band,
        "focal_plane_irradiance_band_w_per_m2": float(e_fp),
    }


def _well_fill(system: ImagingSystem, signal_e: float) -> dict[str, Any]:
    """``well_fill`` (None without a full well) and ``saturated``: the accumulated charge (CCD) or one stage's
    charge (CMOS digital TDI) over ``detector.full_well_e``."""
    det = system.detector
    if det.full_well_e is None:
        return {"well_fill": None, "saturated": False}
    fill = (signal_e if det.readout == "ccd" else signal_e / det.tdi_stages) / det.full_well_e
    return {"well_fill": fill, "saturated": bool(fill >= 1.0)}
