"""The light sections of an ImagingSystem: ``[radiometry]`` (spectral band, exposure), ``[illumination]`` (sun,
surface, path radiance), ``[atmosphere]`` (atmospheric blur) and ``[[bands]]`` (the bands of a multiband camera).
:mod:`satchain.config.sections` re-exports them beside the geometric sections (orbit, optics, detector, motion)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, field_validator, model_validator

from satchain.config._base import _Frozen, schema_bounds

__all__ = ["Atmosphere", "Band", "Illumination", "Radiometry"]


class Radiometry(_Frozen):
    """Spectral band and exposure for the radiometric budget (:mod:`satchain.radiometry`).

    ``band_m`` is the sensor's spectral band (the signal is integrated over it); it is distinct from
    ``optics.wavelengths_m``, the wavelengths at which the polychromatic MTF is evaluated. The default band,
    450-900 nm, is a typical silicon panchromatic band. ``integration_time_s`` is the exposure of one TDI
    stage; when omitted it is the line time, ``gsd_alt_m / ground_speed_m_per_s``.
    """

    band_m: tuple[float, float] = Field(
        default=(4.5e-7, 9.0e-7),
        description="spectral band [min, max], m, over which the signal is integrated; "
        "2.8e-07 <= min < max <= 4e-06 m (the solar table's 280-4000 nm)",
        json_schema_extra=schema_bounds(items={"minimum": 2.8e-7, "maximum": 4.0e-6}),
    )
    integration_time_s: float | None = Field(
        default=None,
        gt=0,
        le=10,
        description="exposure per TDI stage; default: the line time, gsd_alt_m / ground speed",
    )

    @field_validator("band_m")
    @classmethod
    def _band(cls, v: tuple[float, float]) -> tuple[float, float]:
        lo, hi = v
        if not (2.8e-7 <= lo < hi <= 4.0e-6):
            raise ValueError(
                f"must be [min, max] with 2.8e-07 <= min < max <= 4e-06 m (the solar table spans "
                f"280-4000 nm), got {list(v)}"
            )
        return v


class Atmosphere(_Frozen):
    """Atmospheric blur (:mod:`satchain.tf.atmosphere`); off by default (the reference paper has none)."""

    turbulence: bool = Field(default=False, description="include the turbulence OTF")
    r0_m: float | None = Field(
        default=None,
        gt=0,
        description="Fried parameter of the turbulence OTF; default: from the Hufnagel-Valley profile "
        "(hv_wind_m_per_s, hv_ground_cn2), looking down from orbit.altitude_m",
    )
    hv_wind_m_per_s: float = Field(
        default=21.0,
        ge=0,
        le=200,
        description="rms upper-atmosphere wind speed of the Hufnagel-Valley Cn2 profile (21: HV 5/7); sets r0 when "
        "turbulence is on and r0_m is not given",
    )
    hv_ground_cn2: float = Field(
        default=1.7e-14,
        ge=0,
        le=1e-10,
        description="ground-level refractive-index structure constant Cn2 of the Hufnagel-Valley profile, m^-2/3 "
        "(1.7e-14: HV 5/7); sets r0 as hv_wind_m_per_s does",
    )
    view_zenith_deg: float = Field(
        default=0.0,
        ge=0,
        le=80,
        description="zenith angle of the path through the turbulence (it lengthens by sec(zenith)); used for r0 only, "
        "not taken from orbit.off_nadir_deg",
    )
    aerosol_scattered_fraction: float = Field(
        default=0.0,
        ge=0,
        lt=1,
        description="fraction s of the signal that aerosols scatter into a wide adjacency PSF (dimensionless): the "
        "OTF (1 - s) + s (1 + (2 pi L f)^2)^-1.5 on ground frequencies, a contrast loss s; 0: off",
    )
    aerosol_psf_scale_m: float = Field(
        default=200.0,
        gt=0,
        le=1e5,
        description="scale L of the aerosol adjacency PSF exp(-r / L) on the ground",
    )


class Illumination(_Frozen):
    """Sun, surface and atmosphere for the radiometric budget (:mod:`satchain.radiometry`).

    ``atmosphere_absorption`` is the fraction absorbed on *one* pass through the atmosphere (transmission
    ``T = 1 - absorption``); ``atmosphere_path`` says where it applies: ``"down"`` (sun to ground: lowers
    the surface radiance), ``"up"`` (ground to sensor) or ``"both"``. The default -- 23 % on both paths --
    is the reading of the reference paper's Figure 2: its "surface" curve is the radiance leaving an
    albedo-0.2 surface lit through a 23 %-absorbing atmosphere, and its TOA curve (MODTRAN "ground
    reflected") is that radiance attenuated again on the way up. ``path_radiance_w_per_m2_sr_per_um`` is a
    spectrally flat radiance added at the top of the atmosphere (default 0, as MODTRAN's ground-reflected
    term excludes path radiance).
    """

    sun_zenith_deg: float = Field(
        default=30.0,
        ge=0,
        lt=90,
        description="angle of the sun from the local vertical at the scene: the surface irradiance goes with "
        "cos(sun_zenith)",
    )
    reflectance: float = Field(
        default=0.2,
        ge=0,
        le=1,
        description="Lambertian surface reflectance (albedo, dimensionless) at which the budget gives the signal "
        "and SNR",
    )
    atmosphere_absorption: float = Field(
        default=0.23,
        ge=0,
        lt=1,
        description="absorbed fraction per pass through the atmosphere (dimensionless; transmission 1 - "
        "absorption), on the path(s) atmosphere_path names",
    )
    atmosphere_path: Literal["both", "down", "up"] = Field(
        default="both",
        description="where atmosphere_absorption applies: 'down' (sun to ground: lowers the surface radiance), "
        "'up' (ground to sensor) or 'both'",
    )
    path_radiance_w_per_m2_sr_per_um: float = Field(
        default=0.0,
        ge=0,
        le=1e4,
        description="spectrally flat path radiance added at the top of the atmosphere: signal and shot noise "
        "without contrast; default 0 (MODTRAN's ground-reflected term has none)",
    )
    solar_spectrum: Literal["astm_g173_etr", "planck_5778k"] = Field(
        default="astm_g173_etr",
        description="the sun's spectral irradiance at the top of the atmosphere: 'astm_g173_etr' (the ASTM G173-03 "
        "extraterrestrial table, 280-4000 nm) or 'planck_5778k' (a 5778 K black body)",
    )


class Band(_Frozen):
    """One spectral band of a multiband camera (a ``[[bands]]`` table of a system file), in the order of the
    bands of a multiband input: ``satchain simulate`` forms band i of the input with the system's optics at
    this band's ``wavelengths_m`` (and ``wavelength_weights``) and, when given, integrates its signal over
    ``band_m`` instead of ``radiometry.band_m``. Without ``[[bands]]`` every band uses the system's own optics.

    Examples
    --------
    >>> Band(name="red", wavelengths_m=(6.5e-7,)).name
    'red'
    """

    name: str = Field(default="", max_length=64, description="the band's name, e.g. 'red' (a label)")
    wavelengths_m: tuple[float, ...] = Field(
        min_length=1,
        description="effective wavelengths of the band, m: the optics' wavelengths_m for this band, each in "
        "[1e-08, 0.0001] m",
        json_schema_extra=schema_bounds(items={"minimum": 1e-8, "maximum": 1e-4}),
    )
    wavelength_weights: tuple[float, ...] | None = Field(
        default=None,
        description="relative weight of each of wavelengths_m (dimensionless): one per wavelength, each >= 0, a "
        "positive sum; default: equal weights",
        json_schema_extra=schema_bounds(items={"minimum": 0}),
    )
    band_m: tuple[float, float] | None = Field(
        default=None,
        description="spectral band [min, max], m, over which this band's signal is integrated (instead of "
        "radiometry.band_m); 2.8e-07 <= min < max <= 4e-06 m",
        json_schema_extra=schema_bounds(items={"minimum": 2.8e-7, "maximum": 4.0e-6}),
    )

    @model_validator(mode="after")
    def _check(self) -> Band:
        for i, lam in enumerate(self.wavelengths_m):
            if not (1e-8 <= lam <= 1e-4):
                raise ValueError(f"wavelengths_m[{i}] = {lam!r}: must be in [1e-08, 0.0001] m (10 nm to 100 um)")
        w = self.wavelength_weights
        if w is not None and (len(w) != len(self.wavelengths_m) or min(w) < 0 or sum(w) <= 0):
            raise ValueError(
                f"wavelength_weights = {list(w)!r}: must give one weight >= 0 per wavelength "
                f"({len(self.wavelengths_m)}), with a positive sum"
            )
        if self.band_m is not None and not (2.8e-7 <= self.band_m[0] < self.band_m[1] <= 4.0e-6):
            raise ValueError(f"band_m = {list(self.band_m)!r}: must be [min, max] with 2.8e-07 <= min < max <= 4e-06 m "
                             "(the solar table spans 280-4000 nm)")  # fmt: skip
        return self
