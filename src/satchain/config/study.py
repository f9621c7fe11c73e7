"""The study file of ``satchain study``: a base run configuration, the axes its cases vary, and how they run.

```toml
[base]                                   # a run configuration: file = "run.toml" (relative to the study file),
file = "run.toml"                        # or its tables inline ([base.system], [base.scene], ...)
[[axes]]                                 # one or more: the cases are their cartesian product (or, zip = true,
key = "optics.aperture_diameter_m"       # their values taken together)
values = [0.35, 0.45, 0.55, 0.70]        # or start / stop / num (linspace), or start / stop / step
[study]
depth = "budget"                         # "budget": predictions only; "run": the whole chain per case
repeats = 1
zip = false
reports = "failed"
```

Every key is validated (unknown keys refused, values named with their allowed range, one
:class:`~satchain.errors.ConfigError` line); the cases themselves are expanded and validated by
:mod:`satchain.studies.cases`.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Any, Literal

from pydantic import ConfigDict, Field, ValidationError, field_validator, model_validator

from satchain.config._base import _config_error, _StrictNumbers, refuse_unknown_keys
from satchain.config.run import RunConfig, load_run_config
from satchain.errors import ConfigError, SatchainIOError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["Axis", "StudyFile", "StudySettings", "load_study"]

_TITLE = "invalid study file"
#: the most values one axis may hold (a typo in step or num, not a study)
MAX_AXIS_VALUES = 100_000


class _Frozen(_StrictNumbers):  # no bool, string or NaN where a number is wanted
    model_config = ConfigDict(frozen=True, extra="forbid")


class Axis(_Frozen):
    """One axis of a study: a key and its values, given as ``values``, ``start``/``stop``/``num`` (evenly
    spaced, both ends included) or ``start``/``stop``/``step`` (``start``, ``start + step``, ... up to ``stop``)."""

    key: str = Field(
        description="the key varied: a system key '<section>.<key>' (e.g. optics.aperture_diameter_m); at "
        "depth = 'run' also as_built.<section>.<key>, scene.pixel_m or simulation.seed"
    )
    values: tuple[float, ...] | None = Field(default=None, description="the values, listed (non-empty, finite)")
    start: float | None = Field(default=None, description="the first value (with stop and num, or stop and step)")
    stop: float | None = Field(default=None, description="the last value (with start and num, or start and step)")
    num: int | None = Field(
        default=None, ge=1, le=MAX_AXIS_VALUES, description="how many evenly spaced values from start to stop"
    )
    step: float | None = Field(
        default=None, description="the spacing of the values from start to stop (non-zero, toward stop)"
    )

    @field_validator("key")
    @classmethod
    def _dotted(cls, v: str) -> str:
        parts = v.split(".")
        if len(parts) < 2 or not all(p.strip() for p in parts):
            raise ValueError(f"key = {v!r}: must be a dotted key '<section>.<key>', e.g. optics.aperture_diameter_m")
        return v.strip()

    @model_validator(mode="after")
    def _one_form(self) -> Axis:
        k = self.key
        ranged = [n for n in ("start", "stop", "num", "step") if getattr(self, n) is not None]
        if self.values is not None:
            if ranged:
                raise ValueError(f"axis {k!r}: values and {', '.join(ranged)} are both given; give one form")
            if not self.values:
                raise ValueError(f"axis {k!r}: values = []: an axis needs at least one value")
            return self
        if not ranged:
            raise ValueError(f"axis {k!r}: give values = [...], or start, stop and num, or start, stop and step")
        if self.start is None or self.stop is None:
            raise ValueError(f"axis {k!r}: start and stop are both needed with num or step")
        if (self.num is None) == (self.step is None):
            both = "both" if self.num is not None else "neither"
            raise ValueError(f"axis {k!r}: give one of num (evenly spaced) or step, not {both}")
        if self.step is not None:
            span = self.stop - self.start
            if self.step == 0 or (span != 0 and (span > 0) != (self.step > 0)):
                raise ValueError(
                    f"axis {k!r}: step = {self.step!r}: must be non-zero and lead from start = {self.start!r} "
                    f"to stop = {self.stop!r}"
                )
            if span / self.step + 1 > MAX_AXIS_VALUES:
                raise ValueError(f"axis {k!r}: step = {self.step!r} gives more than {MAX_AXIS_VALUES} values")
        return self

    def expanded(self) -> tuple[float, ...]:
        """The axis' values, in order.

        Examples
        --------
        >>> Axis(key="optics.wfe_rms_waves", start=0.0, stop=0.1, step=0.05).expanded()
        (0.0, 0.05, 0.1)
        >>> Axis(key="optics.aperture_diameter_m", start=0.3, stop=0.7, num=3).expanded()
        (0.3, 0.5, 0.7)
        """
        if self.values is not None:
            return tuple(float(v) for v in self.values)
        assert self.start is not None and self.stop is not None
        a, b = float(self.start), float(self.stop)
        if self.num is not None:
            n = self.num
            if n == 1:
                return (a,)
            return tuple(a if i == 0 else b if i == n - 1 else _tidy(a + (b - a) * i / (n - 1)) for i in range(n))
        assert self.step is not None
        n = int(math.floor((b - a) / self.step + 1e-9)) + 1
        return tuple(_tidy(a + i * self.step) for i in range(n))


def _tidy(x: float) -> float:
    """``x`` without the last-digit noise of a sum (0.1 + 2 * 0.05 -> 0.2)."""
    return float(f"{x:.12g}")


class StudySettings(_Frozen):
    """``[study]``: how the cases run."""

    depth: Literal["budget", "run"] = Field(
        default="budget",
        description="'budget' (the default): the predicted budget per case only (fast); 'run': the whole chain "
        "per case (simulate, measure, compare)",
    )
    repeats: int = Field(
        default=1, ge=1, le=10_000, description="noise realisations per case (each its own seed, from the base seed)"
    )
    zip: bool = Field(
        default=False,
        description="true: the axes (of equal lengths) are taken together, value i of each in case i; false: "
        "their cartesian product",
    )
    reports: Literal["none", "failed", "all"] = Field(
        default="failed", description="which cases keep their report.html: none, failed (the default) or all"
    )


class StudyFile(_Frozen):
    """A study file: ``[base]``, ``[[axes]]`` and ``[study]``; ``base_dir`` is the study file's folder."""

    base: dict[str, Any] = Field(
        default_factory=dict,
        description="[base]: the run configuration the cases start from: file = 'run.toml' (relative to the "
        "study file), or its tables inline ([base.system], [base.scene], [base.simulation], ...); empty: the "
        "default run configuration",
    )
    axes: tuple[Axis, ...] = Field(description="[[axes]]: one or more axes, each a key and its values")
    study: StudySettings = Field(default_factory=StudySettings, description="[study]: how the cases run")
    base_dir: str = Field(default=".", exclude=True, description="the folder relative paths are relative to")

    @field_validator("base")
    @classmethod
    def _base(cls, v: dict[str, Any]) -> dict[str, Any]:
        if "file" in v:
            if not isinstance(v["file"], str):
                raise ValueError(f"base.file = {v['file']!r}: must be a run configuration file path (a string)")
            others = [k for k in v if k != "file"]
            if others:
                raise ValueError(f"base: file and {', '.join(others)} are both given; give a file or inline tables")
        return v

    @field_validator("axes")
    @classmethod
    def _axes(cls, v: tuple[Axis, ...]) -> tuple[Axis, ...]:
        if not v:
            raise ValueError("at least one [[axes]] is needed")
        keys = [a.key for a in v]
        twice = sorted({k for k in keys if keys.count(k) > 1})
        if twice:
            raise ValueError(f"key {twice[0]!r} is on more than one axis; give each key one axis")
        return v

    @classmethod
    def from_dict(cls, data: dict[str, Any], *, base_dir: str | Path = ".") -> StudyFile:
        refuse_unknown_keys(cls, data, _TITLE)
        try:
            return cls.model_validate({**data, "base_dir": str(base_dir)})
        except ValidationError as exc:
            raise ConfigError(str(_config_error(exc)).replace("invalid imaging system", _TITLE)) from None

    def run_config(self) -> RunConfig:
        """The base run configuration (validated; a file's errors name it)."""
        if "file" in self.base:
            return load_run_config(Path(self.base_dir) / self.base["file"])
        try:
            return RunConfig.from_dict(self.base, base_dir=self.base_dir)
        except ConfigError as exc:
            raise ConfigError(f"[base]: {exc}") from None

    def axis_values(self) -> dict[str, tuple[float, ...]]:
        """Each axis' key and its values, in the file's order."""
        return {a.key: a.expanded() for a in self.axes}


def load_study(path: str | Path) -> StudyFile:
    """Read and validate a study file (TOML); its base run configuration is read and validated too."""
    p = Path(path)
    if not p.is_file():
        raise SatchainIOError(f"study file {str(p)!r}: not found (or not a file)")
    try:
        data = tomllib.loads(p.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"study file {str(p)!r}: not valid TOML: {exc}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SatchainIOError(f"study file {str(p)!r}: cannot be read: {exc}") from None
    study = StudyFile.from_dict(data, base_dir=p.parent.resolve())
    study.run_config()
    return study
