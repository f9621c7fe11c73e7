"""The light sections of an ImagingSystem: ``[radiometry]`` (spectral band, exposure), ``[illumination]`` (sun,
surface, path radiance), ``[atmosphere]`` (atmospheric blur) and ``[[bands]]`` (the bands of a multiband camera).
:mod:`satchain.config.sections` re-exports them beside the geometric sections (orbit, optics, detector, motion)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Literal

from pydantic import Field, field_validator, model_validator

from satchain.config._base import _Frozen, schema_bounds
from satchain.config.response import (
    SuperGaussianResponse,
    TabulatedResponse,
    response_quadrature,
)
from satchain.errors import SatchainIOError

__all__ = ["Atmosphere", "Band", "GaussianResponse", "Illumination", "Radiometry", "read_response_csv"]


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


class GaussianResponse(_Frozen):
    """A band's spectral response as a (super-)Gaussian of peak 1
    (:class:`satchain.config.response.SuperGaussianResponse`)."""

    center_m: float = Field(ge=2.8e-7, le=4.0e-6, description="centre wavelength of the band's spectral response")
    fwhm_m: float = Field(gt=0, le=3.0e-6, description="full width at half maximum of the band's spectral response")
    order: int = Field(
        default=1,
        ge=1,
        le=32,
        description="super-Gaussian order n (count): exp(-ln2 |2 (lambda - center) / fwhm|^(2 n)); 1: a Gaussian; "
        "higher: a flatter top and steeper edges (an interference filter), the same FWHM",
    )

    @model_validator(mode="after")
    def _inside_solar_table(self) -> GaussianResponse:
        lo, hi = self.curve.support_m
        if not (2.8e-7 <= lo and hi <= 4.0e-6):
            raise ValueError(
                f"center_m = {self.center_m!r}, fwhm_m = {self.fwhm_m!r}: the response spans {lo:.4g}-{hi:.4g} m (to "
                "1e-3 of its peak); it must lie within 2.8e-07-4e-06 m (the solar table)"
            )
        return self

    @property
    def curve(self) -> SuperGaussianResponse:
        return SuperGaussianResponse(self.center_m, self.fwhm_m, self.order)


class Band(_Frozen):
    """One spectral band of a multiband camera (a ``[[bands]]`` table of a system file), in the order of the
    bands of a multiband input: ``ImagingSystem.for_band(i)`` is the system that forms band i.

    The band's spectrum is given one way: ``wavelengths_m`` (and ``wavelength_weights``; ``band_m`` for the signal)
    as before, or a spectral ``response`` (a Gaussian or super-Gaussian), or a table (``response_file``, or inline
    ``response_wavelengths_m`` / ``response_values``). A response sets the optics' wavelengths and weights (a
    quadrature of it over its support), the radiometric band (its support) and multiplies the QE. The other keys
    replace the system detector's own for this band (``pitch_m``: a square pixel); ``offset_alt_mm`` /
    ``offset_act_mm`` place the band on the focal plane relative to the system's own detector. Without
    ``[[bands]]`` every band uses the system's own optics.

    Examples
    --------
    >>> Band(name="red", wavelengths_m=(6.5e-7,)).name
    'red'
    >>> round(Band(name="red", response={"center_m": 6.6e-7, "fwhm_m": 6e-8}).center_wavelength_m * 1e9, 3)
    660.0
    """

    name: str = Field(default="", max_length=64, description="the band's name, e.g. 'red' (a label; unique)")
    wavelengths_m: tuple[float, ...] | None = Field(
        default=None,
        min_length=1,
        description="effective wavelengths of the band, m: the optics' wavelengths_m for this band, each in "
        "[1e-08, 0.0001] m; or give a response",
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
        "radiometry.band_m); 2.8e-07 <= min < max <= 4e-06 m; with a response: its support",
        json_schema_extra=schema_bounds(items={"minimum": 2.8e-7, "maximum": 4.0e-6}),
    )
    response: GaussianResponse | None = Field(
        default=None,
        description="[bands.response]: the band's spectral response as a (super-)Gaussian {center_m, fwhm_m, order}",
    )
    response_file: str | None = Field(
        default=None,
        description="a CSV table of the band's spectral response (header wavelength_m,response; wavelengths "
        "increasing; response in [0, 1], dimensionless), relative to the system file; read into "
        "response_wavelengths_m / response_values when the system loads",
    )
    response_wavelengths_m: tuple[float, ...] | None = Field(
        default=None,
        description="wavelengths of a tabulated response (>= 2, strictly increasing, in [2.8e-07, 4e-06] m)",
        json_schema_extra=schema_bounds(items={"minimum": 2.8e-7, "maximum": 4.0e-6}),
    )
    response_values: tuple[float, ...] | None = Field(
        default=None,
        description="the tabulated response at response_wavelengths_m (dimensionless, in [0, 1]: the filter's "
        "transmission; the QE multiplies it)",
        json_schema_extra=schema_bounds(items={"minimum": 0, "maximum": 1}),
    )
    qe: float | tuple[float, ...] | None = Field(
        default=None,
        description="this band's quantum efficiency, e-/photon (dimensionless): a number in (0, 1] or a table on "
        "qe_wavelengths_m; default: detector.qe",
        json_schema_extra=schema_bounds(
            number={"exclusiveMinimum": 0, "maximum": 1}, items={"minimum": 0, "maximum": 1}
        ),
    )
    qe_wavelengths_m: tuple[float, ...] | None = Field(
        default=None,
        description="wavelengths of this band's qe table: one per value (>= 2), strictly increasing, in "
        "[1e-08, 0.0001] m",
        json_schema_extra=schema_bounds(items={"minimum": 1e-8, "maximum": 1e-4}),
    )
    pitch_m: float | None = Field(
        default=None, gt=0, le=1e-3, description="this band's (square) pixel pitch; default: the detector's"
    )
    active_width_m: float | None = Field(
        default=None,
        gt=0,
        le=1e-3,
        description="width of this band's (square) photosensitive area, <= its pitch; default: the detector's "
        "fraction of its pitch",
    )
    tdi_stages: int | None = Field(
        default=None, ge=1, le=1024, description="this band's number of TDI stages (count); default: the detector's"
    )
    offset_alt_mm: float = Field(
        default=0.0,
        ge=-1000,
        le=1000,
        description="along-track position of the band's array on the focal plane relative to the system's own "
        "detector (positive: the image reaches it later, so it sees the same ground offset / image speed later)",
    )
    offset_act_mm: float = Field(
        default=0.0,
        ge=-1000,
        le=1000,
        description="across-track position of the band's array on the focal plane relative to the system's own "
        "detector",
    )
    registration_offset_px: tuple[float, float] = Field(
        default=(0.0, 0.0),
        description="an injected misregistration [ALT, ACT] of this band, in its own pixels (tests, studies)",
        json_schema_extra=schema_bounds(items={"minimum": -1000, "maximum": 1000}),
    )

    @model_validator(mode="before")
    @classmethod
    def _read_table(cls, data: Any) -> Any:
        if (
            isinstance(data, dict)
            and data.get("response_file") is not None
            and ("response_wavelengths_m" not in data and "response_values" not in data)
        ):
            data = dict(data)
            data["response_wavelengths_m"], data["response_values"] = read_response_csv(data["response_file"])
        return data

    @model_validator(mode="after")
    def _check(self) -> Band:
        ways = [k for k in ("wavelengths_m", "response", "response_values") if getattr(self, k) is not None]
        if len(ways) != 1:
            given = " and ".join(ways) if ways else "none"
            raise ValueError(f"give one of wavelengths_m, response or response_file (a table); got {given}")
        if self.wavelengths_m is not None:
            _check_wavelengths(self.wavelengths_m, self.wavelength_weights)
        elif self.wavelength_weights is not None or self.band_m is not None:
            key = "wavelength_weights" if self.wavelength_weights is not None else "band_m"
            raise ValueError(f"{key} = {list(getattr(self, key))!r}: a band with a response takes its weights and "
                             "band from the response; give one or the other")  # fmt: skip
        if self.response_values is not None or self.response_wavelengths_m is not None:
            _check_table(self.response_wavelengths_m, self.response_values, self.response_file)
        if self.band_m is not None and not (2.8e-7 <= self.band_m[0] < self.band_m[1] <= 4.0e-6):
            raise ValueError(f"band_m = {list(self.band_m)!r}: must be [min, max] with 2.8e-07 <= min < max <= 4e-06 m "
                             "(the solar table spans 280-4000 nm)")  # fmt: skip
        _check_qe(self.qe, self.qe_wavelengths_m)
        if self.active_width_m is not None and self.pitch_m is not None and self.active_width_m > self.pitch_m:
            raise ValueError(f"active_width_m = {self.active_width_m!r}: must be <= pitch_m ({self.pitch_m!r})")
        for i, v in enumerate(self.registration_offset_px):
            if not (math.isfinite(v) and abs(v) <= 1000):
                raise ValueError(f"registration_offset_px[{i}] = {v!r}: must be finite, within +-1000 px")
        return self

    # ----------------------------------------------------------------- derived
    @property
    def spectral_response(self) -> SuperGaussianResponse | TabulatedResponse | None:
        """The band's response curve, or None for a band given by its wavelengths."""
        if self.response is not None:
            return self.response.curve
        if self.response_values is not None and self.response_wavelengths_m is not None:
            return TabulatedResponse(self.response_wavelengths_m, self.response_values)
        return None

    def optics_wavelengths(self) -> tuple[tuple[float, ...], tuple[float, ...] | None]:
        """The optics' wavelengths and weights for this band: ``wavelengths_m`` as given, or the quadrature of the
        response (:data:`RESPONSE_NODES` nodes)."""
        r = self.spectral_response
        if r is None:
            assert self.wavelengths_m is not None  # _check: one of the ways
            return self.wavelengths_m, self.wavelength_weights
        lam, w = response_quadrature(r, RESPONSE_NODES)
        return tuple(float(x) for x in lam), tuple(float(x / w.sum()) for x in w)

    @property
    def radiometric_band_m(self) -> tuple[float, float] | None:
        """``band_m``, or the response's support; None: the system's ``radiometry.band_m``."""
        r = self.spectral_response
        return self.band_m if r is None else r.support_m

    @property
    def center_wavelength_m(self) -> float:
        """The centroid of the band: of its response, else the weighted mean of its wavelengths."""
        lam, w = self.optics_wavelengths()
        weights = [1.0] * len(lam) if w is None else list(w)
        return sum(a * b for a, b in zip(lam, weights, strict=True)) / sum(weights)


