"""Image files: atomic writes; tiled (Big)TIFF with pixel-size metadata; PNG 8/16 bit; NPY; generic read.

Pixel-size metadata is written three ways so that every kind of reader finds it:

* GeoTIFF ``ModelPixelScaleTag`` (33550) = ``(pixel_m, pixel_m, 0)`` and ``ModelTiepointTag`` (33922)
  tying the top-left corner of pixel [0, 0] to model ``(x0, -y0)``, plus a minimal
  ``GeoKeyDirectoryTag`` (34735, ``GTRasterTypeGeoKey = PixelIsArea``): GIS tools (GDAL, QGIS) read the
  pixel size from these. Scene y points down (ALT), GIS Y up, hence the sign.
* The TIFF ``ImageDescription`` holds JSON ``{"satchain": {"pixel_m": ..., "origin_m": [x0, y0], ...}}``.
* PNG files carry the same JSON in a ``satchain`` text chunk and ``pHYs`` in pixels per metre.

Every write goes to a temporary file in the destination directory and is moved into place with
``os.replace``, so a failed write never leaves a partial file under the final name.

Examples
--------
>>> import tempfile, os
>>> d = tempfile.mkdtemp()
>>> write_tiff(os.path.join(d, "a.tif"), np.ones((3, 4), np.float32), pixel_m=0.5)
>>> img, meta = read_image(os.path.join(d, "a.tif"))
>>> img.shape, meta["pixel_m"]
((3, 4), 0.5)
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import tifffile
from PIL import Image, PngImagePlugin

from satchain._validate import check_positive
from satchain.errors import InputError, SatchainIOError

__all__ = [
    "BIGTIFF_THRESHOLD_BYTES",
    "atomic_path",
    "read_image",
    "write_npy",
    "write_png",
    "write_tiff",
    "write_tiff_tiles",
]

#: classic TIFF offsets are 32-bit; switch to BigTIFF well before 4 GiB (with room for tags)
BIGTIFF_THRESHOLD_BYTES = 2_000_000_000
_MODEL_PIXEL_SCALE = 33550
_MODEL_TIEPOINT = 33922
_GEO_KEY_DIRECTORY = 34735


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; on success move it onto ``path``, on error delete it.

    Examples
    --------
    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "x.txt")
    >>> with atomic_path(p) as tmp:
    ...     _ = tmp.write_text("hi")
    >>> open(p).read()
    'hi'
    """
    final = Path(path)
    if not final.parent.is_dir():
        raise SatchainIOError(f"output = {str(final)!r}: directory {str(final.parent)!r} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{final.name}.", suffix=".tmp", dir=final.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp_path, 0o666 & ~umask)  # mkstemp makes 0600 files; give the usual permissions
        os.replace(tmp_path, final)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp_path.unlink()
        raise


def _geo_tags(pixel_m: float | None, origin_m: tuple[float, float]) -> list[tuple]:
    if pixel_m is None:
        return []
    x0, y0 = origin_m
    return [
        (_MODEL_PIXEL_SCALE, "d", 3, (pixel_m, pixel_m, 0.0), True),
        (_MODEL_TIEPOINT, "d", 6, (0.0, 0.0, 0.0, x0, -y0, 0.0), True),
        # version 1.1.0, one key: GTRasterTypeGeoKey (1025) = RasterPixelIsArea (1)
        (_GEO_KEY_DIRECTORY, "H", 8, (1, 1, 0, 1, 1025, 0, 1, 1), True),
    ]


def _description(pixel_m, origin_m, extra) -> str:
    meta: dict[str, Any] = {"pixel_m": pixel_m, "origin_m": list(origin_m)}
    meta.update(extra or {})
    return json.dumps({"satchain": meta})


