"""ImagingSystem: a frozen, validated description of a satellite camera and its orbit.

Built from a TOML file (``load_system``), a packaged preset (``load_preset``) or in Python. Every
invalid or inconsistent value is rejected with a :class:`~satchain.errors.ConfigError` whose message
names the key, the value and what is allowed, e.g.::

    optics.obscuration_ratio = 1.2: must be less than 1

Derived quantities (focal length / F#, IFOV, GSD, Nyquist, optical cutoff, Q, Airy diameter and
whether the system is detector- or optics-limited) are properties of the frozen object.

Examples
--------
>>> s = load_preset("ankarasat3")
>>> round(s.gsd_alt_m, 3), round(s.nyquist_alt_cy_per_mm, 2), s.limited_by
(0.49, 85.03, 'detector')
"""

from __future__ import annotations

import math
import sys
from importlib import resources
from pathlib import Path
from typing import Any, ClassVar, Literal

import numpy as np
from pydantic import Field, ValidationError, model_validator

from satchain import units
from satchain._argcheck import checked
from satchain.errors import ConfigError, SatchainIOError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from satchain.config._base import refuse_unknown_keys
from satchain.config.response import response_table
from satchain.config.sections import (  # noqa: F401  (re-exported: the sections are part of this module's API)
    EARTH_GM_M3_PER_S2,
    EARTH_RADIUS_M,
    Atmosphere,
    Band,
    Detector,
    Illumination,
    Motion,
    Optics,
    Orbit,
    Radiometry,
    Spiders,
    _config_error,
    _Frozen,
)

__all__ = [
    "Atmosphere",
    "Band",
    "Detector",
    "Illumination",
    "ImagingSystem",
    "Motion",
    "Optics",
    "Orbit",
    "Radiometry",
    "Spiders",
    "load_preset",
    "load_system",
]


