"""The sections of an ImagingSystem (``[orbit]``, ``[optics]``, ``[detector]``, ``[motion]``; ``[radiometry]``,
``[illumination]``, ``[atmosphere]`` and ``[[bands]]`` live in :mod:`satchain.config.sections_light` and are
re-exported here): frozen pydantic models whose validation errors name key, value and range.
:mod:`satchain.config.system` assembles them and re-exports them."""

from __future__ import annotations

import math
from typing import Any, ClassVar, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from satchain.config._base import (  # noqa: F401  (re-exported: other modules import them from here)
    _allowed,
    _config_error,
    _Frozen,
    _not_a_number,
    _number_kinds,
    _StrictNumbers,
    schema_bounds,
)
from satchain.config.sections_cfa import CFAPattern, CFAResponses
from satchain.config.sections_light import Atmosphere, Band, Illumination, Radiometry
from satchain.config.sections_motion import JitterPSD, LineOfSightLog, Oscillation, as_tables, check_earth_rotation
from satchain.config.sections_staggered import STAGGER_SEPARATION_DOC, check_stagger_separation

EARTH_RADIUS_M = 6_371_008.8  # IUGG mean radius
EARTH_GM_M3_PER_S2 = 3.986004418e14  # WGS 84
EARTH_ROTATION_RAD_PER_S = 7.292115e-5  # IERS nominal mean angular velocity

__all__ = [
    "EARTH_GM_M3_PER_S2",
    "EARTH_RADIUS_M",
    "EARTH_ROTATION_RAD_PER_S",
    "Atmosphere",
    "Band",
    "Detector",
    "Illumination",
    "JitterPSD",
    "Motion",
    "Optics",
    "Orbit",
    "Oscillation",
    "Radiometry",
    "Spiders",
]


class Orbit(_Frozen):
    """Circular orbit; the camera looks ``off_nadir_deg`` across-track (a roll) from ``altitude_m``.

    Spherical Earth: the incidence angle at the ground is ``asin((R + h) / R * sin(eta))``, the slant range
    ``(R + h) cos(eta) - sqrt(R^2 - (R + h)^2 sin^2(eta))`` (Wertz & Larson, *Space Mission Analysis and
    Design*, sec. 5.3). Off nadir the along-track GSD grows with the range and the across-track GSD also by
    the foreshortening ``1 / cos(incidence)``.
    """

    altitude_m: float = Field(
        gt=0,
        le=1e8,
        description="height above the ground, m, of the circular orbit: sets the range, GSD and ground speed",
    )
    off_nadir_deg: float = Field(
        default=0.0,
        ge=0,
        lt=90,
        description="look angle across-track at the satellite (a roll): slant range, foreshortened ACT GSD, GIQE "
        "elevation; must stay below the Earth's limb seen from altitude_m",
    )
    # --- the Earth's rotation under a pushbroom scan (satchain.config.sections_motion, README "Pushbroom TDI motion")
    latitude_deg: float | None = Field(
        default=None,
        ge=-90,
        le=90,
        description="latitude of the scene: the Earth's surface speed and the ground track's heading under "
        "earth_rotation; within what the orbit reaches, |latitude| <= min(i, 180 - i)",
    )
    inclination_deg: float | None = Field(
        default=None, ge=0, le=180, description="orbit inclination i: the ground track's heading under earth_rotation"
    )
    earth_rotation: bool = Field(
        default=False,
        description="the ground moves east under the satellite during the scan (a shear and a line-rate mismatch of "
        "the pushbroom image); needs latitude_deg and inclination_deg",
    )
    yaw_steering: bool = Field(
        default=False,
        description="the detector line is turned to stay across the ground's relative motion (needs earth_rotation)",
    )
    pass_direction: Literal["descending", "ascending"] = Field(
        default="descending",
        description="'descending' (southbound) or 'ascending' (northbound) pass: the sign of the Earth-rotation shear",
    )

    @model_validator(mode="after")
    def _below_horizon(self) -> Orbit:
        limit = math.degrees(math.asin(EARTH_RADIUS_M / (EARTH_RADIUS_M + self.altitude_m)))
        if self.off_nadir_deg >= limit - 1e-6:
            raise ValueError(
                f"orbit.off_nadir_deg = {self.off_nadir_deg!r}: must be below {limit:.2f} deg (the Earth's limb "
                f"seen from {self.altitude_m:g} m)"
            )
        check_earth_rotation(self)
        return self

    @property
    def incidence_deg(self) -> float:
        """Angle between the line of sight and the local vertical at the ground."""
        r, h = EARTH_RADIUS_M, self.altitude_m
        return math.degrees(math.asin((r + h) / r * math.sin(math.radians(self.off_nadir_deg))))

    @property
    def elevation_deg(self) -> float:
        """Elevation of the satellite seen from the ground target (90 at nadir; the GIQE's angle)."""
        return 90.0 - self.incidence_deg

    @property
    def range_m(self) -> float:
        """Camera-to-ground distance along the line of sight (m); the altitude at nadir."""
        r, h, eta = EARTH_RADIUS_M, self.altitude_m, math.radians(self.off_nadir_deg)
        if eta == 0:
            return h
        return (r + h) * math.cos(eta) - math.sqrt(r * r - ((r + h) * math.sin(eta)) ** 2)

    @property
    def orbital_speed_m_per_s(self) -> float:
        """Circular orbital speed ``sqrt(GM / (R + h))``."""
        return math.sqrt(EARTH_GM_M3_PER_S2 / (EARTH_RADIUS_M + self.altitude_m))

    @property
    def ground_speed_m_per_s(self) -> float:
        """Speed of the nadir point over a non-rotating Earth: ``v_orbit * R / (R + h)``."""
        return self.orbital_speed_m_per_s * EARTH_RADIUS_M / (EARTH_RADIUS_M + self.altitude_m)


