"""The time-varying line-of-sight motion of a pushbroom TDI camera: ``[[motion.oscillation]]`` and
``[motion.jitter_psd]`` tables of the ``[motion]`` section, and the checks of the ``[orbit]`` keys of the
Earth's rotation (``latitude_deg``, ``inclination_deg``, ``earth_rotation``, ``yaw_steering``,
``pass_direction``). :mod:`satchain.sections` uses them; :mod:`satchain.tf.pushbroom` turns them into
exposure-averaged transfer functions and geometry.

Conventions (README, "Pushbroom TDI motion"): time ``t = 0`` is the start of the TDI window of image row 0;
row ``i`` integrates over ``[i dt, i dt + N dt]`` (``dt`` the line time, ``N`` the TDI stages). A line-of-sight
offset of ``+a`` px on an axis means every pixel sees the scene point ``a`` px further along ``+x`` (ACT, the
columns) or ``+y`` (ALT, the rows), so image features move by ``-a``. Amplitudes are in detector pixels of
that axis (the GSD on the ground).
"""

from __future__ import annotations

import math
from typing import Any, Literal

from pydantic import Field, model_validator

from satchain._sections_base import _Frozen

__all__ = ["MAX_FREQUENCY_HZ", "JitterPSD", "Oscillation", "check_earth_rotation"]

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

    axis: Literal["act", "alt"]
    amplitude_px: float = Field(ge=0, le=1000, description="zero-to-peak, detector pixels on the ground")
    frequency_hz: float = Field(gt=0, le=MAX_FREQUENCY_HZ)
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

    axis: Literal["act", "alt"]
    frequency_hz: tuple[float, ...] = Field(min_length=2, max_length=10000)
    psd_px2_per_hz: tuple[float, ...] = Field(min_length=2, max_length=10000)

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