#: Nodes of the quadrature of a band's response (its optics wavelengths).
RESPONSE_NODES = 11


def _check_wavelengths(lam: tuple[float, ...], w: tuple[float, ...] | None) -> None:
    for i, x in enumerate(lam):
        if not (1e-8 <= x <= 1e-4):
            raise ValueError(f"wavelengths_m[{i}] = {x!r}: must be in [1e-08, 0.0001] m (10 nm to 100 um)")
    if w is not None and (len(w) != len(lam) or min(w) < 0 or sum(w) <= 0):
        raise ValueError(
            f"wavelength_weights = {list(w)!r}: must give one weight >= 0 per wavelength ({len(lam)}), with a "
            "positive sum"
        )


def _check_table(lam: tuple[float, ...] | None, r: tuple[float, ...] | None, file: str | None) -> None:
    where = f"response_file = {file!r}: " if file is not None else ""
    if lam is None or r is None or len(lam) != len(r) or len(lam) < 2:
        n = (None if lam is None else len(lam)), (None if r is None else len(r))
        raise ValueError(f"{where}response_wavelengths_m and response_values: give both, one value per wavelength "
                         f"(>= 2); got {n[0]} and {n[1]}")  # fmt: skip
    for i, x in enumerate(lam):
        if not (math.isfinite(x) and 2.8e-7 <= x <= 4.0e-6):
            raise ValueError(f"{where}response_wavelengths_m[{i}] = {x!r}: must be in [2.8e-07, 4e-06] m")
        if i and x <= lam[i - 1]:
            raise ValueError(f"{where}response_wavelengths_m[{i}] = {x!r}: not greater than the one before "
                             f"({lam[i - 1]!r}); the wavelengths must increase")  # fmt: skip
    for i, v in enumerate(r):
        if not (math.isfinite(v) and 0 <= v <= 1):
            raise ValueError(f"{where}response_values[{i}] = {v!r}: must be in [0, 1]")
    if max(r) <= 0:
        raise ValueError(f"{where}response_values: all 0; the response must be > 0 somewhere")