class Spiders(_Frozen):
    """Secondary-mirror support vanes: ``count`` straight vanes of ``width_m`` through the pupil centre."""

    count: int = Field(
        ge=0, le=16, description="number of straight radial vanes, equally spaced by 360 / count deg (count); 0: none"
    )
    width_m: float = Field(gt=0, description="width of each vane; must be < optics.aperture_diameter_m")
    angle_deg: float = Field(default=0.0, ge=-360, le=360, description="angle of the first vane from +x (ACT)")


class Optics(_Frozen):
    """Telescope: aperture, focal length or F#, central obscuration, spectral band, aberrations.

    ``zernike_rms_waves`` is the wavefront ``W = sum_j c_j Z_j`` (Noll's order and unit-rms normalisation,
    :mod:`satchain.tf.zernike`; ``Z_2 = 2 rho cos(theta)``, ``theta`` from +x = ACT towards +y = ALT), in waves at
    the effective wavelength. Sign: the pupil carries ``exp(+2 pi i W)`` and the PSF is
    ``|FT{p}|^2`` with the kernel ``exp(-2 pi i u.x / (lambda f))`` (Goodman's), so with
    ``zernike_sign = "satchain"`` (the default) a positive Z2 (Z3) moves the image towards +x, ACT, increasing
    column (+y, ALT, increasing row) by ``4 c lambda F#`` in the focal plane (``4 c lambda / D`` rad), and a
    positive Z8 (Z7) moves its centroid the same way (``sqrt 2`` times as far per wave for a clear pupil, more
    with an obscuration) while its core stays. ``zernike_sign = "zemax"`` reads coefficients in the opposite
    convention, the kernel ``exp(+2 pi i ...)`` of Zemax OpticStudio's FFT PSF and of GalSim's default
    (``fft_sign = "+"``): a positive Z2 moves the image towards -x. The change of convention is ``W -> -W``,
    which for a real pupil transmission is exactly ``PSF(x) -> PSF(-x)`` (a 180-degree rotation; the OTF
    becomes its complex conjugate): even terms (defocus, astigmatism, spherical) alone are unchanged, odd ones
    (tilt, coma, trefoil) move the other way. :attr:`wavefront_zernikes_waves` gives the coefficients in
    satchain's convention.
    """

    aperture_diameter_m: float = Field(
        gt=0,
        le=100,
        description="entrance-pupil (primary mirror) diameter D: with the wavelength it sets the diffraction blur, "
        "with the F# the light collected",
    )
    focal_length_m: float = Field(
        gt=0,
        le=1e3,
        description="effective focal length f = F# D: with the pixel pitch and the range it sets the GSD; give it "
        "or f_number (both: they must agree within 0.1 %)",
    )
    f_number: float = Field(
        gt=0,
        le=1e3,
        description="focal ratio F# = focal_length_m / aperture_diameter_m (dimensionless): the optical cutoff "
        "1 / (lambda F#) and the focal-plane irradiance; give it or focal_length_m",
    )
    obscuration_ratio: float = Field(
        default=0.0,
        ge=0,
        lt=1,
        description="central obscuration diameter ratio (secondary mirror / aperture, dimensionless): an annular "
        "pupil; blocks ratio^2 of its area",
    )
    wavelengths_m: tuple[float, ...] = Field(
        min_length=1,
        description="wavelengths at which the diffraction OTF is evaluated and summed into the polychromatic MTF, "
        "each in [1e-08, 0.0001] m (not the radiometric band, radiometry.band_m)",
        json_schema_extra=schema_bounds(items={"minimum": 1e-8, "maximum": 1e-4}),
    )
    wavelength_weights: tuple[float, ...] | None = Field(
        default=None,
        description="relative weight of each of wavelengths_m in the polychromatic MTF (dimensionless): one per "
        "wavelength, each >= 0, a positive sum; default: equal weights",
        json_schema_extra=schema_bounds(items={"minimum": 0}),
    )
    transmission: float = Field(
        default=1.0,
        gt=0,
        le=1,
        description="optics transmission tau (dimensionless fraction): scales the focal-plane irradiance "
        "pi L tau (1 - eps^2) / (4 F#^2), so the signal; no effect on the MTF",
    )
    wfe_rms_waves: float = Field(
        default=0.0,
        ge=0,
        le=0.25,
        description="random wavefront error, rms waves at the effective wavelength (Shannon's aberration transfer "
        "factor)",
    )
    zernike_rms_waves: dict[int, float] = Field(
        default_factory=dict,
        description="Noll index -> rms coefficient in waves (defocus is 4); sign as zernike_sign says; Noll indices "
        "in [1, 66], coefficients in [-1, 1]; non-zero terms use the pupil FFT",
        json_schema_extra=schema_bounds(items={"minimum": -1, "maximum": 1}),
    )
    zernike_sign: Literal["satchain", "zemax"] = Field(
        default="satchain",
        description="convention of zernike_rms_waves: 'satchain' (a positive Z2 moves the image +x, ACT) or "
        "'zemax' (Zemax OpticStudio's and GalSim's: -x); 'zemax' is W -> -W, the PSF rotated by 180 deg",
    )
    spiders: Spiders | None = Field(
        default=None,
        description="secondary-mirror support vanes, e.g. { count = 4, width_m = 0.02 } (through the pupil FFT); "
        "default: none",
    )
    diffraction_model: Literal["auto", "analytic", "pupil_fft"] = Field(
        default="auto",
        description="how the diffraction OTF is computed: 'auto' (the closed-form annular OTF, O'Neill 1956, or the "
        "pupil function by FFT when spiders or Zernike terms need it), 'analytic' (always the closed form: spiders "
        "and Zernike terms left out) or 'pupil_fft' (always the FFT)",
    )

    @model_validator(mode="before")
    @classmethod
    def _focal_or_f_number(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            return data
        d = dict(data)
        D = d.get("aperture_diameter_m")
        f, n = d.get("focal_length_m"), d.get("f_number")
        try:
            D = float(D) if D is not None else None
        except (TypeError, ValueError):
            return d  # field validation reports it
        if D is None or D <= 0:
            return d
        if f is None and n is None:
            raise ValueError("give optics.focal_length_m or optics.f_number (got neither)")
        try:
            if f is None:
                assert n is not None  # neither given: raised above
                d["focal_length_m"] = float(n) * D
            elif n is None:
                d["f_number"] = float(f) / D
            elif abs(float(f) / D - float(n)) > 1e-3 * float(n):
                raise ValueError(
                    f"optics.focal_length_m = {f!r} and optics.f_number = {n!r} disagree: "
                    f"focal_length_m / aperture_diameter_m = {float(f) / D:.6g}; give one of them"
                )
        except (TypeError, ValueError) as exc:
            if "disagree" in str(exc):
                raise
        return d

    @field_validator("wavelengths_m")
    @classmethod
    def _wavelengths(cls, v: tuple[float, ...]) -> tuple[float, ...]:
        for i, w in enumerate(v):
            if not (1e-8 <= w <= 1e-4):
                raise ValueError(f"wavelengths_m[{i}] = {w!r}: must be in [1e-08, 0.0001] m (10 nm to 100 um)")
        return v

    @field_validator("zernike_rms_waves")
    @classmethod
    def _zernikes(cls, v: dict[int, float]) -> dict[int, float]:
        for j, c in v.items():
            if not 1 <= j <= 66:
                raise ValueError(f"zernike_rms_waves key {j!r}: Noll index must be in [1, 66]")
            if not (math.isfinite(c) and abs(c) <= 1.0):
                raise ValueError(f"zernike_rms_waves[{j}] = {c!r}: must be in [-1, 1] waves rms")
        return v

    @model_validator(mode="after")
    def _weights(self) -> Optics:
        w = self.wavelength_weights
        if w is not None:
            if len(w) != len(self.wavelengths_m):
                raise ValueError(
                    f"wavelength_weights has {len(w)} entries but wavelengths_m has {len(self.wavelengths_m)}"
                )
            if any((not math.isfinite(x)) or x < 0 for x in w) or sum(w) <= 0:
                raise ValueError(f"wavelength_weights = {list(w)!r}: must be >= 0 with a positive sum")
        if self.spiders is not None and self.spiders.count and self.spiders.width_m >= self.aperture_diameter_m:
            raise ValueError(
                f"spiders.width_m = {self.spiders.width_m!r}: must be < aperture_diameter_m "
                f"({self.aperture_diameter_m!r})"
            )
        return self

    @property
    def weights(self) -> np.ndarray:
        """Normalised polychromatic weights (uniform when none are given)."""
        w = np.ones(len(self.wavelengths_m)) if self.wavelength_weights is None else np.array(self.wavelength_weights)
        return w / w.sum()

    @property
    def effective_wavelength_m(self) -> float:
        """Weight-averaged wavelength."""
        return float(np.dot(self.weights, self.wavelengths_m))

    @property
    def wavefront_zernikes_waves(self) -> dict[int, float]:
        """``zernike_rms_waves`` in satchain's sign convention (negated, ``W -> -W``, for ``zernike_sign =
        "zemax"``): the wavefront the pupil FFT uses."""
        flip = -1.0 if self.zernike_sign == "zemax" else 1.0
        return {j: flip * c for j, c in self.zernike_rms_waves.items()}

    @property
    def needs_pupil_fft(self) -> bool:
        """True when the pupil has features the closed-form (O'Neill) OTF cannot describe."""
        if self.diffraction_model != "auto":
            return self.diffraction_model == "pupil_fft"
        spiders = self.spiders is not None and self.spiders.count > 0
        return spiders or any(c != 0 for c in self.zernike_rms_waves.values())


class Detector(_Frozen):
    """Detector line / TDI array. Give ``pitch_m`` or both ``pitch_x_m`` and ``pitch_y_m``; the active
    area by ``fill_factor`` (area fraction, square active area centred in the pixel) or by
    ``active_width_x_m`` / ``active_width_y_m``."""

    _input_keys: ClassVar[tuple[str, ...]] = ("pitch_m", "fill_factor")  # turned into fields by _pitch_and_fill

    pitch_x_m: float = Field(
        gt=0,
        le=1e-3,
        description="pixel pitch across-track (x, the columns): the sampling; with the focal length and range the ACT "
        "GSD (pitch_m sets both axes)",
    )
    pitch_y_m: float = Field(
        gt=0,
        le=1e-3,
        description="pixel pitch along-track (y, the rows): with the focal length and range the ALT GSD and the line "
        "time (pitch_m sets both axes)",
    )
    active_width_x_m: float = Field(
        gt=0,
        description="width of a pixel's photosensitive area across-track: the pixel OTF sinc(d_x f_x) and the "
        "collecting area; <= pitch_x_m; default: pitch_x_m, or from fill_factor",
    )
    active_width_y_m: float = Field(
        gt=0,
        description="height of a pixel's photosensitive area along-track: the pixel OTF sinc(d_y f_y) and the "
        "collecting area; <= pitch_y_m; default: pitch_y_m, or from fill_factor",
    )
    charge_diffusion_length_m: float = Field(
        default=0.0,
        ge=0,
        le=1e-3,
        description="lateral charge-diffusion length L (an exponential PSF): the OTF (1 + (2 pi L f)^2)^-1.5; 0: none",
    )
    tdi_stages: int = Field(
        default=1,
        ge=1,
        le=1024,
        description="number of TDI stages N (count): the signal adds over N line periods, the TDI window over "
        "which line-rate mismatch and pushbroom motion act",
    )
    tdi_sync_error: float = Field(
        default=0.0,
        ge=-0.5,
        le=0.5,
        description="fractional along-track line-rate mismatch of TDI clocking (dimensionless): a smear of "
        "tdi_stages x |error| px ALT; the older name of motion.line_rate_error (give one)",
    )
    # --- radiometric properties (satchain.radiometry). Defaults describe an ideal detector: QE 1, no
    # read or dark noise, no full-well limit, no quantisation.
    qe: float | tuple[float, ...] = Field(
        default=1.0,
        description="quantum efficiency, e-/photon (dimensionless): a number in (0, 1], or a table of values in "
        "[0, 1] on qe_wavelengths_m (linear between them, 0 outside)",
        json_schema_extra=schema_bounds(
            number={"exclusiveMinimum": 0, "maximum": 1}, items={"minimum": 0, "maximum": 1}
        ),
    )
    qe_wavelengths_m: tuple[float, ...] | None = Field(
        default=None,
        description="wavelengths of a qe table: one per qe value (>= 2), strictly increasing, each in "
        "[1e-08, 0.0001] m",
        json_schema_extra=schema_bounds(items={"minimum": 1e-8, "maximum": 1e-4}),
    )
    full_well_e: float | None = Field(
        default=None,
        gt=0,
        le=1e9,
        description="charge capacity, electrons: the signal clips there and the ADC range spans it; default: "
        "the signal of reflectance 1",
    )
    read_noise_e: float = Field(default=0.0, ge=0, le=1e4, description="read noise per read, electrons rms")
    dark_current_e_per_s: float = Field(default=0.0, ge=0, le=1e9, description="dark current, e-/s per pixel")
    bit_depth: int | None = Field(
        default=None,
        ge=1,
        le=32,
        description="ADC resolution in bits: full_well_e / 2^bit_depth electrons per DN; needs full_well_e; "
        "default: 12 bits",
    )
    readout: Literal["ccd", "cmos"] = Field(
        default="ccd",
        description="TDI accumulation: 'ccd' sums charge (one read), 'cmos' sums digitally (one per stage)",
    )
    prnu: float = Field(
        default=0.0,
        ge=0,
        le=1,
        description="photo-response non-uniformity, fraction of the signal rms (dimensionless): a fixed gain pattern",
    )
    dsnu_e: float = Field(default=0.0, ge=0, le=1e6, description="dark-signal non-uniformity, electrons rms")
    cfa: CFAPattern | None = Field(
        default=None,
        description="colour filter array: the 2x2 Bayer cell read row by row from the first pixel ('RGGB': red at row "
        "0, column 0), 'RGGB', 'GRBG', 'GBRG' or 'BGGR'; default: none (a monochrome array)",
    )
    layout: Literal["single", "staggered"] = Field(
        default="single",
        description="'single': one array; 'staggered': two arrays half a pixel apart along and across track, "
        "combined onto the grid of half the pitch (SPOT-5's supermode; quincunx bilinear fill)",
    )
    stagger_separation_px: float | None = Field(default=None, gt=0, le=1e4,
                                                description=STAGGER_SEPARATION_DOC)  # fmt: skip
    cfa_responses: CFAResponses | None = Field(
        default=None,
        description="[detector.cfa_responses.red|green|blue]: each colour's relative spectral response (center_m and "
        "fwhm_m, or wavelengths_m and values); needs cfa; default: the packaged Nikon D5100 (NPL) responses",
    )

    @model_validator(mode="before")
    @classmethod
    def _pitch_and_fill(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            return data
        d = dict(data)
        p = d.pop("pitch_m", None)
        if p is not None:
            for k in ("pitch_x_m", "pitch_y_m"):
                if k in d and d[k] != p:
                    raise ValueError(f"detector.pitch_m = {p!r} conflicts with detector.{k} = {d[k]!r}; give one")
                d[k] = p
        elif "pitch_x_m" not in d or "pitch_y_m" not in d:
            raise ValueError("give detector.pitch_m, or both detector.pitch_x_m and detector.pitch_y_m")
        ff = d.pop("fill_factor", None)
        if ff is not None:
            if "active_width_x_m" in d or "active_width_y_m" in d:
                raise ValueError("give detector.fill_factor or detector.active_width_x_m/_y_m, not both")
            why = _not_a_number(ff)
            if why is not None:
                raise ValueError(f"detector.fill_factor = {ff!r}: {why}")
            try:
                ffv = float(ff)
            except (TypeError, ValueError):
                raise ValueError(f"detector.fill_factor = {ff!r}: must be a number in (0, 1]") from None
            if not 0 < ffv <= 1:
                raise ValueError(f"detector.fill_factor = {ff!r}: must be in (0, 1]")
            try:
                d["active_width_x_m"] = float(d["pitch_x_m"]) * math.sqrt(ffv)
                d["active_width_y_m"] = float(d["pitch_y_m"]) * math.sqrt(ffv)
            except (TypeError, ValueError):
                return d
        else:
            d.setdefault("active_width_x_m", d.get("pitch_x_m"))
            d.setdefault("active_width_y_m", d.get("pitch_y_m"))
        return d

    @model_validator(mode="after")
    def _active_within_pitch(self) -> Detector:
        for ax in ("x", "y"):
            a, p = getattr(self, f"active_width_{ax}_m"), getattr(self, f"pitch_{ax}_m")
            if a > p * (1 + 1e-12):
                raise ValueError(f"active_width_{ax}_m = {a!r}: must be <= pitch_{ax}_m ({p!r})")
        return self

    @field_validator("qe")
    @classmethod
    def _qe_values(cls, v: float | tuple[float, ...]) -> float | tuple[float, ...]:
        if isinstance(v, tuple):
            for i, q in enumerate(v):
                if not (math.isfinite(q) and 0 <= q <= 1):
                    raise ValueError(f"qe[{i}] = {q!r}: must be in [0, 1] (electrons per photon)")
        elif not (math.isfinite(v) and 0 < v <= 1):
            raise ValueError("must be in (0, 1] (electrons per photon)")
        return v

    @model_validator(mode="after")
    def _qe_table_and_adc(self) -> Detector:
        w, q = self.qe_wavelengths_m, self.qe
        if isinstance(q, tuple):
            if w is None or len(w) != len(q) or len(q) < 2:
                raise ValueError(
                    f"detector.qe is a table of {len(q)} values: give detector.qe_wavelengths_m with the "
                    f"same number (>= 2) of wavelengths (got {None if w is None else len(w)})"
                )
            increasing = all(b > a for a, b in zip(w[:-1], w[1:], strict=True))
            if not increasing or any(not 1e-8 <= x <= 1e-4 for x in w):
                raise ValueError(
                    f"detector.qe_wavelengths_m = {list(w)!r}: must be strictly increasing, in [1e-08, 0.0001] m"
                )
            if max(q) <= 0:
                raise ValueError("detector.qe: a tabulated QE must be > 0 somewhere")
        elif w is not None:
            raise ValueError("detector.qe_wavelengths_m is given but detector.qe is a single number; give a qe table")
        if self.bit_depth is not None and self.full_well_e is None:
            raise ValueError(
                f"detector.bit_depth = {self.bit_depth!r} needs detector.full_well_e (the ADC range is "
                "mapped to the full well, which sets electrons per DN)"
            )
        return self

    @model_validator(mode="after")
    def _cfa_responses_need_cfa(self) -> Detector:
        if self.cfa_responses is not None and self.cfa is None:
            raise ValueError("detector.cfa_responses is given but detector.cfa is not: give cfa (e.g. 'RGGB')")
        if self.layout == "staggered" and (self.pitch_x_m != self.pitch_y_m or self.cfa is not None):
            raise ValueError("detector.layout = 'staggered': needs square pixels (pitch_x_m = pitch_y_m) and no cfa")
        check_stagger_separation(self)  # a TDI count the arrays' separation cannot hold (sections_staggered)
        return self

    def qe_at(self, wavelength_m) -> np.ndarray:
        """Quantum efficiency at the given wavelengths (linear interpolation of the table, 0 outside it)."""
        lam = np.asarray(wavelength_m, dtype=float)
        if isinstance(self.qe, tuple):
            assert self.qe_wavelengths_m is not None  # _qe_table_and_adc: a qe table needs its wavelengths
            return np.interp(lam, self.qe_wavelengths_m, self.qe, left=0.0, right=0.0)
        return np.full_like(lam, float(self.qe))

    @property
    def active_area_m2(self) -> float:
        """Photosensitive area of one pixel (m^2): what collects light in the radiometric budget."""
        return self.active_width_x_m * self.active_width_y_m

    @property
    def fill_factor(self) -> float:
        """Active area / pixel area."""
        return self.active_width_x_m * self.active_width_y_m / (self.pitch_x_m * self.pitch_y_m)


class Motion(_Frozen):
    """Platform motion during one exposure: linear along-track smear and random jitter (detector pixels)."""

    smear_px: float = Field(default=0.0, ge=0, le=100, description="along-track (ALT, y) linear smear length")
    smear_act_px: float = Field(default=0.0, ge=0, le=100, description="across-track (ACT, x) smear, e.g. yaw")
    jitter_rms_px: float = Field(default=0.0, ge=0, le=10, description="Gaussian jitter per axis, rms")
    # --- pushbroom TDI motion in time (satchain.config.sections_motion, satchain.tf.pushbroom)
    line_rate_error: float = Field(
        default=0.0,
        ge=-0.5,
        le=0.5,
        description="image motion per line period / one line, minus 1 (TDI mismatch, dimensionless): a TDI smear "
        "of tdi_stages x e px and an along-track scale 1 + e",
    )
    oscillation: tuple[Oscillation, ...] = Field(
        default=(),
        max_length=64,
        description="[[motion.oscillation]]: sinusoidal line-of-sight motions during the TDI window",
    )
    jitter_psd: tuple[JitterPSD, ...] = Field(
        default=(),
        max_length=16,
        description="[motion.jitter_psd] table(s): random line-of-sight motion given by its power spectral density",
    )
    line_of_sight: LineOfSightLog | None = Field(
        default=None, description="[motion.line_of_sight]: a measured log of the line of sight, e.g. attitude data"
    )

    @field_validator("jitter_psd", mode="before")
    @classmethod
    def _one_or_more(cls, v: Any) -> Any:
        return as_tables(v)

    @field_validator("oscillation", mode="before")
    @classmethod
    def _array_of_tables(cls, v: Any) -> Any:
        # [motion.oscillation] (one table), oscillation = "act", a list of strings ...: [[motion.oscillation]] is meant
        if not isinstance(v, (list, tuple)) or not all(isinstance(o, (dict, Oscillation)) for o in v):
            raise ValueError(
                "motion.oscillation must be an array of tables: write [[motion.oscillation]] (one per oscillation) "
                "with axis, amplitude_px, frequency_hz (and phase_deg)"
            )
        return v

    @property
    def time_varying(self) -> bool:
        """True when the motion has terms that change during a TDI window (oscillations, a jitter PSD, a log)."""
        return bool(self.oscillation or self.jitter_psd or self.line_of_sight is not None)
