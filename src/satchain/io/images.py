"""Image files: atomic writes; tiled (Big)TIFF with pixel-size metadata; PNG 8/16 bit; NPY; generic read.

Pixel-size metadata is written three ways so that every kind of reader finds it:

* GeoTIFF ``ModelPixelScaleTag`` (33550) = ``(pixel_m, pixel_m, 0)`` and ``ModelTiepointTag`` (33922)
  tying the top-left corner of pixel [0, 0] to model ``(x0, -y0)``, plus a minimal
  ``GeoKeyDirectoryTag`` (34735, ``GTRasterTypeGeoKey = PixelIsArea``): GIS tools (GDAL, QGIS) read the
  pixel size from these. Scene y points down (ALT), GIS Y up, hence the sign.
* The TIFF ``ImageDescription`` holds JSON ``{"satchain": {"pixel_m": ..., "origin_m": [x0, y0], ...}}``.
* PNG files carry the same JSON in a ``satchain`` text chunk and ``pHYs`` in pixels per metre.

Reading warns (:class:`~satchain.errors.SatchainWarning`) where a file is not used as it stands: a colour or
palette image converted to grey (the conversion named), a multi-page TIFF (page 1 is used), a pixel size that
is implausible for the ground (below 1 mm or above 100 km), resolution tags that disagree with the stated pixel
size, a print resolution (72 dpi) that is not a ground pixel size, or a pixel scale in degrees (a geographic CRS).

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
import os
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import tifffile
from PIL import Image, PngImagePlugin

from satchain._safety import check_memory, clean_stale_temp_files
from satchain._validate import check_positive
from satchain.errors import ConfigError, InputError, SatchainIOError
from satchain.io._commit import committed_together, defer_rename, staged  # noqa: F401 (named here too)
from satchain.io.imagemeta import (  # the checks of what a file says of itself
    _GEO_KEY_DIRECTORY,
    _MODEL_PIXEL_SCALE,
    _MODEL_TIEPOINT,
    PLAUSIBLE_PIXEL_M,
    _checked_meta,
    _gdal_meta,
    _grey_mode,
    _read_grey,
    _warn,
)
from satchain.io.raster import RasterReader, open_raster

__all__ = [
    "BIGTIFF_THRESHOLD_BYTES",
    "PNG_COMPRESS_LEVEL",
    "ImageReader",
    "atomic_path",
    "integer_scale",
    "open_image",
    "read_image",
    "simulated_dtype",
    "write_simulated",
    "write_npy",
    "write_png",
    "write_tiff",
    "write_tiff_tiles",
]

#: classic TIFF offsets are 32-bit; switch to BigTIFF well before 4 GiB (with room for tags)
BIGTIFF_THRESHOLD_BYTES = 2_000_000_000
#: zlib level of every PNG satchain writes (previews, figures, report thumbnails). Level 3 encodes a default run
#: folder's PNGs in half the time of zlib's default 6 (0.19 s against 0.37 s of CPU) for 20 % more bytes (1.6
#: against 1.3 MB); PNG is lossless at any level, so the pixels are the same.
PNG_COMPRESS_LEVEL = 3


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
    clean_stale_temp_files(final)  # left by a killed process (the pid in the name is gone)
    fd, tmp = tempfile.mkstemp(prefix=f".{final.name}.{os.getpid()}.", suffix=".tmp", dir=final.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp_path, 0o666 & ~umask)  # mkstemp makes 0600 files; give the usual permissions
        if not defer_rename(tmp_path, final):  # inside committed_together: renamed in at the group's end
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
    kwargs: dict[str, Any] = {"pnginfo": info, "compress_level": PNG_COMPRESS_LEVEL}
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


def _nbytes(shape, dtype) -> int:
    return int(np.prod([int(v) for v in shape], dtype=np.float64) * max(np.dtype(dtype).itemsize, 4))


#: suffixes read through GDAL (rasterio); PNG keeps its own reader (its text chunk and pHYs), NPY a memory map
GDAL_SUFFIXES = (".tif", ".tiff", ".jp2", ".j2k", ".ntf", ".nitf", ".vrt", ".img")
SUFFIXES = (*GDAL_SUFFIXES, ".png", ".npy")


def _read_gdal(path: Path, band: int | None, mask: bool) -> tuple[np.ndarray, np.ndarray | None, dict[str, Any]]:
    with open_raster(path, band=band) as r:
        meta = _gdal_meta(r)
        rows, cols = r.shape
        check_memory(2 * _nbytes(r.shape, r.dtype), f"image = {str(path)!r} ({rows} x {cols} px)")
        image = _read_grey(r, _grey_mode(r), 0, 0, rows, cols)
        valid = r.read_mask() if r.has_mask else None
        if valid is not None and not valid.any():
            raise InputError(f"image = {str(path)!r}: every pixel is nodata or masked (nodata = {r.nodata!r}); "
                             "nothing to use")  # fmt: skip
        if valid is not None:
            meta["valid_fraction"] = float(valid.mean())
    return image, (valid if mask else None), meta


def _read_png(path: Path) -> tuple[np.ndarray, dict[str, Any]]:
    with Image.open(path) as img:
        check_memory(8.0 * img.size[0] * img.size[1], f"image = {str(path)!r} ({img.size[0]} x {img.size[1]} px)")
        img.load()
        meta: dict[str, Any] = {"format": "png"}
        text = img.info.get("satchain")
        if text:
            with contextlib.suppress(ValueError, TypeError):
                meta.update(json.loads(text))
        with contextlib.suppress(TypeError, ValueError, ZeroDivisionError, IndexError):
            if "pixel_m" not in meta and img.info.get("dpi"):
                dpi_m = 0.0254 / float(img.info["dpi"][0])
                if dpi_m >= PLAUSIBLE_PIXEL_M[0]:
                    meta["pixel_m"] = dpi_m
                else:
                    _warn(path, f"its resolution {float(img.info['dpi'][0]):g} dpi ({dpi_m * 1e3:.3g} mm per pixel) "
                          "is a print resolution, not a ground pixel size: ignored (give --pixel-m)")  # fmt: skip
        if img.mode in ("I;16", "I;16B", "I;16L"):
            arr = np.array(img, dtype=np.uint16)
        elif img.mode == "I":
            arr = np.array(img).astype(np.uint16)
        elif img.mode in ("L", "1"):
            arr = np.array(img.convert("L"))
        else:
            how = {"P": "palette image: its colours"}.get(img.mode, f"{img.mode} image")
            _warn(path, f"{how} converted to grey by luma 0.299 R + 0.587 G + 0.114 B (alpha ignored)")
            arr = np.array(img.convert("L"))
            meta["converted_from"] = img.mode
    return arr, _checked_meta(meta, path)


def _check_path(p: Path) -> None:
    if not p.is_file():
        what = "is a directory, not an image file" if p.is_dir() else "no such file"
        raise SatchainIOError(f"image = {str(p)!r}: {what}")
    if p.suffix.lower() not in SUFFIXES:
        raise SatchainIOError(f"image = {str(p)!r}: unsupported suffix {p.suffix!r}; use {', '.join(SUFFIXES)}")


def read_image(path: str | os.PathLike, *, band: int | None = None, mask: bool = False):
    """Read an image whole: ``(array, metadata)``, or ``(array, valid, metadata)`` with ``mask=True``.

    Every GDAL raster (GeoTIFF, COG, JP2, NITF, VRT ...) is read through :mod:`satchain.io.raster`; PNG and NPY by
    their own readers. ``band`` (1-based) picks one band of a multiband raster; without it band 1 is used (an
    RGB image is converted to grey by luma), with a :class:`~satchain.errors.SatchainWarning`. ``valid`` is a
    boolean array (True = valid pixel: not nodata, not masked, alpha > 0), or None when every pixel is valid.
    ``metadata["pixel_m"]`` is present when the file states a metric pixel size (a projected CRS, satchain's
    local pixel scale, its description, PNG text chunk or pHYs); a geographic CRS gives ``invalid_pixel_m``.
    The georeference comes as ``crs``, ``transform`` (GDAL order), ``nodata``, ``band``, ``count``.
    """
    p = Path(path)
    _check_path(p)
    suffix = p.suffix.lower()
    valid = None
    try:
        if suffix == ".png":
            image, meta = _read_png(p)
        elif suffix == ".npy":
            image, meta = np.load(p, allow_pickle=False), {"format": "npy"}
        else:
            image, valid, meta = _read_gdal(p, band, mask)
        if image.dtype.kind not in "biuf":
            raise InputError(f"image = {str(p)!r}: values must be real numbers, got dtype {image.dtype}")
    except (OSError, ValueError, Image.DecompressionBombError) as exc:
        if isinstance(exc, (SatchainIOError, InputError, ConfigError)):
            raise
        raise SatchainIOError(f"image = {str(p)!r}: cannot read: {exc}") from exc
    return (image, valid, meta) if mask else (image, meta)


# ---------------------------------------------------------------------------------------------- windowed reading
class ImageReader:
    """Window access to a 2-D image file without reading it whole where the format allows it.

    Every GDAL raster (tiled or stripped GeoTIFF / COG / BigTIFF, JP2, NITF, VRT) is read block by block
    through :class:`satchain.io.raster.RasterReader`, NPY through a memory map; PNG is read whole (after a memory
    check). ``read(row0, col0, height, width)`` returns the stored values (the file's dtype) of a window of the
    chosen band (``band``, default 1; an RGB image without a band named: its luma), ``read_mask`` its validity.

    Examples
    --------
    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "t.tif")
    >>> write_tiff(p, np.arange(1200, dtype=np.uint16).reshape(30, 40), tile=(16, 16))
    >>> with open_image(p) as r:
    ...     r.shape, r.read(17, 20, 2, 3).tolist()
    ((30, 40), [[700, 701, 702], [740, 741, 742]])
    """

    def __init__(self, path: Path, *, band: int | None = None):
        self.path = path
        self.band = band
        self.raster: RasterReader | None = None
        self._array: np.ndarray | None = None
        self.segments_read = 0  # blocks (tiles or strips) the window reads touched: what GDAL decodes
        suffix = path.suffix.lower()
        if suffix == ".npy":
            self._array = np.load(path, mmap_mode="r", allow_pickle=False)
            self.meta: dict[str, Any] = {"format": "npy"}
        elif suffix == ".png":
            self._array, self.meta = read_image(path)
        else:
            self.raster = r = open_raster(path, band=band)
            self.meta = _gdal_meta(r)
            self._mode = _grey_mode(r)
            rgb_float = self._mode == "rgb" and r.dtype.kind == "f"
            self.shape, self.dtype = r.shape, (np.dtype(np.float32) if rgb_float else r.dtype)
        if self._array is not None:
            if self._array.dtype.kind not in "biuf":
                raise InputError(f"image = {str(path)!r}: values must be real numbers, got dtype {self._array.dtype}")
            if self._array.ndim != 2:
                raise InputError(f"image = {str(path)!r}: must be 2-D (one band), got shape {self._array.shape}")
            rows, cols = self._array.shape
            self.shape, self.dtype = (int(rows), int(cols)), self._array.dtype

    def _check(self, row0, col0, height, width) -> None:
        rows, cols = self.shape
        if row0 < 0 or col0 < 0 or height < 1 or width < 1 or row0 + height > rows or col0 + width > cols:
            raise InputError(f"window = {(row0, col0, height, width)!r}: outside the image of shape {self.shape}")

    def read(self, row0: int, col0: int, height: int, width: int) -> np.ndarray:
        self._check(row0, col0, height, width)
        if self._array is not None:
            return np.array(self._array[row0 : row0 + height, col0 : col0 + width])
        assert self.raster is not None  # no array: a GDAL raster
        self.segments_read += self.raster.blocks_touched(row0, col0, height, width)
        return _read_grey(self.raster, self._mode, row0, col0, height, width)

    def read_mask(self, row0: int, col0: int, height: int, width: int) -> np.ndarray | None:
        """Validity of a window (True = valid), or None when the file has no nodata, mask or alpha."""
        self._check(row0, col0, height, width)
        if self.raster is None or not self.raster.has_mask:
            return None
        return self.raster.read_mask(row0, col0, height, width)

    def __getstate__(self) -> dict:  # picklable (Dask workers): reopened from the path
        return {"path": self.path, "band": self.band}

    def __setstate__(self, state: dict) -> None:
        type(self).__init__(self, state["path"], band=state.get("band"))

    def close(self) -> None:
        if self.raster is not None:
            self.raster.close()
            self.raster = None

    def __enter__(self) -> ImageReader:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def open_image(path: str | os.PathLike, *, band: int | None = None) -> ImageReader:
    """Open any GDAL raster, PNG or NPY image for window reads (see :class:`ImageReader`)."""
    p = Path(path)
    _check_path(p)
    try:
        return ImageReader(p, band=band)
    except (OSError, ValueError, IndexError, KeyError) as exc:
        if isinstance(exc, (SatchainIOError, InputError, ConfigError)):
            raise
        raise SatchainIOError(f"image = {str(p)!r}: cannot read: {exc}") from exc


def integer_scale(dtype, metadata: dict[str, Any] | None = None) -> float:
    """The factor that turns stored values into reflectance: ``1 / (2**bits - 1)`` for integers, 1 for floats.

    ``bits`` is the file's stated ``bit_depth`` (satchain writes it with DN images), else its TIFF
    BitsPerSample, else the integer type's width; signed integers use ``2**(bits - 1) - 1``.
    So 8-bit 0..255 and 16-bit 0..65535 both map to reflectance 0..1; give an explicit scale otherwise.

    Examples
    --------
    >>> integer_scale(np.uint8), integer_scale(np.uint16, {"bit_depth": 12}), integer_scale(np.float32)
    (0.00392156862745098, 0.0002442002442002442, 1.0)
    """
    dt = np.dtype(dtype)
    if dt.kind == "b":
        return 1.0
    if dt.kind not in "ui":
        return 1.0
    meta = metadata or {}
    bits = meta.get("bit_depth") or meta.get("bits_per_sample") or dt.itemsize * 8
    try:
        bits = int(bits)
    except (TypeError, ValueError):
        bits = dt.itemsize * 8
    bits = min(max(bits, 1), dt.itemsize * 8)
    return 1.0 / (2.0 ** (bits - 1 if dt.kind == "i" else bits) - 1.0) if bits > 1 or dt.kind == "u" else 1.0


# ---------------------------------------------------------------------------------------------- simulated images
def simulated_dtype(units: str, bit_depth: int | None) -> np.dtype:
    """The file type of a simulated image: DN at the camera's bit depth (uint8/16/32), float32 otherwise."""
    if units != "dn":
        return np.dtype(np.float32)
    b = 12 if bit_depth is None else int(bit_depth)
    return np.dtype(np.uint8 if b <= 8 else np.uint16 if b <= 16 else np.uint32)


