"""Small validation helpers that produce errors naming the parameter, the value and the allowed range."""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from satchain.errors import ConfigError, InputError


def _interval(lo: float | None, hi: float | None, lo_open: bool, hi_open: bool) -> str:
    left = "(" if lo_open or lo is None else "["
    right = ")" if hi_open or hi is None else "]"
    lo_s = "-inf" if lo is None else f"{lo:g}"
    hi_s = "inf" if hi is None else f"{hi:g}"
    return f"{left}{lo_s}, {hi_s}{right}"


def check_range(
    name: str,
    value: float,
    lo: float | None = None,
    hi: float | None = None,
    *,
    lo_open: bool = False,
    hi_open: bool = False,
    error: type[Exception] = ConfigError,
) -> float:
    """Return ``float(value)`` if it is finite and in the interval, else raise naming ``name``.

    Examples
    --------
    >>> check_range("optics.obscuration_ratio", 0.3, 0, 1, hi_open=True)
    0.3
    """
    allowed = _interval(lo, hi, lo_open, hi_open)
    if isinstance(value, (bool, np.bool_, str, bytes)):
        kind = "a boolean" if isinstance(value, (bool, np.bool_)) else "a string"
        raise error(f"{name} = {value!r}: must be a number in {allowed}, not {kind}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise error(f"{name} = {value!r}: must be a number in {allowed}") from None
    if not math.isfinite(v):
        raise error(f"{name} = {value!r}: not a finite number; must be in {allowed}")
    bad = False
    if lo is not None:
        bad |= v <= lo if lo_open else v < lo
    if hi is not None:
        bad |= v >= hi if hi_open else v > hi
    if bad:
        raise error(f"{name} = {value!r}: must be in {_interval(lo, hi, lo_open, hi_open)}")
    return v


def check_positive(name: str, value: float, *, error: type[Exception] = ConfigError) -> float:
    """Finite and strictly positive."""
    return check_range(name, value, 0.0, None, lo_open=True, error=error)


def check_choice(name: str, value: str, choices: Iterable[str], *, error: type[Exception] = ConfigError) -> str:
    """``value`` must be one of ``choices``."""
    choices = tuple(choices)
    if value not in choices:
        raise error(f"{name} = {value!r}: must be one of {', '.join(map(repr, choices))}")
    return value


def as_float_array(name: str, value, *, ndim: int | None = None, finite: bool = True) -> np.ndarray:
    """Convert to a float64 array, refusing NaN/inf (when ``finite``) and wrong dimensionality."""
    _check_array_like(name, value)
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{name}: cannot be converted to a numeric array") from None
    if ndim is not None and a.ndim != ndim:
        raise InputError(f"{name}: must be {ndim}-D, got shape {a.shape}")
    if finite and a.size and not np.all(np.isfinite(a)):
        n = int(np.count_nonzero(~np.isfinite(a)))
        raise InputError(f"{name}: contains {n} NaN/inf value(s); all values must be finite")
    return a


def _check_array_like(name: str, value) -> None:
    """Refuse, naming the parameter, what is not an array of numbers: None, a path or string (a file name
    where the image's pixels are wanted), a mapping, a boolean or complex/object/string array."""
    import os
    from collections.abc import Mapping

    if value is None or isinstance(value, (str, bytes, os.PathLike, Mapping, bool)):
        shown = repr(value) if not isinstance(value, Mapping) else f"a {type(value).__name__}"
        path = isinstance(value, (str, os.PathLike)) and "image" in name
        hint = " (read a file with satchain.io.read_image first)" if path else ""
        raise InputError(f"{name} = {shown[:80]}: must be an array of numbers{hint}")
    kind = getattr(getattr(value, "dtype", None), "kind", None)
    if kind is not None and kind not in "biuf":
        raise InputError(f"{name}: must be an array of real numbers, got dtype {value.dtype}")
