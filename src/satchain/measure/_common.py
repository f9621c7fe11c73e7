"""Helpers shared by the measurement modules: ROI extraction, input checks, JSON-ready results."""

from __future__ import annotations

import dataclasses
import math
from typing import Any, ClassVar

import numpy as np

from satchain._validate import as_float_array, masked_as_nan, split_mask
from satchain.errors import InputError
from satchain.measure._clipping import find_clipping
from satchain.measure._robust import median, robust_sigma
from satchain.measure._zero_fill import zero_fill_mask

__all__ = [
    "valid_mask",
    "unmask",
    "masked_as_nan",
    "zero_fill_mask",
    "fill_invalid",
    "crop_roi",
    "robust_sigma",
    "median",
    "to_jsonable",
    "ResultMixin",
    "first_crossing",
    "clipping_flag",
]


def crop_roi(image, roi, *, name: str = "image", min_size: int = 8) -> np.ndarray:
    """Return the float64 region ``image[y0:y1, x0:x1]`` for ``roi = (x0, y0, x1, y1)`` (half-open, pixels)
    or a :class:`satchain.geometry.Rect`.

    Refuses non-2-D input, NaN/inf, and regions smaller than ``min_size`` in either direction.

    Examples
    --------
    >>> crop_roi(np.zeros((20, 30)), (5, 2, 25, 12)).shape
    (10, 20)
    """
    a = as_float_array(name, image, ndim=2, finite=False)
    if hasattr(roi, "to_roi"):  # a satchain.geometry.Rect
        roi = roi.to_roi()
    if roi is not None:
        try:
            x0, y0, x1, y1 = (int(v) for v in roi)
        except (TypeError, ValueError):
            raise InputError(f"roi = {roi!r}: must be four integers (x0, y0, x1, y1)") from None
        ny, nx = a.shape
        if not (0 <= x0 < x1 <= nx and 0 <= y0 < y1 <= ny):
            raise InputError(
                f"roi = {tuple(roi)!r}: must satisfy 0 <= x0 < x1 <= {nx} and 0 <= y0 < y1 <= {ny} "
                f"for an image of shape {a.shape}"
            )
        a = a[y0:y1, x0:x1]
    if not np.all(np.isfinite(a)):
        n = int(np.count_nonzero(~np.isfinite(a)))
        raise InputError(
            f"{name}: the region contains {n} NaN/inf value(s) (no data: NaN, or a masked array's masked pixels); "
            "all values must be finite"
        )
    if min(a.shape) < min_size:
        raise InputError(f"{name}: region of shape {a.shape} is too small; both sides must be >= {min_size} px")
    return np.array(a, dtype=np.float64)


def valid_mask(image, valid=None, nodata=None, *, name: str = "image") -> np.ndarray | None:
    """The boolean mask of the pixels to measure, or None when every pixel counts.

    ``valid`` (True = measure) and ``nodata`` (pixels equal to it are excluded; NaN: NaN pixels) combine.
    Excluded pixels (outside an area of interest, nodata) are left out of a measurement: never clipping,
    never in the noise estimate.

    Examples
    --------
    >>> valid_mask(np.array([[0, 5], [7, 0]]), nodata=0).tolist()
    [[False, True], [True, False]]
    >>> valid_mask(np.ones((2, 2))) is None
    True
    """
    shape = np.shape(image)
    out = None
    if valid is not None:
        v = np.asarray(valid)
        if v.dtype != bool or v.shape != shape:
            raise InputError(
                f"valid: must be a boolean array of the {name}'s shape {shape}, got {v.dtype} of shape {v.shape}"
            )
        out = v.copy()
    if nodata is not None:
        try:
            nd = float(nodata)
        except (TypeError, ValueError):
            raise InputError(f"nodata = {nodata!r}: must be a number (or NaN)") from None
        a = np.asarray(image)
        m = ~np.isnan(a) if math.isnan(nd) else a != nd
        out = m if out is None else out & m
    if out is not None and not np.any(out):
        raise InputError(f"{name}: every pixel is excluded (nodata / valid mask); nothing to measure")
    return out


