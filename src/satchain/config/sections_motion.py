"""The time-varying line-of-sight motion of a pushbroom TDI camera: ``[[motion.oscillation]]`` and
``[motion.jitter_psd]`` tables of the ``[motion]`` section, and the checks of the ``[orbit]`` keys of the
Earth's rotation (``latitude_deg``, ``inclination_deg``, ``earth_rotation``, ``yaw_steering``,
``pass_direction``). :mod:`satchain.config.sections` uses them; :mod:`satchain.tf.pushbroom` turns them into
exposure-averaged transfer functions and geometry.

Conventions (README, "Pushbroom TDI motion"): time ``t = 0`` is the start of the TDI window of image row 0;
row ``i`` integrates over ``[i dt, i dt + N dt]`` (``dt`` the line time, ``N`` the TDI stages). A line-of-sight
offset of ``+a`` px on an axis means every pixel sees the scene point ``a`` px further along ``+x`` (ACT, the
columns) or ``+y`` (ALT, the rows), so image features move by ``-a``. Amplitudes are in detector pixels of
that axis (the GSD on the ground).
"""

from __future__ import annotations

import math
from typing import Any, ClassVar, Literal

import numpy as np
from pydantic import Field, model_validator

from satchain.config._base import _Frozen, schema_bounds
from satchain.errors import ConfigError, SatchainIOError

__all__ = ["MAX_FREQUENCY_HZ", "JitterPSD", "LineOfSightLog", "Oscillation", "check_earth_rotation", "read_los_csv"]

#: The longest line-of-sight log accepted (samples).
MAX_LOG_SAMPLES = 2_000_000

#: The highest line-of-sight frequency accepted (the time path samples as finely as the highest one needs).
MAX_FREQUENCY_HZ = 1e6


class Oscillation(_Frozen):
    """One sinusoidal line-of-sight motion ``x(t) = amplitude_px sin(2 pi frequency_hz t + phase_deg)`` along
    ``axis`` (``"act"`` = x, ``"alt"`` = y), ``t = 0`` at the start of row 0's TDI window.

    Examples
    --------
    >>> Oscillation(axis="act", amplitude_px=0.5, frequency_hz=4465.0).phase_deg
    0.0
    """

    axis: Literal["act", "alt"] = Field(
        description="the axis the line of sight moves along: 'act' (x, across-track, the columns) or 'alt' (y, "
        "along-track, the rows)"
    )
    amplitude_px: float = Field(ge=0, le=1000, description="zero-to-peak, detector pixels on the ground")
    frequency_hz: float = Field(gt=0, le=MAX_FREQUENCY_HZ, description="frequency of the sinusoid")
    phase_deg: float = Field(default=0.0, ge=-360, le=360, description="phase at t = 0")


class JitterPSD(_Frozen):
    """Random (Gaussian, stationary) line-of-sight motion along ``axis`` with a one-sided power spectral density
    ``psd_px2_per_hz`` (px^2/Hz) at ``frequency_hz``, linear between the points and zero outside them; its
    variance is the area under it. Several tables (on one axis or both) are independent motions that add.

    Examples
    --------
    >>> p = JitterPSD(axis="act", frequency_hz=[5e3, 5e4], psd_px2_per_hz=[3.6e-6, 3.6e-6])
    >>> round(p.variance_px2, 4)
    0.162
    """

    axis: Literal["act", "alt"] = Field(
        description="the axis the line of sight moves along: 'act' (x, across-track, the columns) or 'alt' (y, "
        "along-track, the rows)"
    )
    frequency_hz: tuple[float, ...] = Field(
        min_length=2,
        max_length=10000,
        description="frequencies of the PSD's points, strictly increasing, each in (0, 1e+06] Hz",
        json_schema_extra=schema_bounds(items={"exclusiveMinimum": 0, "maximum": MAX_FREQUENCY_HZ}),
    )
    psd_px2_per_hz: tuple[float, ...] = Field(
        min_length=2,
        max_length=10000,
        description="one-sided power spectral density at each frequency_hz, each >= 0, linear between the points and "
        "0 outside them; its area, the variance, at most 1e6 px^2",
        json_schema_extra=schema_bounds(items={"minimum": 0}),
    )

    @model_validator(mode="after")
    def _table(self) -> JitterPSD:
        f, p = self.frequency_hz, self.psd_px2_per_hz
        if len(f) != len(p):
            raise ValueError(
                f"psd_px2_per_hz has {len(p)} values but frequency_hz has {len(f)}: give one PSD value per frequency"
            )
        if any(b <= a for a, b in zip(f[:-1], f[1:], strict=True)):
            raise ValueError(f"frequency_hz = {list(f)!r}: must be strictly increasing")
        if f[0] <= 0 or f[-1] > MAX_FREQUENCY_HZ:
            raise ValueError(f"frequency_hz = {list(f)!r}: must lie in (0, {MAX_FREQUENCY_HZ:g}] Hz")
        if min(p) < 0:
            raise ValueError(f"psd_px2_per_hz = {list(p)!r}: must be >= 0 (a power spectral density)")
        if self.variance_px2 > 1e6:
            raise ValueError(
                f"psd_px2_per_hz: the variance {self.variance_px2:.3g} px^2 is beyond 1e6 px^2 (1000 px rms)"
            )
        return self

    @property
    def variance_px2(self) -> float:
        """The motion's variance, the area under the PSD (px^2)."""
        f, p = self.frequency_hz, self.psd_px2_per_hz
        return float(sum(0.5 * (p[k] + p[k + 1]) * (f[k + 1] - f[k]) for k in range(len(f) - 1)))


