"""The configuration of one ``satchain run``: system, scene, simulation, measurement and tolerances.

One TOML file holds everything; ``satchain run --print-config`` prints the default to start from. Every
key is validated (unknown keys are refused, values name their allowed range).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any, Literal

from pydantic import ConfigDict, Field, ValidationError, field_validator, model_validator

from satchain.config._base import refuse_unknown_keys
from satchain.config.sections import _StrictNumbers
from satchain.config.system import ImagingSystem, _config_error, load_preset
from satchain.errors import ConfigError, SatchainIOError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["DEFAULT_CONFIG_TOML", "RunConfig", "load_run_config", "system_differences"]


class _Frozen(_StrictNumbers):  # no bool, string or NaN where a number is wanted
    model_config = ConfigDict(frozen=True, extra="forbid")


class SystemRef(_Frozen):
    """``preset`` (a packaged name), or ``file`` (a system TOML, relative to the config), or ``inline``."""

    preset: str | None = Field(
        default="ankarasat3", description="a packaged system by name (the default, 'ankarasat3': the paper's camera)"
    )
    file: str | None = Field(default=None, description="a system TOML file, relative to this configuration file")
    inline: dict[str, Any] | None = Field(default=None, description="the system itself, as a system file holds it")

    @model_validator(mode="before")
    @classmethod
    def _one(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            return data
        given = [k for k in ("preset", "file", "inline") if data.get(k) is not None]
        if len(given) > 1:
            raise ValueError(f"system: {' and '.join(given)} are both given; give one of preset, file or inline")
        if given and given[0] != "preset":
            data = {**data, "preset": None}  # the default preset does not apply when a file or inline is given
        return data


class SceneConfig(_Frozen):
    """The ground-truth scene: its layout of targets and its sampling."""

    layout: str = Field(default="paper", description="'paper' or a scene file (.toml/.json)")
    pixel_m: float = Field(
        default=0.035,
        gt=0,
        le=100,
        description="ground-truth pixel size, m (the paper's 3.5 cm, GSD/14); objects smaller than the GSD need "
        "about GSD/28 for 1e-3 of their image's peak",
    )
    overview_pixel_m: float = Field(default=0.25, gt=0, le=100, description="pixel size of the Figure 1 overview")


class SimulationConfig(_Frozen):
    """How the image is simulated: its units, noise and borders."""

    units: Literal["dn", "electrons", "radiance", "reflectance"] = Field(
        default="dn",
        description="unit of the simulated image: 'dn' (the detector's ADC counts), 'electrons', 'radiance' "
        "(top-of-atmosphere, in band, W/(m^2 sr)) or 'reflectance' (the ground truth's own unit)",
    )
    noise: bool = Field(
        default=True,
        description="add the detector's noise (shot, dark, read, PRNU/DSNU); false: a noise-free image, for which "
        "no SNR (nor NIIRS) is measured",
    )
    seed: int = Field(
        default=20260101,
        ge=0,
        description="seed of the noise and of the random line-of-sight motion (an integer, no unit): one seed, "
        "one image",
    )
    far_margin_px: int = Field(
        default=128,
        ge=0,
        le=100_000,
        description="output pixels of border context around the ground truth (continued by the border rule), "
        "within which the PSF's tails are exact",
    )
    border: Literal["symmetric", "periodic", "constant"] = Field(
        default="symmetric",
        description="how the ground truth is continued beyond its edge: 'symmetric' (mirrored), 'periodic' "
        "(wrapped) or 'constant' (0)",
    )


class MeasurementConfig(_Frozen):
    """Settings of the measurements."""

    wedge_threshold: float = Field(
        default=0.15,
        gt=0,
        lt=1,
        description="contrast (dimensionless) at which a hyperbolic wedge stops resolving: the paper's threshold "
        "(Rayleigh)",
    )


class Tolerances(_Frozen):
    """Pass/fail limits of measured vs predicted figures of merit (absolute unless said otherwise)."""

    edge_mtf_at_nyquist: float = Field(
        default=0.02,
        gt=0,
        description="largest |measured - predicted| MTF at Nyquist of a slanted edge that passes (MTF, dimensionless)",
    )
    edge_angle_deg: float = Field(
        default=0.2, gt=0, description="largest |measured - true| angle of a slanted edge that passes"
    )
    star_mtf: float = Field(
        default=0.05,
        gt=0,
        description="largest |measured - predicted| MTF of a Siemens star up to Nyquist, in its worst direction, "
        "that passes (MTF, dimensionless)",
    )
    bar_ctf: float = Field(
        default=0.06,
        gt=0,
        description="largest |measured - predicted| CTF of a bar target up to 0.4 cy/px that passes (CTF, "
        "dimensionless)",
    )
    wedge_resolution_rel: float = Field(
        default=0.15,
        gt=0,
        description="largest |measured / predicted - 1| resolution of a hyperbolic wedge that passes (a ratio, "
        "dimensionless: 0.15 is 15 %)",
    )
    niirs: float = Field(
        default=0.2,
        gt=0,
        description="largest |measured - predicted| NIIRS (GIQE 5) that passes, in NIIRS levels (dimensionless)",
    )
    band_snr_rel: float = Field(
        default=0.05,
        gt=0,
        description="largest |measured / predicted - 1| SNR of a band of a [[bands]] system that passes (a ratio, "
        "dimensionless: 0.05 is 5 %)",
    )
    registration_px: float = Field(
        default=0.05,
        gt=0,
        description="largest |measured - predicted| offset of a band from the PAN band that passes, per axis, in "
        "the band's own pixels",
    )


class RunConfig(_Frozen):
    """Everything one run needs; a frozen, validated object.

    ``as_built`` (optional): the camera as built, a partial system (the sections and keys of a system file,
    e.g. ``{"motion": {"smear_px": 3.0}}``) and/or ``file`` (a system file, relative to the config) deep-merged
    over the design ``system``; it is applied to the simulation only, every prediction uses ``system``
    (:meth:`load_as_built_system`).
    """

    system: SystemRef = Field(
        default_factory=SystemRef, description="[system]: the camera designed, a preset, a system file or inline"
    )
    as_built: dict[str, Any] | None = Field(
        default=None,
        description="the camera as built: a system file (file) and/or its sections, merged over [system]; applied "
        "to the simulation only",
    )
    scene: SceneConfig = Field(default_factory=SceneConfig, description="[scene]: the ground truth")
    simulation: SimulationConfig = Field(
        default_factory=SimulationConfig, description="[simulation]: units, noise and borders of the image"
    )
    measurement: MeasurementConfig = Field(
        default_factory=MeasurementConfig, description="[measurement]: settings of the measurements"
    )
    tolerances: Tolerances = Field(
        default_factory=Tolerances, description="[tolerances]: pass/fail limits of measured vs predicted"
    )
    base_dir: str = Field(default=".", description="directory that relative paths are resolved against")

    @field_validator("as_built")
    @classmethod
    def _as_built_shape(cls, v: dict[str, Any] | None) -> dict[str, Any] | None:
        if v is None:
            return v
        for key, value in v.items():
            if key == "file":
                if not isinstance(value, str) or not value:
                    raise ValueError(f"as_built.file = {value!r}: must be a system file path (a string)")
            elif key not in _SYSTEM_SECTIONS:
                raise ValueError(
                    f"as_built.{key}: unknown key; allowed: file, {', '.join(_SYSTEM_SECTIONS)} (the sections of a "
                    "system file)"
                )
            elif not isinstance(value, dict):
                raise ValueError(f"as_built.{key} = {value!r}: must be a table of {key} keys, e.g. {{ ... }}")
        return v

    @classmethod
    def from_dict(cls, data: dict[str, Any], *, base_dir: str | Path = ".") -> RunConfig:
        refuse_unknown_keys(cls, data, "invalid run configuration")
        try:
            return cls.model_validate({**data, "base_dir": str(base_dir)})
        except ValidationError as exc:
            err = _config_error(exc)
            raise ConfigError(str(err).replace("invalid imaging system", "invalid run configuration")) from None

    def load_system(self) -> ImagingSystem:
        ref = self.system
        if ref.inline is not None:
            return ImagingSystem.from_dict(ref.inline)
        if ref.file is not None:
            return ImagingSystem.from_toml(Path(self.base_dir) / ref.file)
        return load_preset(ref.preset or "ankarasat3")

    def as_built_path(self) -> Path | None:
        """The as-built system file this configuration reads (absolute), or None."""
        f = (self.as_built or {}).get("file")
        return None if f is None else (Path(self.base_dir) / f).resolve()

    def load_as_built_system(self, design: ImagingSystem | None = None) -> ImagingSystem | None:
        """The camera as built (``as_built`` merged over the design system), or None when there is no
        ``as_built``. Validated as a system file is; errors name the ``as_built.<section>.<key>``."""
        if self.as_built is None:
            return None
        design = self.load_system() if design is None else design
        sections: dict[str, dict[str, Any]] = {}
        path = self.as_built_path()
        if path is not None:
            design, sections = _as_built_file(path, design)
        for key, value in self.as_built.items():
            if key != "file":
                sections[key] = _deep_merge(sections.get(key, {}), value)
        return _merge_system(design, sections)

    def layout_source(self) -> str:
        if self.scene.layout == "paper":
            return "paper"
        return str(Path(self.base_dir) / self.scene.layout)

    def to_dict(self) -> dict[str, Any]:
        return self.model_dump(mode="json", exclude={"base_dir"}, exclude_none=True)

    def system_path(self) -> Path | None:
        """The system file this configuration reads (absolute), or None."""
        return None if self.system.file is None else (Path(self.base_dir) / self.system.file).resolve()

    def absolute(self) -> RunConfig:
        """The same configuration with its system and scene files as absolute paths (valid from anywhere)."""
        d = self.to_dict()
        if self.system.file is not None:
            d["system"] = {"file": str(self.system_path())}
        if self.as_built is not None and "file" in self.as_built:
            d["as_built"] = {**d["as_built"], "file": str(self.as_built_path())}
        if self.scene.layout != "paper":
            d["scene"] = {**d["scene"], "layout": str(Path(self.layout_source()).resolve())}
        return RunConfig.from_dict(d, base_dir=Path(self.base_dir).resolve())


_SYSTEM_SECTIONS = ("orbit", "optics", "detector", "motion", "radiometry", "illumination", "atmosphere")
#: Keys a system section accepts besides its fields (the system file's shorthands).
_SHORTHANDS = {"optics": ("wavelength_m",), "detector": ("pitch_m", "fill_factor")}


def _as_built_file(path: Path, design: ImagingSystem) -> tuple[ImagingSystem, dict[str, dict[str, Any]]]:
    """What an ``[as_built] file`` gives: ``(base, sections)``. A complete system file (one that is valid on its
    own) is the camera as built: ``(its system, {})``; a partial one is ``(design, its sections)``, to be merged
    over the design. A ``[motion.line_of_sight] file`` in it is relative to it, as in a system file."""
    from satchain.config.system import _read_toml

    try:
        data = _read_toml(path)
    except (ConfigError, SatchainIOError) as exc:
        raise type(exc)(f"as_built.file: {exc}") from None
    los = data.get("motion", {}).get("line_of_sight") if isinstance(data.get("motion"), dict) else None
    if isinstance(los, dict) and isinstance(los.get("file"), str):
        los["file"] = str((path.parent / los["file"]).resolve())
    try:
        return ImagingSystem.from_dict(data), {}
    except ConfigError:
        pass  # not a camera on its own: its sections are merged over the design (and named if invalid there)
    sections: dict[str, dict[str, Any]] = {}
    for key, value in data.items():
        if key in _SYSTEM_SECTIONS and isinstance(value, dict):
            sections[key] = dict(value)
        elif key not in ("name", "description", "provenance"):
            raise ConfigError(f"as_built.file {str(path)!r}: {key}: unknown key (a system file's sections)")
    return design, sections


def _deep_merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for k, v in over.items():
        out[k] = _deep_merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


def _merge_system(design: ImagingSystem, sections: dict[str, dict[str, Any]]) -> ImagingSystem:
    """``design`` with the keys of ``sections`` replaced (nested tables merged), validated."""
    import re

    current = design.model_dump(mode="python")
    flat: dict[str, Any] = {}
    for section, values in sections.items():
        model = type(getattr(design, section))
        allowed = set(model.model_fields) | set(_SHORTHANDS.get(section, ()))
        for key, value in values.items():
            if key not in allowed:
                raise ConfigError(f"as_built.{section}.{key}: unknown key; {section} has {', '.join(sorted(allowed))}")
            old = current[section].get(key)
            nested = isinstance(value, dict) and isinstance(old, dict)
            flat[f"{section}.{key}"] = _deep_merge(old, value) if nested else value
    try:
        return design.replace(flat)
    except ConfigError as exc:
        names = "|".join(_SYSTEM_SECTIONS)
        msg = re.sub(rf"(^|; )({names})\.", r"\1as_built.\2.", str(exc).removeprefix("invalid imaging system: "))
        raise ConfigError(f"invalid as-built system: {msg}") from None


def system_differences(design: ImagingSystem, built: ImagingSystem | None) -> list[dict[str, Any]]:
    """The parameters where ``built`` differs from ``design``: ``[{"key", "design", "as_built"}]`` (dotted keys of
    the system file; name, description and provenance left out); empty when ``built`` is None.

    Examples
    --------
    >>> from satchain.config.system import load_preset
    >>> d = load_preset("ankarasat3")
    >>> system_differences(d, d.replace({"motion.smear_px": 3.0}))
    [{'key': 'motion.smear_px', 'design': 1.0325, 'as_built': 3.0}]
    """
    if built is None:
        return []

    def flat(d: dict[str, Any], prefix: str = "") -> dict[str, Any]:
        out: dict[str, Any] = {}
        for k, v in d.items():
            if not prefix and k in ("name", "description", "provenance"):
                continue
            out.update(flat(v, f"{prefix}{k}.") if isinstance(v, dict) else {f"{prefix}{k}": v})
        return out

    a, b = flat(design.to_dict()), flat(built.to_dict())
    return [
        {"key": k, "design": a.get(k), "as_built": b.get(k)} for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)
    ]


DEFAULT_CONFIG_TOML = """\
# satchain run configuration. Every key is optional; these are the defaults.
[system]                       # one of: preset = "ankarasat3" (the default), file = "mycamera.toml", inline
preset = "ankarasat3"