def _check_qe(q: float | tuple[float, ...] | None, w: tuple[float, ...] | None) -> None:
    if isinstance(q, tuple):
        for i, v in enumerate(q):
            if not (math.isfinite(v) and 0 <= v <= 1):
                raise ValueError(f"qe[{i}] = {v!r}: must be in [0, 1] (electrons per photon)")
        if w is None or len(w) != len(q) or len(q) < 2:
            raise ValueError(f"qe is a table of {len(q)} values: give qe_wavelengths_m with the same number (>= 2) "
                             f"of wavelengths (got {None if w is None else len(w)})")  # fmt: skip
        if any(b <= a for a, b in zip(w[:-1], w[1:], strict=True)) or any(not 1e-8 <= x <= 1e-4 for x in w):
            raise ValueError(f"qe_wavelengths_m = {list(w)!r}: must be strictly increasing, in [1e-08, 0.0001] m")
        if max(q) <= 0:
            raise ValueError("qe: a tabulated QE must be > 0 somewhere")
        return
    if q is not None and not (math.isfinite(q) and 0 < q <= 1):
        raise ValueError(f"qe = {q!r}: must be in (0, 1] (electrons per photon)")
    if w is not None:
        raise ValueError(f"qe_wavelengths_m = {list(w)!r} is given but qe is not a table; give qe as a table")