class LineOfSightLog(_Frozen):
    """A measured line of sight, e.g. from an attitude log: ``act_px`` / ``alt_px`` (detector pixels, either
    may be left out: zero) at ``time_s``, linear between the samples. ``time_offset_s`` is the log's time at
    ``t = 0``, the start of row 0's TDI window; the log must cover the whole scan. ``file = "log.csv"`` reads the
    columns ``time_s``, ``act_px``, ``alt_px`` (a header row naming them; ``#`` comments) when the system is
    loaded, relative to the system file: the system then holds the samples (self-contained).

    Examples
    --------
    >>> log = LineOfSightLog(time_s=[0.0, 0.01, 0.02], act_px=[0.0, 0.5, 0.0])
    >>> log.alt_px, log.duration_s
    ((0.0, 0.0, 0.0), 0.02)
    """

    _input_keys: ClassVar[tuple[str, ...]] = ("file",)  # read into time_s, act_px, alt_px by _file

    time_s: tuple[float, ...] = Field(
        min_length=2,
        max_length=MAX_LOG_SAMPLES,
        description="the log's sample times, finite and strictly increasing (time_offset_s is the log's time at t = 0)",
    )
    act_px: tuple[float, ...] | None = Field(
        default=None,
        max_length=MAX_LOG_SAMPLES,
        description="line-of-sight offset across-track (x) at each time_s, each within +-1000 px; default: 0",
        json_schema_extra=schema_bounds(items={"minimum": -1000, "maximum": 1000}),
    )
    alt_px: tuple[float, ...] | None = Field(
        default=None,
        max_length=MAX_LOG_SAMPLES,
        description="line-of-sight offset along-track (y) at each time_s, each within +-1000 px; default: 0",
        json_schema_extra=schema_bounds(items={"minimum": -1000, "maximum": 1000}),
    )
    time_offset_s: float = Field(default=0.0, ge=-1e9, le=1e9, description="the log's time at t = 0")

    @model_validator(mode="before")
    @classmethod
    def _file(cls, data: Any) -> Any:
        if isinstance(data, dict) and "file" in data:
            data = dict(data)
            table = read_los_csv(data.pop("file"))
            for key in ("time_s", "act_px", "alt_px"):
                if key in data:
                    raise ValueError(f"motion.line_of_sight: give either file or {key}, not both")
            data.update(table)
        return data

    @model_validator(mode="after")
    def _table(self) -> LineOfSightLog:
        t = self.time_s
        if self.act_px is None and self.alt_px is None:
            raise ValueError("motion.line_of_sight: needs act_px, alt_px or both (detector pixels at time_s)")
        if self.act_px is None:
            object.__setattr__(self, "act_px", (0.0,) * len(t))
        if self.alt_px is None:
            object.__setattr__(self, "alt_px", (0.0,) * len(t))
        for key in ("act_px", "alt_px"):
            v = getattr(self, key)
            if len(v) != len(t):
                raise ValueError(f"{key} has {len(v)} values but time_s has {len(t)}: give one per time")
            if not all(math.isfinite(x) and abs(x) <= 1000 for x in v):
                raise ValueError(f"{key}: every value must be finite and within +-1000 px")
        if not all(math.isfinite(x) for x in t) or any(b <= a for a, b in zip(t[:-1], t[1:], strict=True)):
            raise ValueError("time_s: must be finite and strictly increasing")
        return self

    @property
    def duration_s(self) -> float:
        return float(self.time_s[-1] - self.time_s[0])

    def at(self, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(act, alt)`` px at the scan times ``t_s`` (``t = 0``: row 0's window starts), linear between the
        samples; a ConfigError when the log does not cover them."""
        t = np.asarray(self.time_s, dtype=float)
        u = np.asarray(t_s, dtype=float) + self.time_offset_s
        if u.size and (u.min() < t[0] - 1e-12 or u.max() > t[-1] + 1e-12):
            raise ConfigError(
                f"motion.line_of_sight: the log covers {t[0]:.6g} .. {t[-1]:.6g} s, the scan needs "
                f"{u.min():.6g} .. {u.max():.6g} s (time_offset_s = {self.time_offset_s:g} at row 0's window): "
                "give a longer log, a smaller scene or another time_offset_s"
            )
        assert self.act_px is not None and self.alt_px is not None  # _table fills both
        return np.interp(u, t, self.act_px), np.interp(u, t, self.alt_px)


def read_los_csv(path: Any) -> dict[str, tuple[float, ...]]:
    """The columns ``time_s`` and ``act_px`` / ``alt_px`` of a CSV line-of-sight log (header row, ``#``
    comments), for :class:`LineOfSightLog`."""
    from pathlib import Path

    p = Path(str(path))
    if not p.is_file():
        what = "a folder, not a file; give the CSV log" if p.is_dir() else "not found"
        raise SatchainIOError(f"motion.line_of_sight.file = {str(p)!r}: {what}")
    try:
        lines = [
            ln for ln in p.read_text(encoding="utf-8").splitlines() if ln.strip() and not ln.lstrip().startswith("#")
        ]
        names = [n.strip().lower() for n in lines[0].split(",")] if lines else []
        arr = np.loadtxt(lines[1:], delimiter=",", ndmin=2, dtype=float) if len(lines) > 1 else np.zeros((0, 0))
    except (ValueError, UnicodeDecodeError) as exc:
        raise ConfigError(f"motion.line_of_sight.file = {str(p)!r}: not a CSV of numbers ({exc})") from None
    if "time_s" not in names or not {"act_px", "alt_px"} & set(names):
        raise ConfigError(
            f"motion.line_of_sight.file = {str(p)!r}: its header names {names}; need time_s and act_px and/or alt_px"
        )
    if arr.shape[1] != len(names):
        raise ConfigError(
            f"motion.line_of_sight.file = {str(p)!r}: {arr.shape[1]} columns, the header names {len(names)}"
        )
    out: dict[str, tuple[float, ...]] = {}
    for key in ("time_s", "act_px", "alt_px"):
        if key in names:
            v = arr[:, names.index(key)]
            if not np.all(np.isfinite(v)):
                raise ConfigError(f"motion.line_of_sight.file = {str(p)!r}: column {key} has non-finite values")
            out[key] = tuple(float(x) for x in v)
    return out


def as_tables(value: Any) -> Any:
    """One ``[motion.jitter_psd]`` table, or ``[[motion.jitter_psd]]`` tables: always a sequence of them."""
    return (value,) if isinstance(value, dict) or isinstance(value, JitterPSD) else value


def check_earth_rotation(orbit: Any) -> None:
    """Refuse ``[orbit]`` Earth-rotation keys that do not describe a pass: ``earth_rotation = true`` needs
    ``latitude_deg`` and ``inclination_deg``; the latitude must be one the orbit reaches
    (``|latitude| <= min(i, 180 - i)``); ``yaw_steering`` needs ``earth_rotation``."""
    lat, inc = orbit.latitude_deg, orbit.inclination_deg
    if orbit.earth_rotation:
        for key, v, why in (
            ("latitude_deg", lat, "the Earth's surface speed, omega R cos(latitude), depends on it"),
            ("inclination_deg", inc, "the ground track's heading depends on it"),
        ):
            if v is None:
                raise ValueError(f"orbit.earth_rotation = true needs orbit.{key} ({why})")
    elif orbit.yaw_steering:
        raise ValueError(
            "orbit.yaw_steering = true needs orbit.earth_rotation = true (it steers out the Earth's motion)"
        )
    if lat is not None and inc is not None:
        reach = min(inc, 180.0 - inc)
        if abs(lat) > reach + 1e-9:
            raise ValueError(
                f"orbit.latitude_deg = {lat!r}: an orbit of inclination {inc:g} deg reaches latitudes within "
                f"[-{reach:g}, {reach:g}] deg"
            )


def cos_heading(orbit: Any) -> tuple[float, float]:
    """(east, north) components of the ground track's unit direction at ``latitude_deg`` of a circular orbit
    of ``inclination_deg``: ``sin(Az) = cos(i) / cos(lat)``, north positive on an ascending pass."""
    lat, inc = math.radians(orbit.latitude_deg), math.radians(orbit.inclination_deg)
    east = math.cos(inc) / math.cos(lat) if math.cos(lat) > 0 else 0.0
    east = max(-1.0, min(1.0, east))
    north = math.sqrt(max(0.0, 1.0 - east * east))
    return east, north if orbit.pass_direction == "ascending" else -north