def write_tiff_tiles(
    path: str | os.PathLike,
    tiles: Iterable[np.ndarray],
    *,
    shape: tuple[int, int],
    dtype,
    tile: tuple[int, int] = (256, 256),
    pixel_m: float | None = None,
    origin_m: tuple[float, float] = (0.0, 0.0),
    bigtiff: bool | None = None,
    metadata: dict[str, Any] | None = None,
) -> None:
    """Write a tiled TIFF from an iterator of tiles (row-major tile order), atomically.

    Each tile is ``tile``-shaped, or smaller at the right/bottom border (it is zero-padded). Memory use
    is one tile. ``bigtiff=None`` chooses BigTIFF above :data:`BIGTIFF_THRESHOLD_BYTES`.
    """
    dtype = np.dtype(dtype)
    rows, cols = (int(s) for s in shape)
    th, tw = tile
    if th % 16 or tw % 16:
        raise InputError(f"tile = {tile!r}: TIFF tile sizes must be multiples of 16")
    if bigtiff is None:
        bigtiff = rows * cols * dtype.itemsize > BIGTIFF_THRESHOLD_BYTES
    if pixel_m is not None:
        check_positive("pixel_m", pixel_m)

    def padded():
        for t in tiles:
            t = np.asarray(t, dtype=dtype)
            if t.shape != (th, tw):
                full = np.zeros((th, tw), dtype)
                full[: t.shape[0], : t.shape[1]] = t
                t = full
            yield t

    extra: dict[str, Any] = {}
    if pixel_m is not None:
        extra = {
            "resolution": (1.0 / (pixel_m * 100.0), 1.0 / (pixel_m * 100.0)),
            "resolutionunit": "CENTIMETER",
        }
    try:
        with atomic_path(path) as tmp:
            tifffile.imwrite(
                tmp,
                padded(),
                shape=(rows, cols),
                dtype=dtype,
                tile=(th, tw),
                bigtiff=bigtiff,
                photometric="minisblack",
                description=_description(pixel_m, origin_m, metadata),
                metadata=None,
                extratags=_geo_tags(pixel_m, origin_m),
                **extra,
            )
    except (OSError, ValueError) as exc:
        if isinstance(exc, (SatchainIOError, InputError)):
            raise
        raise SatchainIOError(f"cannot write TIFF {str(path)!r}: {exc}") from exc


def write_tiff(
    path: str | os.PathLike,
    image: np.ndarray,
    *,
    pixel_m: float | None = None,
    origin_m: tuple[float, float] = (0.0, 0.0),
    tile: tuple[int, int] = (256, 256),
    bigtiff: bool | None = None,
    metadata: dict[str, Any] | None = None,
) -> None:
    """Write a 2-D array as a tiled TIFF (BigTIFF when large) with pixel-size metadata, atomically."""
    image = np.asarray(image)
    if image.ndim != 2:
        raise InputError(f"image: must be 2-D, got shape {image.shape}")
    th, tw = tile

    def tiles():
        for r in range(0, image.shape[0], th):
            for c in range(0, image.shape[1], tw):
                yield image[r : r + th, c : c + tw]

    write_tiff_tiles(
        path,
        tiles(),
        shape=image.shape,
        dtype=image.dtype,
        tile=tile,
        pixel_m=pixel_m,
        origin_m=origin_m,
        bigtiff=bigtiff,
        metadata=metadata,
    )


def write_png(
    path: str | os.PathLike,
    image: np.ndarray,
    *,
    pixel_m: float | None = None,
    metadata: dict[str, Any] | None = None,
) -> None:
    """Write a 2-D ``uint8`` (8-bit) or ``uint16`` (16-bit) grayscale PNG, atomically.

    Scale float images yourself (e.g. ``np.round(np.clip(img, 0, 1) * 255).astype(np.uint8)``).
    """
    image = np.asarray(image)
    if image.ndim != 2:
        raise InputError(f"image: must be 2-D, got shape {image.shape}")
    if image.dtype not in (np.uint8, np.uint16):
        raise InputError(f"image.dtype = {image.dtype}: PNG needs uint8 (8-bit) or uint16 (16-bit)")
    info = PngImagePlugin.PngInfo()
    meta = dict(metadata or {})
    if pixel_m is not None:
        meta["pixel_m"] = check_positive("pixel_m", pixel_m)
    info.add_text("satchain", json.dumps(meta))
    kwargs: dict[str, Any] = {"pnginfo": info}
    if pixel_m is not None:
        ppm = 1.0 / pixel_m
        kwargs["dpi"] = (ppm * 0.0254, ppm * 0.0254)
    img = Image.fromarray(image.astype(np.uint16) if image.dtype == np.uint16 else image)
    try:
        with atomic_path(path) as tmp:
            img.save(tmp, format="PNG", **kwargs)
    except OSError as exc:
        if isinstance(exc, SatchainIOError):
            raise
        raise SatchainIOError(f"cannot write PNG {str(path)!r}: {exc}") from exc


