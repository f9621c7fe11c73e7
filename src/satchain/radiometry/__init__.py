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

Modules, one per stretch of the chain (every public name is re-exported here): :mod:`.source` (1-4: the sun,
the atmosphere, the surface), :mod:`.focal_plane` (5-6: camera equation, electrons), :mod:`.noise` (the
noise budget) and :mod:`.budget` (the chain for a whole ImagingSystem: signal, SNR, GIQE contrast SNR).

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

from satchain.radiometry.budget import (
    GIQE_REFLECTANCES,
    RadiometryResult,
    contrast_snr,
    radiometric_budget,
    signal_electrons,
    snr_vs_reflectance,
)
from satchain.radiometry.focal_plane import band_radiance, electrons_per_pixel, focal_plane_irradiance
from satchain.radiometry.noise import NoiseBudget, noise_budget
from satchain.radiometry.source import (
    AU_M,
    C_M_PER_S,
    H_J_S,
    K_J_PER_K,
    SIGMA_W_PER_M2_K4,
    SOLAR_SPECTRA,
    SUN_RADIUS_M,
    atmosphere_transmissions,
    lambertian_radiance,
    photon_radiance,
    planck_solar_irradiance,
    planck_spectral_radiance,
    solar_spectrum,
    spectral_per_m_to_per_um,
    spectral_per_um_to_per_m,
    surface_irradiance,
    toa_radiance,
)

__all__ = [
    "AU_M",
    "C_M_PER_S",
    "GIQE_REFLECTANCES",
    "H_J_S",
    "K_J_PER_K",
    "SIGMA_W_PER_M2_K4",
    "SOLAR_SPECTRA",
    "SUN_RADIUS_M",
    "NoiseBudget",
    "RadiometryResult",
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
    "snr_vs_reflectance",
    "solar_spectrum",
    "spectral_per_m_to_per_um",
    "spectral_per_um_to_per_m",
    "surface_irradiance",
    "toa_radiance",
]