class ImagingSystem(_Frozen):
    """A complete satellite camera: orbit, optics, detector and motion, plus derived quantities."""

    _error_title: ClassVar[str] = "invalid imaging system"
    name: str = Field(default="custom", description="the camera's name, shown in reports and results.json")
    description: str = Field(default="", description="free text about the camera")
    orbit: Orbit = Field(description="[orbit]: the circular orbit and the look angle")
    optics: Optics = Field(description="[optics]: the telescope")
    detector: Detector = Field(description="[detector]: the pixels, TDI and the detector's signal chain")
    motion: Motion = Field(default_factory=Motion, description="[motion]: line-of-sight motion during the exposure")
    radiometry: Radiometry = Field(
        default_factory=Radiometry, description="[radiometry]: spectral band and exposure of the signal"
    )
    illumination: Illumination = Field(
        default_factory=Illumination, description="[illumination]: sun, surface and atmosphere of the signal"
    )
    atmosphere: Atmosphere = Field(
        default_factory=Atmosphere, description="[atmosphere]: atmospheric blur (turbulence, aerosols); off by default"
    )
    bands: tuple[Band, ...] = Field(default=(), description="per-band optics of a multiband camera ([[bands]])")
    provenance: dict[str, Any] = Field(default_factory=dict, description="free-form notes, e.g. fitted values")

    @model_validator(mode="after")
    def _one_line_rate(self) -> ImagingSystem:
        e = self.detector.tdi_sync_error
        if e != 0 and (self.motion.line_rate_error != 0 or self.orbit.earth_rotation):
            lr = self.motion.line_rate_error
            other = f"motion.line_rate_error = {lr!r}" if lr != 0 else "orbit.earth_rotation = true"
            raise ValueError(
                f"detector.tdi_sync_error = {e!r} and {other}: both set the TDI line-rate mismatch; give "
                "motion.line_rate_error (the same quantity) instead of detector.tdi_sync_error"
            )
        return self

    # ----------------------------------------------------------------- construction
    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ImagingSystem:
        """Validate a nested mapping (as read from TOML); raise ConfigError naming the key on failure."""
        refuse_unknown_keys(cls, data, "invalid imaging system")
        try:
            return cls.model_validate(data)
        except ValidationError as exc:
            raise _config_error(exc) from None

    @classmethod
    def from_toml(cls, path: str | Path) -> ImagingSystem:
        """Read and validate a system TOML file (a ``[motion.line_of_sight] file`` is relative to it)."""
        data = _read_toml(path)
        los = data.get("motion", {}).get("line_of_sight") if isinstance(data.get("motion"), dict) else None
        if isinstance(los, dict) and isinstance(los.get("file"), str):
            los["file"] = str((Path(path).resolve().parent / los["file"]).resolve())
        for band in data.get("bands", []) if isinstance(data.get("bands"), list) else []:
            if isinstance(band, dict) and isinstance(band.get("response_file"), str):
                band["response_file"] = str((Path(path).resolve().parent / band["response_file"]).resolve())
        return cls.from_dict(data)

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict (the TOML structure; pitches and active widths in explicit form)."""
        d = self.model_dump(mode="json", exclude_none=True)
        for section, defaults in _TIME_KEYS.items():  # the pushbroom motion keys appear only when set
            for key, default in defaults.items():
                if d[section].get(key) == default:
                    d[section].pop(key)
        return d

    def replace(self, values: dict[str, Any]) -> ImagingSystem:
        """A new validated system with dotted keys replaced, e.g. ``{"optics.obscuration_ratio": 0.3}``.

        For ``optics.focal_length_m`` / ``optics.f_number`` the other one follows (aperture fixed);
        for ``detector.pitch_*`` each active width keeps its fraction of its pitch. An entry of a table list is named by
        its index: ``{"motion.oscillation[0].amplitude_px": 2.0}``.

        Examples
        --------
        >>> s = load_preset("ankarasat3").replace({"motion.oscillation": [dict(axis="act", amplitude_px=0.5,
        ...     frequency_hz=4465.0)]})
        >>> s.replace({"motion.oscillation[0].amplitude_px": 2.0}).motion.oscillation[0].amplitude_px
        2.0
        """
        d = self.model_dump(mode="python")
        area = {k.partition(".")[2]: v for k, v in values.items() if k.startswith("detector.") and k[9:] in _AREA_KEYS}
        for key, v in values.items():
            section, _, field = key.partition(".")
            if section not in _SECTIONS or not field:
                raise ConfigError(f"parameter {key!r}: must be '<{'|'.join(_SECTIONS)}>.<field>'")
            sub = d[section]
            if section == "detector" and field in _AREA_KEYS:
                continue  # pitches and active area together, below
            if field.split(".")[0].split("[")[0] not in sub and field != "wavelength_m":
                raise ConfigError(f"parameter {key!r}: {section} has no field {field!r}")
            if section == "optics" and field in ("focal_length_m", "f_number"):
                sub.pop("f_number" if field == "focal_length_m" else "focal_length_m")
            if section == "optics" and field == "wavelength_m":
                field, v = "wavelengths_m", (v,)
                sub["wavelength_weights"] = None
            _set(sub, field, v, key)
        if area:
            _set_detector_area(d["detector"], area)
        return type(self).from_dict(d)

    def for_band(self, index: int) -> ImagingSystem:
        """The system that forms band ``index`` (0-based) of a multiband input: its ``[[bands]]`` entry's keys in
        place of the system's own -- the optics' wavelengths and weights (a response's quadrature), the radiometric
        band (a response's support), the QE (times the response), the (square) pixel pitch and active width, the TDI
        stages; the same telescope (focal length). The system itself without ``bands``.

        Examples
        --------
        >>> s = load_preset("ankarasat3").replace({})
        >>> s.for_band(2) is s
        True
        >>> ms = load_preset("ankarasat3-pms")
        >>> round(ms.for_band(ms.band_index("red")).gsd_m, 3)
        1.96
        """
        if not self.bands:
            return self
        i = index if isinstance(index, (int, np.integer)) and not isinstance(index, bool) else -1
        if not 0 <= i < len(self.bands):
            raise ConfigError(f"band index = {index!r}: the system has {len(self.bands)} bands (0 to "
                              f"{len(self.bands) - 1}: {', '.join(self.band_names)})")  # fmt: skip
        b = self.bands[int(i)]
        lam, weights = b.optics_wavelengths()
        values: dict[str, Any] = {"optics.wavelengths_m": lam, "optics.wavelength_weights": weights}
        band_m = b.radiometric_band_m
        if band_m is not None:
            values["radiometry.band_m"] = band_m
        qe = _band_qe(b, self.detector)
        if qe is not None:
            values["detector.qe"], values["detector.qe_wavelengths_m"] = qe
        if b.tdi_stages is not None:
            values["detector.tdi_stages"] = b.tdi_stages
        if b.pitch_m is not None:
            values["detector.pitch_m"] = b.pitch_m
        if b.active_width_m is not None:
            values["detector.active_width_x_m"] = values["detector.active_width_y_m"] = b.active_width_m
        out = self.replace(values)
        if b.pitch_m is not None:  # the line-of-sight motion is an angle: fewer of the band's (larger) pixels
            out = out.model_copy(update={"motion": _motion_in_pixels_of(self.motion, self.detector, b.pitch_m)})
        return out.model_copy(update={"bands": ()})

    @property
    def band_names(self) -> tuple[str, ...]:
        """The names of the ``[[bands]]`` in order (``band<i>``, 1-based, for a band without one); () without bands."""
        return tuple(b.name or f"band{i + 1}" for i, b in enumerate(self.bands))

    def band_index(self, name: str) -> int:
        """The 0-based index of the band called ``name`` (case-insensitive); a ConfigError listing the names."""
        names = [n.casefold() for n in self.band_names]
        if str(name).casefold() not in names:
            listed = ", ".join(map(repr, self.band_names)) or "none: the system has no [[bands]]"
            raise ConfigError(f"band = {name!r}: not a band of {self.name!r}; its bands are {listed}")
        return names.index(str(name).casefold())

    @model_validator(mode="after")
    def _bands_fit(self) -> ImagingSystem:
        seen: dict[str, int] = {}
        for i, b in enumerate(self.bands):
            key = b.name.casefold()
            if key and key in seen:
                j = seen[key]
                raise ValueError(f"bands[{i}].name = {b.name!r}: the same as bands[{j}].name = "
                                 f"{self.bands[j].name!r}; every band needs its own name")  # fmt: skip
            seen.setdefault(key, i)
            pitch = b.pitch_m or min(self.detector.pitch_x_m, self.detector.pitch_y_m)
            if b.active_width_m is not None and b.active_width_m > pitch * (1 + 1e-12):
                raise ValueError(f"bands[{i}].active_width_m = {b.active_width_m!r}: must be <= the band's pitch "
                                 f"({pitch!r})")  # fmt: skip
        return self

    # ----------------------------------------------------------------- derived quantities
    @property
    def focal_length_m(self) -> float:
        return self.optics.focal_length_m

    @property
    def f_number(self) -> float:
        return self.optics.f_number

    @property
    def ifov_act_rad(self) -> float:
        """Instantaneous field of view of one pixel, across-track (rad)."""
        return self.detector.pitch_x_m / self.focal_length_m

    @property
    def ifov_alt_rad(self) -> float:
        """Instantaneous field of view of one pixel, along-track (rad)."""
        return self.detector.pitch_y_m / self.focal_length_m

    @property
    def gsd_los_m(self) -> float:
        """Geometric-mean GSD perpendicular to the line of sight, ``pitch * range / f`` (what the GIQE takes
        together with the elevation angle)."""
        p = math.sqrt(self.detector.pitch_x_m * self.detector.pitch_y_m)
        return units.gsd_m(p, focal_length_m=self.focal_length_m, range_m=self.orbit.range_m)

    @property
    def gsd_act_m(self) -> float:
        """Ground sample distance across-track (x), m, on the ground (foreshortened off nadir)."""
        los = units.gsd_m(self.detector.pitch_x_m, focal_length_m=self.focal_length_m, range_m=self.orbit.range_m)
        return los / math.cos(math.radians(self.orbit.incidence_deg))

    @property
    def gsd_alt_m(self) -> float:
        """Ground sample distance along-track (y), m."""
        return units.gsd_m(self.detector.pitch_y_m, focal_length_m=self.focal_length_m, range_m=self.orbit.range_m)

    def focal_cy_per_mm_per_ground_cy_per_m(self, axis: str) -> float:
        """Focal-plane cy/mm of one ground cy/m along ``axis`` ("alt" = y, "act" = x): ``gsd / pitch / 1000``.
        Equals ``range / focal_length / 1000`` at nadir; across-track off nadir it includes the foreshortening.

        Examples
        --------
        >>> round(load_preset("ankarasat3").focal_cy_per_mm_per_ground_cy_per_m("alt"), 3)
        83.333
        """
        if axis == "alt":
            return self.gsd_alt_m / self.detector.pitch_y_m / units.MM_PER_M
        if axis == "act":
            return self.gsd_act_m / self.detector.pitch_x_m / units.MM_PER_M
        raise ConfigError(f"axis = {axis!r}: must be 'alt' or 'act'")

    @property
    def gsd_m(self) -> float:
        """Geometric-mean GSD, ``sqrt(gsd_act * gsd_alt)`` (the GIQE convention)."""
        return math.sqrt(self.gsd_act_m * self.gsd_alt_m)

    @property
    def nyquist_act_cy_per_mm(self) -> float:
        return units.nyquist_cy_per_mm(self.detector.pitch_x_m)

    @property
    def nyquist_alt_cy_per_mm(self) -> float:
        return units.nyquist_cy_per_mm(self.detector.pitch_y_m)

    @property
    def nyquist_act_cy_per_m_ground(self) -> float:
        return 0.5 / self.gsd_act_m

    @property
    def nyquist_alt_cy_per_m_ground(self) -> float:
        return 0.5 / self.gsd_alt_m

    @property
    def optical_cutoff_cy_per_mm(self) -> np.ndarray:
        """Incoherent diffraction cutoff ``1 / (lambda F#)`` for each wavelength (cy/mm)."""
        return 1.0 / (np.asarray(self.optics.wavelengths_m) * self.f_number * units.MM_PER_M)

    @property
    def q(self) -> np.ndarray:
        """Sampling ratio ``Q = lambda F# / pitch`` per wavelength (geometric-mean pitch). Q = 2 is Nyquist
        sampling of the optical cutoff."""
        p = math.sqrt(self.detector.pitch_x_m * self.detector.pitch_y_m)
        return np.asarray(self.optics.wavelengths_m) * self.f_number / p

    @property
    def q_effective(self) -> float:
        """Q at the effective (weight-averaged) wavelength."""
        p = math.sqrt(self.detector.pitch_x_m * self.detector.pitch_y_m)
        return self.optics.effective_wavelength_m * self.f_number / p

    @property
    def airy_diameter_m(self) -> np.ndarray:
        """Diameter of the Airy disk to its first dark ring, ``2.44 lambda F#``, per wavelength (focal plane, m)."""
        return 2.0 * 1.219669891266504 * np.asarray(self.optics.wavelengths_m) * self.f_number

    @property
    def airy_diameter_px(self) -> np.ndarray:
        return self.airy_diameter_m / math.sqrt(self.detector.pitch_x_m * self.detector.pitch_y_m)

    @property
    def limited_by(self) -> Literal["detector", "optics"]:
        """``"detector"`` when the optical cutoff lies above the detector Nyquist frequency at the
        effective wavelength (Q < 2: the pixel grid, i.e. the GSD, limits resolution), else ``"optics"``."""
        return "detector" if self.q_effective < 2.0 else "optics"

    @property
    def line_time_s(self) -> float:
        """Time for the nadir point to move one along-track GSD: ``gsd_alt_m / ground_speed_m_per_s``."""
        return self.gsd_alt_m / self.orbit.ground_speed_m_per_s

    @property
    def integration_time_s(self) -> float:
        """Exposure of one TDI stage: ``radiometry.integration_time_s`` or, by default, the line time."""
        t = self.radiometry.integration_time_s
        return self.line_time_s if t is None else t

    limited_by_criterion: ClassVar[str] = (
        "Q = lambda_eff * F# / pitch < 2 (optical cutoff 1/(lambda F#) above detector Nyquist 1/(2 pitch)) "
        "-> detector-limited; otherwise optics-limited"
    )

    def derived(self) -> dict[str, Any]:
        """All derived quantities as a JSON-ready dict (names carry their units)."""
        lam = np.asarray(self.optics.wavelengths_m)
        return {
            "focal_length_m": self.focal_length_m,
            "f_number": self.f_number,
            "ifov_act_urad": self.ifov_act_rad * 1e6,
            "ifov_alt_urad": self.ifov_alt_rad * 1e6,
            "gsd_act_m": self.gsd_act_m,
            "gsd_alt_m": self.gsd_alt_m,
            "gsd_m": self.gsd_m,
            "off_nadir_deg": self.orbit.off_nadir_deg,
            "range_m": self.orbit.range_m,
            "elevation_deg": self.orbit.elevation_deg,
            "nyquist_cy_per_mm": self.nyquist_alt_cy_per_mm,
            "nyquist_act_cy_per_mm": self.nyquist_act_cy_per_mm,
            "nyquist_alt_cy_per_mm": self.nyquist_alt_cy_per_mm,
            "nyquist_act_cy_per_m_ground": self.nyquist_act_cy_per_m_ground,
            "nyquist_alt_cy_per_m_ground": self.nyquist_alt_cy_per_m_ground,
            "wavelengths_m": lam.tolist(),
            "effective_wavelength_m": self.optics.effective_wavelength_m,
            "optical_cutoff_cy_per_mm": self.optical_cutoff_cy_per_mm.tolist(),
            "q": self.q.tolist(),
            "q_effective": self.q_effective,
            "airy_diameter_um": (self.airy_diameter_m * 1e6).tolist(),
            "airy_diameter_px": self.airy_diameter_px.tolist(),
            "limited_by": self.limited_by,
            "limited_by_criterion": self.limited_by_criterion,
            "ground_speed_m_per_s": self.orbit.ground_speed_m_per_s,
        }


_SECTIONS = ("orbit", "optics", "detector", "motion", "radiometry", "illumination", "atmosphere")

#: The pushbroom motion keys and their defaults: ``to_dict`` leaves them out at these values.
_TIME_KEYS = {
    "orbit": {"earth_rotation": False, "yaw_steering": False, "pass_direction": "descending"},
    "motion": {"line_rate_error": 0.0, "oscillation": [], "jitter_psd": []},
}


#: The detector keys that together give its pitches and active area (``replace`` sets them together).
_AREA_KEYS = ("pitch_m", "pitch_x_m", "pitch_y_m", "fill_factor", "active_width_x_m", "active_width_y_m")


def _set_detector_area(sub: dict[str, Any], new: dict[str, Any]) -> None:
    """Set the pitch and active-area keys ``new`` in a detector's dict (explicit pitches and widths).

    A ``fill_factor`` replaces both active widths; an active width not given keeps its fraction of its pitch
    (a new pitch scales it). Conflicting keys given together (fill factor and widths, ``pitch_m`` and another
    ``pitch_x_m``) are left for the detector's validator to name.
    """
    old_pitch = {ax: sub[f"pitch_{ax}_m"] for ax in "xy"}
    old_width = {ax: sub.pop(f"active_width_{ax}_m") for ax in "xy"}
    if "pitch_m" in new:
        for ax in "xy":
            if f"pitch_{ax}_m" not in new:
                sub.pop(f"pitch_{ax}_m")
    sub.update(new)
    if "fill_factor" in new:
        return
    for ax in "xy":
        if f"active_width_{ax}_m" in new:
            continue
        try:
            pitch = float(new.get(f"pitch_{ax}_m", new.get("pitch_m", old_pitch[ax])))
        except (TypeError, ValueError):
            continue  # the validator names the pitch
        if math.isfinite(pitch) and pitch > 0:
            sub[f"active_width_{ax}_m"] = old_width[ax] * (pitch / old_pitch[ax])


def _band_qe(band: Band, detector: Detector) -> tuple[Any, Any] | None:
    """``(qe, qe_wavelengths_m)`` of a band: its own QE (or the detector's) times its response, tabulated over the
    response's support; its own QE alone without a response; None when neither changes the detector's."""
    r = band.spectral_response
    if r is None:
        if band.qe is None:
            return None
        return band.qe, band.qe_wavelengths_m
    lam, resp = response_table(r)
    if isinstance(band.qe, tuple):
        lo, hi = lam[0], lam[-1]
        k = np.asarray(band.qe_wavelengths_m)  # Band._check: a qe table has its wavelengths
        lam = np.union1d(lam, k[(k > lo) & (k < hi)])
        resp = r(lam)
        qe = np.interp(lam, k, band.qe, left=0.0, right=0.0)
    elif band.qe is not None:
        qe = np.full(lam.shape, float(band.qe))
    else:
        qe = detector.qe_at(lam)
    return tuple(float(x) for x in np.clip(qe * resp, 0.0, 1.0)), tuple(float(x) for x in lam)


def _motion_in_pixels_of(motion: Motion, detector: Detector, pitch_m: float) -> Motion:
    """``motion`` (in ``detector``'s pixels) in pixels of pitch ``pitch_m``: the line-of-sight angles of the
    oscillations, jitter, jitter PSDs and log scaled by the pitch ratio. The smears stay in pixels: they are the
    motion over one integration time, which scales with the pitch as the line time does."""
    k = {"act": detector.pitch_x_m / pitch_m, "alt": detector.pitch_y_m / pitch_m}
    upd: dict[str, Any] = {"jitter_rms_px": motion.jitter_rms_px * math.sqrt(k["act"] * k["alt"])}
    upd["oscillation"] = tuple(
        o.model_copy(update={"amplitude_px": o.amplitude_px * k[o.axis]}) for o in motion.oscillation
    )
    upd["jitter_psd"] = tuple(
        j.model_copy(update={"psd_px2_per_hz": tuple(v * k[j.axis] ** 2 for v in j.psd_px2_per_hz)})
        for j in motion.jitter_psd
    )
    los = motion.line_of_sight
    if los is not None:
        upd["line_of_sight"] = los.model_copy(update={
            f"{ax}_px": tuple(v * k[ax] for v in getattr(los, f"{ax}_px") or ()) for ax in ("act", "alt")
        })  # fmt: skip
    return motion.model_copy(update=upd)


def _set(sub: dict[str, Any], field: str, value: Any, key: str) -> None:
    """Set ``field`` of a section's dict, following ``name[i].name`` into table lists."""
    parts = [p for p in field.replace("[", ".[").split(".") if p]
    node: Any = sub
    for i, part in enumerate(parts):
        last = i == len(parts) - 1
        slot: str | int = part
        if part.startswith("["):
            if not (part.endswith("]") and part[1:-1].isdigit()) or not isinstance(node, (list, tuple)):
                raise ConfigError(f"parameter {key!r}: {part!r} does not index a list of tables")
            idx = int(part[1:-1])
            if idx >= len(node):
                raise ConfigError(f"parameter {key!r}: index {idx} is beyond the {len(node)} entries")
            slot = idx
        elif not isinstance(node, dict) or (i > 0 and part not in node):
            raise ConfigError(f"parameter {key!r}: no field {part!r} there")
        if last:
            node[slot] = value
        else:
            child = node[slot]
            if isinstance(child, tuple):
                child = node[slot] = list(child)
            node = child


def _read_toml(path: str | Path) -> dict[str, Any]:
    from satchain._safety import check_input_file

    p = check_input_file(path, "system file")
    try:
        with p.open("rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise SatchainIOError(f"system file {str(p)!r}: not found") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"system file {str(p)!r}: not valid TOML ({exc})") from None
    except UnicodeDecodeError as exc:
        from satchain._safety import not_utf8

        raise not_utf8(p, exc, "system file") from None


def preset_names() -> list[str]:
    """Names of the packaged presets."""
    return sorted(
        r.name.removesuffix(".toml") for r in resources.files("satchain.presets").iterdir() if r.name.endswith(".toml")
    )


def load_preset(name: str) -> ImagingSystem:
    """Load a packaged preset by name (see :func:`preset_names`).

    Examples
    --------
    >>> load_preset("ankarasat3").optics.aperture_diameter_m
    0.7
    """
    names = preset_names()
    if name not in names:
        raise ConfigError(f"preset = {name!r}: must be one of {', '.join(map(repr, names))}")
    with resources.as_file(resources.files("satchain.presets") / f"{name}.toml") as p:
        return ImagingSystem.from_toml(p)


@checked
def load_system(path_or_preset: str | Path) -> ImagingSystem:
    """A preset name or a TOML file path."""
    s = str(path_or_preset)
    if s in preset_names():
        return load_preset(s)
    return ImagingSystem.from_toml(path_or_preset)