def unmask(image, valid=None, *, name: str = "image"):
    """``(image, valid)`` for a measurement that takes a ``valid`` mask: a numpy masked array's masked pixels
    are excluded as ``valid = False`` pixels are (never edge, plateau, noise or clipping), its data keep their
    dtype (an integer image's full scale and zero-fill test); anything else passes as it is. Measurements
    without ``valid`` take :func:`masked_as_nan` (masked pixels are NaN, refused in any region they fall in).

    Examples
    --------
    >>> img = np.ma.masked_array(np.arange(4).reshape(2, 2), mask=[[1, 0], [0, 0]])
    >>> data, ok = unmask(img)
    >>> data.dtype.kind, ok.tolist()
    ('i', [[False, True], [True, True]])
    """
    data, masked = split_mask(name, image)
    if masked is None:
        return data, valid
    keep = ~masked
    if valid is not None:
        keep &= valid_mask(data, valid, name=name)
    if not keep.any():
        extra = " and valid" if valid is not None else ""
        raise InputError(f"{name}: every pixel is masked (the masked array's mask{extra}); nothing to measure")
    return data, keep


def fill_invalid(a: np.ndarray, mask: np.ndarray | None) -> np.ndarray:
    """``a`` (float64) with each excluded pixel replaced by its nearest valid pixel's value, so that filters
    see no step at the mask's border (their response there is not used: callers keep to valid pixels)."""
    a = np.asarray(a, dtype=np.float64)
    if mask is None or mask.all():
        return a
    from scipy.ndimage import distance_transform_edt

    idx = distance_transform_edt(~mask, return_distances=False, return_indices=True)
    return a[tuple(idx)]


def clipping_flag(data, *, full_scale: float | None = None, noise_std: float | None = None) -> str | None:
    """The one-line flag of :func:`satchain.measure._clipping.find_clipping` (None: no evidence of clipping).

    A region's own maximum is not evidence: pixels at the sensor's ``full_scale`` are, and so is a flat
    run at an extreme that shows saturation (see :mod:`satchain.measure._clipping`).

    Examples
    --------
    >>> ramp = np.tile(np.tanh(np.linspace(-2.0, 2.0, 100)), (4, 1))
    >>> clipping_flag(np.minimum(ramp, 0.9))[:54]
    'clipping: 56 pixel(s) (14.0 %) exactly at the region m'
    >>> clipping_flag(ramp) is None, clipping_flag(ramp, full_scale=1.0) is None
    (True, True)
    """
    c = find_clipping(data, full_scale=full_scale, noise_std=noise_std)
    return None if c is None else c.message


def first_crossing(x, y, level: float):
    """First ``x`` where ``y`` falls to ``level`` or below (linear interpolation), or None.

    Examples
    --------
    >>> first_crossing(np.array([0.0, 1.0, 2.0]), np.array([1.0, 0.6, 0.2]), 0.5)
    1.25
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    below = np.nonzero(y <= level)[0]
    if below.size == 0:
        return None
    i = int(below[0])
    if i == 0:
        return float(x[0])
    x0, x1, y0, y1 = x[i - 1], x[i], y[i - 1], y[i]
    if y0 == y1:
        return float(x1)
    return float(x0 + (level - y0) * (x1 - x0) / (y1 - y0))


def to_jsonable(value):
    """Convert arrays, numpy scalars, tuples and non-finite floats to plain JSON types (NaN/inf -> None).

    Examples
    --------
    >>> to_jsonable({"a": np.array([1.0, np.nan]), "b": (np.int64(2),)})
    {'a': [1.0, None], 'b': [2]}
    """
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return [to_jsonable(v) for v in value.tolist()]
    if isinstance(value, list | tuple):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


class ResultMixin:
    """``to_dict()`` for frozen result dataclasses: every field, JSON-ready."""

    __dataclass_fields__: ClassVar[dict[str, dataclasses.Field[Any]]]  # set by @dataclass on each result class

    def to_dict(self) -> dict:
        return {f.name: to_jsonable(getattr(self, f.name)) for f in dataclasses.fields(self)}