def read_response_csv(path: Any) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The columns ``wavelength_m`` and ``response`` of a CSV table (a header row; ``#`` comments), wavelengths
    strictly increasing: a ``[[bands]] response_file``. A row out of order is named by its line in the file."""
    p = Path(str(path))
    if not p.is_file():
        what = "a folder, not a file; give the CSV table" if p.is_dir() else "not found"
        raise SatchainIOError(f"bands.response_file = {str(p)!r}: {what}")
    try:
        lines = p.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise ValueError(f"response_file = {str(p)!r}: cannot be read ({exc})") from None
    rows = [(n, ln) for n, ln in enumerate(lines, 1) if ln.strip() and not ln.lstrip().startswith("#")]
    if not rows:
        raise ValueError(f"response_file = {str(p)!r}: empty; need a header wavelength_m,response and rows")
    header = [h.strip() for h in rows[0][1].split(",")]
    if "wavelength_m" not in header or "response" not in header:
        raise ValueError(f"response_file = {str(p)!r}: its header names {header}; need wavelength_m and response")
    iw, ir = header.index("wavelength_m"), header.index("response")
    lam: list[float] = []
    val: list[float] = []
    for n, ln in rows[1:]:
        cells = ln.split(",")
        try:
            x, v = float(cells[iw]), float(cells[ir])
        except (IndexError, ValueError):
            raise ValueError(f"response_file = {str(p)!r}: line {n} ({ln.strip()!r}) is not two numbers") from None
        if lam and not x > lam[-1]:
            raise ValueError(f"response_file = {str(p)!r}: line {n}: wavelength_m {x!r} is not greater than the row "
                             f"before ({lam[-1]!r}); the table must increase in wavelength")  # fmt: skip
        lam.append(x)
        val.append(v)
    return tuple(lam), tuple(val)
