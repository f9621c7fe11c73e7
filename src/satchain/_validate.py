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


def split_mask(name: str, value):
    """(data, mask) of an image argument: a :class:`numpy.ma.MaskedArray`'s data (a plain array of its own
    dtype) and its mask (bool, True = masked; None where no pixel is masked); anything else as it is, with
    None. A boolean array is refused: it is a mask, not an image.

    Examples
    --------
    >>> data, mask = split_mask("image", np.ma.masked_array([[1, 2], [3, 4]], mask=[[0, 1], [0, 0]]))
    >>> type(data).__name__, mask.tolist()
    ('ndarray', [[False, True], [False, False]])
    >>> split_mask("image", np.ma.masked_array([1.0, 2.0]))[1] is None
    True
    """
    if getattr(getattr(value, "dtype", None), "kind", None) == "b":
        raise InputError(
            f"{name}: a boolean array is a mask, not an image; give the image's values (image.astype(float) for "
            "a 0/1 image), and a mask as valid= or as a numpy masked array's mask"
        )
    if not isinstance(value, np.ma.MaskedArray):
        return value, None
    mask = np.ma.getmask(value)
    data = np.ma.getdata(value)
    if mask is np.ma.nomask or not mask.any():
        return data, None
    return data, np.array(np.broadcast_to(mask, data.shape), dtype=bool)


def masked_as_nan(name: str, value):
    """An image argument with a masked array's masked pixels set to NaN (a float64 copy; nodata, as NaN is
    everywhere in satchain); anything else (and a masked array with no masked pixel: its data) as it is."""
    data, mask = split_mask(name, value)
    if mask is None:
        return data
    out = np.array(data, dtype=np.float64)
    out[mask] = np.nan
    return out


def _check_array_like(name: str, value) -> None:
    """Refuse, naming the parameter, what is not an array of numbers: None, a path or string (a file name
    where the image's pixels are wanted), a mapping, a boolean or complex/object/string array."""
    import os
    from collections.abc import Mapping

    if value is None or isinstance(value, (str, bytes, os.PathLike, Mapping, bool)):
        shown = repr(value) if not isinstance(value, Mapping) else f"a {type(value).__name__}"
        path = isinstance(value, (str, os.PathLike)) and "image" in name
        hint = " (read a file with satchain.io.images.read_image first)" if path else ""
        raise InputError(f"{name} = {shown[:80]}: must be an array of numbers{hint}")
    kind = getattr(getattr(value, "dtype", None), "kind", None)
    if kind is not None and kind not in "biuf":
        raise InputError(f"{name}: must be an array of real numbers, got dtype {value.dtype}")
