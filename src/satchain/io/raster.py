"""Imagery through rasterio (GDAL): any raster GDAL reads (GeoTIFF, COG, JP2, NITF, PNG, VRT ...), by window.

:func:`open_raster` returns a :class:`RasterReader`, which never reads a file whole unless asked: ``read`` and
``read_mask`` take a window ``(row0, col0, height, width)``. What the file says of itself comes with it:

* ``crs`` (a :class:`rasterio.crs.CRS` or None), ``transform`` (an :class:`affine.Affine`), ``nodata``,
  ``scales`` / ``offsets`` (applied by ``read(..., scaled=True)``), ``descriptions`` (band names),
  ``bit_depth`` (GDAL's ``NBITS``, e.g. 12 for 12-bit data stored in uint16) and ``alpha_band``;
* ``pixel_m = (x, y)``: the ground size of a pixel in metres, from the transform, when the CRS is projected
  (in metres, feet ...: converted) or when there is no CRS but a pixel scale (the local metric "pixel scale"
  that :func:`satchain.io.images.write_tiff` stores); None for a geographic CRS (degrees), no georeference, or
  ground control points only, with the reason in ``pixel_m_problem``. :meth:`RasterReader.require_pixel_m`
  turns that into a one-line error naming the option that supplies it. A rotated transform is handled (the
  pixel sizes are the lengths of the column and row steps, ``rotation_deg`` says by how much); a sheared one
  (non-square pixel corners) has no pixel size: ``pixel_m_problem`` says so.

An alpha band is the mask, not a band: ``count`` counts the data bands only. Bad files are refused at open with
one line naming the file and the problem (:class:`~satchain.errors.SatchainIOError` for a file GDAL cannot
read or whose header claims more data than it holds, :class:`~satchain.errors.InputError` for complex values
or no bands).

Examples
--------
>>> import tempfile, os, numpy as np, rasterio
>>> from rasterio import Affine
>>> p = os.path.join(tempfile.mkdtemp(), "u.tif")
>>> with rasterio.open(p, "w", driver="GTiff", width=40, height=30, count=2, dtype="uint16",
...                    crs="EPSG:32636", transform=Affine(0.098, 0, 5e5, 0, -0.098, 4e6)) as d:
...     d.write(np.arange(2400, dtype=np.uint16).reshape(2, 30, 40))
>>> with open_raster(p) as r:
...     r.shape, r.count, r.pixel_m, r.read(1, 2, 1, 3, band=2).tolist()
((30, 40), 2, (0.098, 0.098), [[1242, 1243, 1244]])
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from satchain.errors import ConfigError, InputError, SatchainIOError

__all__ = ["RasterReader", "open_raster"]

#: a TIFF whose header names more tiles/strips than it stores offsets for is refused (a forged/damaged header)
_ROTATION_TOL = 1e-9


def _rasterio():
    import rasterio  # imported lazily: `import satchain` stays fast

    # GDAL's warnings (e.g. "tags are not sorted") reach Python logging inside a rasterio.Env; without this a
    # command line with no logging set up would print them to stderr (logging's last resort) beside its one line
    logging.getLogger("rasterio").addHandler(logging.NullHandler())
    return rasterio


#: GDAL's block cache, MB: its default (5 % of the machine's memory) would count in a streamed run's peak RSS
GDAL_CACHE_MB = 128


def _gdal_env():
    """The rasterio environment every GDAL call of this module runs in (GDAL messages go to logging; a
    bounded block cache)."""
    return _rasterio().Env(GDAL_CACHEMAX=GDAL_CACHE_MB)


class RasterReader:
    """Window reads of one raster through rasterio; see the module docstring.

    Parameters
    ----------
    path : the raster file (anything GDAL opens).
    band : the 1-based data band that ``read`` uses by default; None: band 1, and ``band_named`` is False
        (callers that need one band out of several say so with :meth:`require_band`).
    """

    def __init__(self, path: str | os.PathLike, *, band: int | None = None):
        self.path = Path(path)
        self._band_arg = band
        self._ds = _open_dataset(self.path)
        try:
            with _gdal_env():
                self._inspect(band)
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------------------------------------ inspection
    def _inspect(self, band: int | None) -> None:
        ds, name = self._ds, str(self.path)
        self.driver: str = ds.driver
        if ds.count == 0:
            raise InputError(f"image = {name!r}: the raster has no bands")
        ci = list(ds.colorinterp)
        alpha = [i + 1 for i, c in enumerate(ci) if c.name == "alpha"]
        self.alpha_band: int | None = alpha[-1] if alpha else None
        self._bands = [i for i in range(1, ds.count + 1) if i != self.alpha_band]
        if not self._bands:
            raise InputError(f"image = {name!r}: the raster has no data bands (only an alpha band)")
        self.count = len(self._bands)
        for b in self._bands:
            if np.dtype(ds.dtypes[b - 1]).kind not in "biuf":
                raise InputError(f"image = {name!r}: band {b} holds {ds.dtypes[b - 1]} values; "
                                 "values must be real numbers (complex data is not an image)")  # fmt: skip
        self.band_named = band is not None
        if band is None:
            band = 1
        if isinstance(band, bool) or not isinstance(band, (int, np.integer)) or not 1 <= band <= self.count:
            raise ConfigError(f"band = {band!r}: must be an integer in [1, {self.count}] ({name!r} has "
                              f"{self.count} data band{'s' * (self.count > 1)})")  # fmt: skip
        self.band = int(band)
        self.shape: tuple[int, int] = (int(ds.height), int(ds.width))
        self.dtype = np.dtype(ds.dtypes[self._bands[self.band - 1] - 1])
        self.crs = ds.crs
        self.transform = ds.transform
        self.nodata = ds.nodatavals[self._bands[self.band - 1] - 1]
        self.scales = tuple(float(ds.scales[b - 1]) for b in self._bands)
        self.offsets = tuple(float(ds.offsets[b - 1]) for b in self._bands)
        self.descriptions = tuple(ds.descriptions[b - 1] for b in self._bands)
        self.colorinterp = tuple(ci[b - 1].name for b in self._bands)
        self.block_shape = tuple(int(v) for v in ds.block_shapes[self._bands[self.band - 1] - 1])
        nbits = ds.tags(self._bands[self.band - 1], ns="IMAGE_STRUCTURE").get("NBITS")
        self.bit_depth: int | None = int(nbits) if nbits and nbits.isdigit() else None
        self.tags: dict[str, str] = dict(ds.tags())
        self.subdatasets: tuple[str, ...] = tuple(ds.subdatasets)
        self.pixel_m, self.pixel_m_problem, self.rotation_deg = _pixel_size(ds)
        _check_plausible_size(ds, self.path, self.dtype)

    @property
    def georeferenced(self) -> bool:
        """True when the raster has a CRS or a non-identity transform."""
        return self.crs is not None or not self.transform.is_identity

    def require_pixel_m(self, option: str = "--scene-pixel-m") -> tuple[float, float]:
        """``pixel_m``, or a one-line :class:`ConfigError` that names ``option`` (which supplies one)."""
        if self.pixel_m is None:
            raise ConfigError(f"image = {str(self.path)!r}: {self.pixel_m_problem}, so it states no ground pixel "
                              f"size in metres; give {option}")  # fmt: skip
        return self.pixel_m

    def require_band(self, option: str = "--band") -> int:
        """The band to use where exactly one is needed: refused when the raster has several and none was named."""
        if self.count > 1 and not self.band_named:
            raise ConfigError(f"image = {str(self.path)!r}: has {self.count} bands; name one with {option} N "
                              f"(1..{self.count})")  # fmt: skip
        return self.band

    def _band(self, band: int | None) -> int:
        if band is None:
            return self._bands[self.band - 1]
        if isinstance(band, bool) or not isinstance(band, (int, np.integer)) or not 1 <= band <= self.count:
            raise ConfigError(f"band = {band!r}: must be an integer in [1, {self.count}]")
        return self._bands[int(band) - 1]

    def _window(self, row0: int, col0: int, height: int | None, width: int | None):
        """The rasterio window; ``height``/``width`` None: the rest of the image from ``(row0, col0)``."""
        rows, cols = self.shape
        height = rows - row0 if height is None else height
        width = cols - col0 if width is None else width
        if row0 < 0 or col0 < 0 or height < 1 or width < 1 or row0 + height > rows or col0 + width > cols:
            raise InputError(f"window = {(row0, col0, height, width)!r}: outside the image of shape {self.shape}")
        from rasterio.windows import Window

        return Window(int(col0), int(row0), int(width), int(height))

    def blocks_touched(self, row0: int, col0: int, height: int, width: int) -> int:
        """How many of the file's blocks (tiles or strips) a window touches: what GDAL decodes to read it."""
        bh, bw = self.block_shape
        return ((row0 + height - 1) // bh - row0 // bh + 1) * ((col0 + width - 1) // bw - col0 // bw + 1)

    # -------------------------------------------------------------------------------------------- reading
    def read(
        self,
        row0: int = 0,
        col0: int = 0,
        height: int | None = None,
        width: int | None = None,
        *,
        band: int | None = None,
        scaled: bool = False,
    ) -> np.ndarray:
        """The stored values of a window of one band (the file's dtype); ``scaled``: ``value * scale + offset``
        as float64. Without ``height``/``width`` the rest of the image from ``(row0, col0)``."""
        win = self._window(row0, col0, height, width)
        b = self._band(band)
        try:
            with _gdal_env():
                out = self._ds.read(b, window=win)
        except Exception as exc:  # rasterio raises RasterioIOError / CPLE_* for damaged data
            what = f"window {(row0, col0, height, width)} of band {b}"
            raise _read_failure(self.path, self.driver, what, exc) from exc
        if scaled:
            i = self._bands.index(b)
            out = out.astype(np.float64) * self.scales[i] + self.offsets[i]
        return out

    def read_mask(
        self, row0: int = 0, col0: int = 0, height: int | None = None, width: int | None = None, *, band=None
    ) -> np.ndarray:
        """Boolean validity of a window (True = valid): GDAL's mask of the band, from its nodata value, an
        internal mask or the alpha band (alpha 0 = invalid)."""
        win = self._window(row0, col0, height, width)
        b = self._band(band)
        try:
            with _gdal_env():
                return self._ds.read_masks(b, window=win) > 0
        except Exception as exc:
            what = f"the mask of window {(row0, col0, height, width)}"
            raise _read_failure(self.path, self.driver, what, exc) from exc

    def overview(self, max_px: int = 1024, *, band: int | None = None, scaled: bool = False):
        """``(values, valid)`` of the whole band decimated (nearest) to at most ``max_px`` a side, from the
        file's overviews where it has them: a fill value, a preview. ``valid`` is None without a mask."""
        from rasterio.enums import Resampling

        rows, cols = self.shape
        f = max(1, -(-max(rows, cols) // int(max_px)))
        shape = (-(-rows // f), -(-cols // f))
        b = self._band(band)
        try:
            with _gdal_env():
                out = self._ds.read(b, out_shape=shape, resampling=Resampling.nearest)
                valid = self._ds.read_masks(b, out_shape=shape, resampling=Resampling.nearest) > 0
        except Exception as exc:
            raise _read_failure(self.path, self.driver, f"band {b}", exc) from exc
        if scaled:
            i = self._bands.index(b)
            out = out.astype(np.float64) * self.scales[i] + self.offsets[i]
        return out, (valid if self.has_mask else None)

    @property
    def has_mask(self) -> bool:
        """True when some pixels may be invalid (a nodata value, an internal mask or an alpha band)."""
        with _gdal_env():
            return any(f.name != "all_valid" for f in self._ds.mask_flag_enums[self._band(None) - 1])

    def __getstate__(self) -> dict:  # picklable (Dask workers): reopened from the path
        return {"path": self.path, "band": self._band_arg}

    def __setstate__(self, state: dict) -> None:
        type(self).__init__(self, state["path"], band=state["band"])

    def close(self) -> None:
        if getattr(self, "_ds", None) is not None:
            with _gdal_env():  # GDAL may re-read a TIFF's directory on closing it (and warn)
                self._ds.close()
            self._ds = None

    def __enter__(self) -> RasterReader:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return (f"RasterReader({str(self.path)!r}, shape={self.shape}, count={self.count}, dtype={self.dtype}, "
                f"band={self.band}, pixel_m={self.pixel_m})")  # fmt: skip


def open_raster(path: str | os.PathLike, *, band: int | None = None) -> RasterReader:
    """Open any raster GDAL reads for window reads (see :class:`RasterReader`)."""
    return RasterReader(path, band=band)


# ------------------------------------------------------------------------------------------------ helpers
def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def _read_failure(path: Path, driver: str, what: str, exc: BaseException) -> SatchainIOError:
    """The error for a read GDAL refused, saying why where the file shows it: a VRT's missing source file, a
    TIFF or JPEG 2000 file cut short, else data that cannot be decoded (corrupt); GDAL's own message (rasterio
    puts it in the exception's cause) ends the line."""
    cause = exc.__cause__ or exc.__context__
    gdal = _one_line(cause if cause is not None else exc)
    why = _damage(path, driver)
    if why is None:
        why = "its data cannot be decoded: the file is corrupt (damaged bytes) or in an encoding GDAL cannot read"
    return SatchainIOError(f"image = {str(path)!r}: cannot read {what}: {why} (GDAL: {gdal})")


def _damage(path: Path, driver: str, depth: int = 0) -> str | None:
    """What is wrong with a file whose data GDAL could not read, where the file shows it (a VRT: its sources,
    missing or damaged); None where it does not."""
    try:
        size = path.stat().st_size
        if driver == "VRT":
            return _vrt_damage(path, depth)
        need = None
        if driver in ("GTiff", "COG"):
            need = _tiff_data_end(path)
        elif driver.startswith("JP2"):
            need = _jp2_needs(path, size)
    except Exception:  # the diagnosis is best effort: the read error itself is what is reported
        return None
    if need is None or need <= size:
        return None
    return (
        f"the file is truncated: it is {size} bytes but its data runs to {need} bytes (a download or copy cut short?)"
    )


def _vrt_damage(path: Path, depth: int) -> str | None:
    """A VRT's source files that are missing, else the first one that is damaged (truncated), else None."""
    sources = _vrt_sources(path)
    missing = [s for s in sources if not s.exists()]
    if missing:
        names = ", ".join(repr(str(m)) for m in missing[:3]) + (" ..." if len(missing) > 3 else "")
        verb = "is" if len(missing) == 1 else "are"
        return f"the VRT's source file{'s' * (len(missing) > 1)} {names} {verb} missing (no such file)"
    drivers = {".tif": "GTiff", ".tiff": "GTiff", ".jp2": "JP2", ".j2k": "JP2", ".vrt": "VRT"}
    for src in sources if depth < 4 else []:
        why = _damage(src, drivers.get(src.suffix.lower(), ""), depth + 1)
        if why is not None:
            return f"the VRT's source file {str(src)!r}: {why}"
    return None


def _vrt_sources(path: Path) -> list[Path]:
    """The local source files a VRT names, once each (relative names resolved as GDAL does)."""
    import xml.etree.ElementTree as ET

    sources = []
    for el in ET.parse(path).getroot().iter("SourceFilename"):
        name = (el.text or "").strip()
        if not name or name.startswith("/vsi") or "://" in name:
            continue
        src = path.parent / name if el.get("relativeToVRT", "0") == "1" else Path(name)
        if src not in sources:
            sources.append(src)
    return sources


def _tiff_data_end(path: Path) -> int:
    """The byte where a TIFF's image data ends, by its strip / tile offsets and byte counts."""
    import tifffile

    with tifffile.TiffFile(path) as t:
        ends = [int(o) + int(c) for pg in t.pages for o, c in zip(pg.dataoffsets, pg.databytecounts, strict=False)]
    return max(ends, default=0)


def _jp2_needs(path: Path, size: int) -> int | None:
    """The size a JPEG 2000 file must have by its boxes (``size + 2`` when its codestream, running to the end of
    the file, lacks its end-of-codestream marker), or None when it is not a JP2 box file."""
    pos = 0
    with path.open("rb") as f:
        while pos + 8 <= size:
            f.seek(pos)
            head = f.read(16)
            length, kind, n = int.from_bytes(head[:4], "big"), head[4:8], 8
            if length == 1:
                length, n = int.from_bytes(head[8:16], "big"), 16
            if 0 < length < n:
                return None
            end = size if length == 0 else pos + length
            if end > size:
                return end
            if kind == b"jp2c":
                f.seek(end - 2)
                return None if f.read(2) == b"\xff\xd9" else size + 2  # stops before its EOC marker
            pos = end
    return None


def _open_dataset(path: Path):
    rasterio = _rasterio()
    if not path.is_file():
        what = "is a directory, not an image file" if path.is_dir() else "no such file"
        raise SatchainIOError(f"image = {str(path)!r}: {what}")
    try:
        with warnings.catch_warnings(), _gdal_env():
            warnings.simplefilter("ignore", rasterio.errors.NotGeoreferencedWarning)
            return rasterio.open(path)
    except Exception as exc:
        raise SatchainIOError(f"image = {str(path)!r}: cannot read: {_one_line(exc)}") from None


def _pixel_size(ds) -> tuple[tuple[float, float] | None, str, float]:
    """(pixel_m or None, why None, rotation in degrees) from the dataset's CRS and transform."""
    t, crs = ds.transform, ds.crs
    if t.is_identity and crs is None:
        if ds.gcps[0] or getattr(ds, "rpcs", None):
            return None, "it is georeferenced by ground control points (or RPCs) only, not a regular grid", 0.0
        return None, "it has no georeference", 0.0
    col_step, row_step = (t.a, t.d), (t.b, t.e)  # ground vectors of one column and one row
    sx, sy = math.hypot(*col_step), math.hypot(*row_step)
    if sx == 0 or sy == 0:
        return None, f"its transform {tuple(t)[:6]} is degenerate", 0.0
    rotation = math.degrees(math.atan2(t.d, t.a))
    cos_corner = (col_step[0] * row_step[0] + col_step[1] * row_step[1]) / (sx * sy)
    if abs(cos_corner) > 1e-6:
        return (
            None,
            f"its transform is sheared (pixel corners of {math.degrees(math.acos(cos_corner)):.3f} deg)",
            rotation,
        )
    if crs is not None and crs.is_geographic:
        return (
            None,
            f"its CRS is geographic ({crs.to_string() or 'latitude/longitude'}: pixel sizes in degrees)",
            rotation,
        )
    factor = 1.0
    if crs is not None and crs.is_projected:
        with contextlib.suppress(Exception):
            unit, factor = crs.linear_units_factor
        if not (math.isfinite(factor) and factor > 0):
            return None, f"its CRS's linear unit {crs.linear_units!r} is not a length", rotation
    return (sx * factor, sy * factor), "", rotation


def _check_plausible_size(ds, path: Path, dtype: np.dtype) -> None:
    """A TIFF whose header claims more tiles or strips than it lists (a forged or damaged header, e.g. one that
    claims 10^10 pixels in a few kB) is refused before anything is read."""
    if ds.driver not in ("GTiff", "COG"):
        return
    rows, cols = ds.height, ds.width
    bh, bw = ds.block_shapes[0]
    n_blocks = -(-rows // bh) * -(-cols // bw)
    claimed = rows * cols * ds.count * dtype.itemsize
    size = path.stat().st_size
    if claimed <= 64 * size:
        return
    import tifffile

    try:
        with tifffile.TiffFile(path) as tf:
            page = tf.pages.first
            per_plane = n_blocks * (ds.count if page.planarconfig == 2 else 1)
            stored = len(page.dataoffsets)
    except Exception:  # tifffile cannot tell: GDAL opened it, so let the reads speak
        return
    if stored < per_plane:
        raise SatchainIOError(
            f"image = {str(path)!r}: its header claims {rows} x {cols} px ({claimed / 2**30:.3g} GiB) in "
            f"{per_plane} blocks but lists {stored}: a damaged or forged header"
        )


def raster_meta(reader: RasterReader) -> dict[str, Any]:
    """The georeference of a reader as plain JSON values (CRS string, GDAL 6-term transform, nodata ...)."""
    t = reader.transform
    meta: dict[str, Any] = {
        "driver": reader.driver,
        "band": reader.band,
        "count": reader.count,
        "transform": [t.c, t.a, t.b, t.f, t.d, t.e],
    }
    if reader.crs is not None:
        meta["crs"] = reader.crs.to_string()
    if reader.nodata is not None:
        meta["nodata"] = float(reader.nodata)
    if reader.bit_depth is not None:
        meta["bit_depth"] = reader.bit_depth
    if reader.rotation_deg:
        meta["rotation_deg"] = reader.rotation_deg
    i = reader.band - 1
    if reader.scales[i] != 1.0 or reader.offsets[i] != 0.0:
        meta["scale"], meta["offset"] = reader.scales[i], reader.offsets[i]
    if any(reader.descriptions):
        meta["band_names"] = list(reader.descriptions)
    if reader.alpha_band is not None:
        meta["alpha_band"] = reader.alpha_band
    return meta
