"""What an image file says about itself, checked: the pixel size (GeoTIFF scale, satchain description, TIFF
resolution tags, PNG pHYs), the number of pages and bands. Whatever is not used as it stands warns with a
:class:`~satchain.errors.SatchainWarning` (see :mod:`satchain.io`)."""

from __future__ import annotations

import contextlib
import json
import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import tifffile

from satchain.errors import SatchainWarning

_MODEL_PIXEL_SCALE = 33550
_MODEL_TIEPOINT = 33922
_GEO_KEY_DIRECTORY = 34735

#: a ground pixel size outside this range (m) is used, with a warning that it looks wrong
PLAUSIBLE_PIXEL_M = (1e-3, 1e5)


def _warn(path, message: str) -> None:
    warnings.warn(f"image = {str(path)!r}: {message}", SatchainWarning, stacklevel=3)


def _to_grey(arr: np.ndarray, page, path: Path) -> np.ndarray:
    """One band from a TIFF page with several samples per pixel: RGB(A) by ITU-R BT.601 luma, other kinds
    (multispectral, extra samples) by their first band; either way with a warning naming the conversion."""
    spp = int(getattr(page, "samplesperpixel", 1))
    if spp <= 1 or arr.ndim != 3:
        return arr
    axis = -1 if arr.shape[-1] == spp else 0
    bands = np.moveaxis(arr, axis, -1)
    if getattr(page, "photometric", None) == tifffile.PHOTOMETRIC.RGB and spp >= 3:
        _warn(path, f"RGB image ({spp} samples per pixel) converted to grey by luma 0.299 R + 0.587 G + 0.114 B")
        grey = bands[..., :3].astype(np.float64) @ np.array([0.299, 0.587, 0.114])
        return grey.astype(np.float32) if arr.dtype.kind == "f" else np.rint(grey).astype(arr.dtype)
    _warn(path, f"{spp} samples (bands) per pixel: band 1 is used, the others are ignored")
    return np.ascontiguousarray(bands[..., 0])


def _tiff_meta(tf, page, path=None) -> dict[str, Any]:
    meta: dict[str, Any] = {"format": "tiff", "bigtiff": tf.is_bigtiff, "bits_per_sample": page.bitspersample}
    pages = [p for p in tf.pages if not getattr(p, "is_reduced", False)]  # overviews of a COG are not images
    if len(pages) > 1:
        _warn(path or tf.filename, f"the TIFF holds {len(pages)} images (pages); page 1 is used, the others ignored")
    desc = page.tags.get(270)
    if desc is not None:
        with contextlib.suppress(ValueError, TypeError, AttributeError):
            meta.update({k: v for k, v in json.loads(desc.value).get("satchain", {}).items() if v is not None})
    scale = page.tags.get(_MODEL_PIXEL_SCALE)
    if scale is not None:
        sx, sy = float(scale.value[0]), float(scale.value[1])
        if not math.isclose(sx, sy, rel_tol=1e-9):
            meta["pixel_m_xy"] = [sx, sy]
        meta["pixel_m"] = sx
    tie = page.tags.get(_MODEL_TIEPOINT)
    if tie is not None and len(tie.value) >= 6:
        i, j = float(tie.value[0]), float(tie.value[1])
        px = meta.get("pixel_m", 1.0)
        meta["origin_m"] = [float(tie.value[3]) - i * px, -(float(tie.value[4]) + j * px)]
    if scale is not None and _geographic(page):
        meta["invalid_pixel_m"] = f"{meta.pop('pixel_m')!r} (degrees: the GeoTIFF has a geographic CRS)"
    meta = _checked_meta(meta, path or tf.filename)
    _check_resolution_tags(page, meta, path or tf.filename)
    return meta


def _geographic(page) -> bool:
    """GTModelTypeGeoKey (1024) = 2: the model space is latitude/longitude, so the pixel scale is in degrees."""
    keys = page.tags.get(_GEO_KEY_DIRECTORY)
    with contextlib.suppress(TypeError, ValueError, IndexError, AttributeError):
        v = [int(x) for x in keys.value]
        return any(v[k] == 1024 and v[k + 1] == 0 and v[k + 3] == 2 for k in range(4, 4 + 4 * v[3], 4))
    return False


def _check_resolution_tags(page, meta: dict[str, Any], path) -> None:
    """Warn when the TIFF resolution tags state a ground-like pixel size that differs from the one used."""
    unit = {2: 0.0254, 3: 0.01}.get(int(getattr(page.tags.get(296), "value", 0) or 0))  # ResolutionUnit
    res = page.tags.get(282)  # XResolution (pixels per unit)
    if unit is None or res is None or meta.get("pixel_m") is None:
        return
    with contextlib.suppress(TypeError, ValueError, ZeroDivisionError, IndexError):
        v = res.value
        per_unit = float(v[0]) / float(v[1]) if isinstance(v, tuple) else float(v)
        tag_m = unit / per_unit
        if tag_m >= PLAUSIBLE_PIXEL_M[0] and not math.isclose(tag_m, meta["pixel_m"], rel_tol=0.01):
            _warn(path, f"its resolution tags say {tag_m:.6g} m per pixel, its pixel size {meta['pixel_m']:.6g} m; "
                  f"{meta['pixel_m']:.6g} m is used")  # fmt: skip


def _checked_meta(meta: dict[str, Any], path=None) -> dict[str, Any]:
    """A stated pixel size must be a number in (0, 1e6] m; otherwise it moves to ``invalid_pixel_m`` (which the
    users of a pixel size refuse unless one is given). A valid one outside :data:`PLAUSIBLE_PIXEL_M` warns."""
    v = meta.get("pixel_m")
    if v is None:
        return meta
    try:
        f = float(v)
        ok = not isinstance(v, (bool, str)) and math.isfinite(f) and 0 < f <= 1e6
    except (TypeError, ValueError):
        ok = False
    if ok:
        meta["pixel_m"] = f
        if not PLAUSIBLE_PIXEL_M[0] <= f <= PLAUSIBLE_PIXEL_M[1]:
            lo, hi = PLAUSIBLE_PIXEL_M
            _warn(path, f"its pixel size {f:g} m is implausible for a ground pixel (outside [{lo:g}, {hi:g}] m); "
                  "check it, or give the pixel size (--pixel-m / --scene-pixel-m)")  # fmt: skip
    else:
        meta.pop("pixel_m")
        meta["invalid_pixel_m"] = v
    return meta