# [as_built]                   # optional: the camera as built, simulated instead of the design (predictions
# file = "built.toml"          #   still use [system]): a system file and/or keys of its sections, e.g.
# motion = { smear_px = 3.0 }  #   merged over [system]; results.json and report.html list what differs

[scene]
layout = "paper"               # the reference paper's Figure 1 layout, or a scene file (.toml / .json)
pixel_m = 0.035                # ground-truth pixel size (m)
overview_pixel_m = 0.25        # pixel size of the Figure 1 overview image (m)

[simulation]
units = "dn"                   # dn | electrons | radiance | reflectance
noise = true
seed = 20260101
far_margin_px = 128            # output pixels of border context (PSF tails)
border = "symmetric"           # symmetric | periodic | constant

[measurement]
wedge_threshold = 0.15         # the paper's contrast threshold (Rayleigh)

[tolerances]                   # |measured - predicted| for pass/fail
edge_mtf_at_nyquist = 0.02
edge_angle_deg = 0.2
star_mtf = 0.05
bar_ctf = 0.06
wedge_resolution_rel = 0.15    # relative
niirs = 0.2
band_snr_rel = 0.05            # relative; a [[bands]] system's SNR per band
registration_px = 0.05         # a band's offset from the PAN band, per axis, in its own pixels
"""


def load_run_config(path: str | Path | None) -> RunConfig:
    """The default configuration, or a TOML file (relative paths inside it are relative to the file)."""
    if path is None:
        return RunConfig()
    from satchain._safety import check_input_file

    p = check_input_file(path, "--config")
    try:
        with p.open("rb") as fh:
            data = tomllib.load(fh)
    except FileNotFoundError:
        raise SatchainIOError(f"--config {str(p)!r}: not found") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"--config {str(p)!r}: not valid TOML ({exc})") from None
    except UnicodeDecodeError as exc:
        from satchain._safety import not_utf8

        raise not_utf8(p, exc, "--config") from None
    return RunConfig.from_dict(data, base_dir=p.parent)


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f'"{k}" = {_toml_value(x)}' for k, x in v.items()) + " }"
    raise ConfigError(f"cannot write {v!r} to TOML")


def _toml_table(name: str, d: dict[str, Any], lines: list[str]) -> None:
    scalars = {k: v for k, v in d.items() if not isinstance(v, dict) or not v or name.endswith("zernike_rms_waves")}
    tables = {k: v for k, v in d.items() if k not in scalars}
    lines.append(f"[{name}]")
    lines.extend(f"{k} = {_toml_value(v)}" for k, v in scalars.items())
    lines.append("")
    for k, v in tables.items():
        _toml_table(f"{name}.{k}", v, lines)


def config_to_toml(config: RunConfig) -> str:
    """The configuration as TOML that :func:`load_run_config` reads back to an equal object.

    Examples
    --------
    >>> import tomllib
    >>> RunConfig.from_dict(tomllib.loads(config_to_toml(RunConfig()))) == RunConfig()
    True
    """
    lines = ["# satchain run configuration (written by satchain; reproduces this run)"]
    for section, values in config.absolute().to_dict().items():
        _toml_table(section, values, lines)
    return "\n".join(lines)