def write_simulated(
    path: str | os.PathLike,
    image: np.ndarray,
    *,
    units: str,
    bit_depth: int | None,
    pixel_m: float,
    metadata: dict[str, Any] | None = None,
    preview: bool = True,
) -> Path | None:
    """Write a simulated image (TIFF; and a PNG preview beside it): the one writer of ``run`` and ``simulate``.

    DN are stored at the camera's bit depth (values rounded and clipped to ``[0, 2**bits - 1]``, which the
    sensor model already guarantees), other units as float32. ``bit_depth`` is recorded in the metadata,
    so reading the file back as ground truth scales it by ``1 / (2**bits - 1)``. Returns the preview path.
    """
    dtype = simulated_dtype(units, bit_depth)
    a = np.asarray(image)
    if units == "dn":
        top = 2.0 ** (12 if bit_depth is None else int(bit_depth)) - 1
        a = np.clip(np.round(a), 0, top)
    meta = {**(metadata or {}), "units": units}
    if units == "dn":
        meta["bit_depth"] = 12 if bit_depth is None else int(bit_depth)
    write_tiff(path, a.astype(dtype), pixel_m=pixel_m, metadata=meta)
    if not preview:
        return None
    png = Path(path).with_suffix(".png")
    write_png(png, preview_uint8(image), pixel_m=pixel_m)
    return png