def preview_uint8(image: np.ndarray, *, low_pct: float = 0.5, high_pct: float = 99.5) -> np.ndarray:
    """An 8-bit display version of any image: a linear stretch between two percentiles.

    Examples
    --------
    >>> preview_uint8(np.array([[0.0, 1.0], [2.0, 3.0]]), low_pct=0, high_pct=100).tolist()
    [[0, 85], [170, 255]]
    """
    a = np.asarray(image, dtype=np.float64)
    finite = a[np.isfinite(a)]
    if finite.size == 0:
        return np.zeros(a.shape, dtype=np.uint8)
    lo, hi = np.percentile(finite, [low_pct, high_pct])
    scale = 255.0 / (hi - lo) if hi > lo else 0.0
    return np.round(np.clip((np.nan_to_num(a, nan=lo) - lo) * scale, 0, 255)).astype(np.uint8)


def write_npy(path: str | os.PathLike, image: np.ndarray) -> None:
    """Write an array as ``.npy`` atomically (no metadata: NPY has nowhere to keep a pixel size)."""
    try:
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as f:
                np.save(f, np.asarray(image), allow_pickle=False)
    except OSError as exc:
        if isinstance(exc, SatchainIOError):
            raise
        raise SatchainIOError(f"cannot write NPY {str(path)!r}: {exc}") from exc


def _read_tiff(path: Path) -> tuple[np.ndarray, dict[str, Any]]:
    with tifffile.TiffFile(path) as tf:
        page = tf.pages[0]
        image = page.asarray()
        meta: dict[str, Any] = {"format": "tiff", "bigtiff": tf.is_bigtiff}
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
    return image, meta


def _read_png(path: Path) -> tuple[np.ndarray, dict[str, Any]]:
    with Image.open(path) as img:
        img.load()
        meta: dict[str, Any] = {"format": "png"}
        text = img.info.get("satchain")
        if text:
            with contextlib.suppress(ValueError, TypeError):
                meta.update(json.loads(text))
        if "pixel_m" not in meta and img.info.get("dpi"):
            meta["pixel_m"] = 0.0254 / float(img.info["dpi"][0])
        if img.mode in ("I;16", "I;16B", "I;16L"):
            arr = np.array(img, dtype=np.uint16)
        elif img.mode == "I":
            arr = np.array(img).astype(np.uint16)
        elif img.mode in ("L", "P", "1"):
            arr = np.array(img.convert("L"))
        else:
            arr = np.array(img.convert("L"))
            meta["converted_from"] = img.mode
    return arr, meta


def read_image(path: str | os.PathLike) -> tuple[np.ndarray, dict[str, Any]]:
    """Read a TIFF/GeoTIFF, PNG or NPY image: ``(array, metadata)``.

    ``metadata["pixel_m"]`` is present when the file states a pixel size (GeoTIFF scale tag, satchain
    description, PNG text chunk or pHYs). Colour images are converted to grayscale (luma).
    """
    p = Path(path)
    if not p.is_file():
        raise SatchainIOError(f"image = {str(p)!r}: no such file")
    suffix = p.suffix.lower()
    try:
        if suffix in (".tif", ".tiff"):
            return _read_tiff(p)
        if suffix == ".png":
            return _read_png(p)
        if suffix == ".npy":
            return np.load(p, allow_pickle=False), {"format": "npy"}
    except (OSError, ValueError, tifffile.TiffFileError) as exc:
        if isinstance(exc, SatchainIOError):
            raise
        raise SatchainIOError(f"image = {str(p)!r}: cannot read: {exc}") from exc
    raise SatchainIOError(f"image = {str(p)!r}: unsupported suffix {suffix!r}; use .tif, .tiff, .png or .npy")
