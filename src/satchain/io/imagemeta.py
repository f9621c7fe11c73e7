"""What an image file says about itself, checked: the pixel size (georeference, satchain description, TIFF
resolution tags, PNG pHYs), the number of pages and bands (files read through :mod:`satchain.io.raster`).
Whatever is not used as it stands warns with a :class:`~satchain.errors.SatchainWarning` (see
:mod:`satchain.io.images`)."""

from __future__ import annotations

import contextlib
import json
import math
import warnings
from typing import Any, cast

import numpy as np

from satchain.errors import SatchainWarning
from satchain.io.raster import RasterReader, raster_meta

_MODEL_PIXEL_SCALE = 33550
_MODEL_TIEPOINT = 33922
_GEO_KEY_DIRECTORY = 34735

#: a ground pixel size outside this range (m) is used, with a warning that it looks wrong
PLAUSIBLE_PIXEL_M = (1e-3, 1e5)


def _warn(path, message: str) -> None:
    warnings.warn(f"image = {str(path)!r}: {message}", SatchainWarning, stacklevel=3)


_RGB = ("red", "green", "blue")


def _is_rgb(r: RasterReader) -> bool:
    return r.count >= 3 and tuple(r.colorinterp[:3]) == _RGB


def _gdal_meta(r: RasterReader) -> dict[str, Any]:
    """The metadata keys satchain has always given (format, bits_per_sample, pixel_m, origin_m, the satchain
    description ...) plus the georeference (:func:`satchain.io.raster.raster_meta`), with the usual warnings."""
    path = r.path
    fmt = {"GTiff": "tiff", "COG": "tiff", "JP2OpenJPEG": "jp2", "NITF": "nitf", "VRT": "vrt"}.get(r.driver)
    meta: dict[str, Any] = {"format": fmt or r.driver.lower()}
    if fmt == "tiff":
        with open(path, "rb") as f:
            meta["bigtiff"] = f.read(4) in (b"II+\x00", b"MM\x00+")
    meta["bits_per_sample"] = r.bit_depth or r.dtype.itemsize * 8
    meta.update(raster_meta(r))
    pages = [s for s in r.subdatasets if s.startswith("GTIFF_DIR:")]
    if len(pages) > 1:
        _warn(path, f"the TIFF holds {len(pages)} images (pages); page 1 is used, the others ignored")
    desc = r.tags.get("TIFFTAG_IMAGEDESCRIPTION")
    if desc:
        with contextlib.suppress(ValueError, TypeError, AttributeError):
            meta.update({k: v for k, v in json.loads(desc).get("satchain", {}).items() if v is not None})
    desc_m, desc_xy = meta.get("pixel_m"), meta.get("pixel_m_xy")
    t = r.transform
    if r.pixel_m is not None:
        sx, sy = r.pixel_m
        meta["pixel_m"] = sx
        if not math.isclose(sx, sy, rel_tol=1e-9):
            meta["pixel_m_xy"] = [sx, sy]
    elif r.crs is not None and r.crs.is_geographic:
        meta.pop("pixel_m", None)
        meta["invalid_pixel_m"] = f"{abs(t.a)!r} (degrees: the raster has a geographic CRS)"
    elif r.pixel_m_problem and r.georeferenced:
        meta.pop("pixel_m", None)
        meta["invalid_pixel_m"] = f"none ({r.pixel_m_problem})"
    if meta.get("georeference") == "image_map" and desc_m is not None:
        # a satchain image under pushbroom geometry: its transform is the image's map to the ground (turned,
        # sheared, scaled along track); its pixel is the detector's, whose ground size (the GSD) it states
        meta["pixel_m"] = desc_m
        meta.pop("invalid_pixel_m", None)
        meta.pop("pixel_m_xy", None)
        if desc_xy is not None:
            meta["pixel_m_xy"] = desc_xy
    if r.georeferenced and not t.is_identity:
        meta["origin_m"] = [t.c, -t.f]
    meta = _checked_meta(meta, path)
    _check_resolution(r.tags, meta, path)
    return meta


def _check_resolution(tags: dict[str, str], meta: dict[str, Any], path) -> None:
    """Warn when the TIFF resolution tags state a ground-like pixel size that differs from the one used."""
    with contextlib.suppress(TypeError, ValueError, ZeroDivisionError, IndexError, KeyError, AttributeError):
        unit = {2: 0.0254, 3: 0.01}.get(int(tags["TIFFTAG_RESOLUTIONUNIT"].split()[0]))
        if unit is None or meta.get("pixel_m") is None:
            return
        tag_m = unit / float(tags["TIFFTAG_XRESOLUTION"])
        if tag_m >= PLAUSIBLE_PIXEL_M[0] and not math.isclose(tag_m, meta["pixel_m"], rel_tol=0.01):
            _warn(path, f"its resolution tags say {tag_m:.6g} m per pixel, its pixel size {meta['pixel_m']:.6g} m; "
                  f"{meta['pixel_m']:.6g} m is used")  # fmt: skip


def _grey_mode(r: RasterReader) -> str:
    """How a single image is made of a raster when no band was named: 'band', 'rgb' (luma), with a warning."""
    if r.band_named or r.count == 1:
        return "band"
    if _is_rgb(r):
        _warn(r.path, f"RGB image ({r.count} samples per pixel) converted to grey by luma 0.299 R + 0.587 G + "
              "0.114 B (name a band to use one)")  # fmt: skip
        return "rgb"
    _warn(r.path, f"{r.count} samples (bands) per pixel: band 1 is used, the others are ignored (name a band "
          "with band=N, --band N)")  # fmt: skip
    return "band"


def _read_grey(r: RasterReader, mode: str, row0: int, col0: int, height: int, width: int) -> np.ndarray:
    if mode == "band":
        return r.read(row0, col0, height, width)
    # the sum of three weighted band arrays is an array (sum() types it ndarray | Literal[0])
    grey = cast(np.ndarray, sum(w * r.read(row0, col0, height, width, band=b).astype(np.float64)
                                for b, w in ((1, 0.299), (2, 0.587), (3, 0.114))))  # fmt: skip
    return grey.astype(np.float32) if r.dtype.kind == "f" else np.rint(grey).astype(r.dtype)


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
